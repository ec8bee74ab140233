#include "rigidtouch/bridge.h"

#include <gtest/gtest.h>
#include <sodium.h>

#include <array>
#include <chrono>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "device/udp_device.h"
#include "draw.h"
#include "limit_malloc.h"
#include "loop/test_poll.h"
#include "udp_test_util.h"

namespace rigidtouch::device {
namespace {

using testing::PollUntil;

// a device that moves along x one millimetre per read and remembers the last command
class FakeDevice final : public Device {
 public:
  explicit FakeDevice(double max_force_N = 0.0, double max_torque_Nm = 0.0) {
    limits_ = {"fake", max_force_N, 800.0, 1.5, max_torque_Nm};
  }
  DeviceState Read() override {
    ++reads;
    DeviceState state;
    state.sequence = 999;  // the server renumbers; this must not reach the wire
    state.time_s = 0.001 * static_cast<double>(reads);
    state.position_m = Vec3(0.001 * static_cast<double>(reads), 0.0, 0.0);
    state.valid = valid;
    return state;
  }
  void Write(const DeviceCommand& command) override {
    ++writes;
    last = command;
    if (!command.safe_fallback) ++command_writes;
  }
  const DeviceLimits& limits() const override { return limits_; }

  bool valid = true;
  std::uint64_t reads = 0;
  std::uint64_t writes = 0;
  std::uint64_t command_writes = 0;
  DeviceCommand last;

 private:
  DeviceLimits limits_;
};

UdpDeviceServerOptions ServerOptions(double watchdog_s = 0.5, double session_timeout_s = 5.0) {
  UdpDeviceServerOptions options;
  options.listen = "udp://127.0.0.1:0";
  options.watchdog_s = watchdog_s;
  options.session_timeout_s = session_timeout_s;
  options.key = KeyOf(7);
  return options;
}

// a raw socket playing the renderer, so tests control every byte that reaches the server
struct Client {
  explicit Client(const DeviceKey& k = KeyOf(7)) : socket(Loopback0(), "client"), key(k) {}

  void Send(UdpDeviceServer& server, std::span<const std::uint8_t> bytes) {
    ASSERT_EQ(socket.SendTo(bytes, server.local_endpoint()), 0);
  }
  void Hello(UdpDeviceServer& server, std::uint64_t nonce) {
    client_nonce = nonce;
    Send(server, EncodeHello(nonce, key));
  }
  std::vector<std::uint8_t> CommandBytes(std::uint64_t sequence, double force_x_N,
                                         std::uint64_t counter) {
    DeviceCommand command;
    command.sequence = sequence;
    command.force_N = Vec3(force_x_N, 0.0, 0.0);
    const CommandPacket packet = EncodeCommand(
        command, PacketHeader{PacketType::kCommand, client_nonce, server_nonce, counter}, key);
    return {packet.begin(), packet.end()};
  }
  void Command(UdpDeviceServer& server, std::uint64_t sequence, double force_x_N) {
    Send(server, CommandBytes(sequence, force_x_N, ++sent_counter));
  }
  // the next datagram from the server of the given type, authenticated; steps the server
  bool ReceiveFrom(UdpDeviceServer& server, PacketType type, std::vector<std::uint8_t>* bytes,
                   PacketHeader* header) {
    std::array<std::uint8_t, kMaxDatagramBytes> buffer{};
    return PollUntil([&] {
      server.Step();
      Datagram datagram;
      while (socket.Receive(buffer, &datagram) == 0) {
        const std::span<const std::uint8_t> received(buffer.data(), datagram.bytes);
        if (CheckFraming(received, PacketType::kHelloReply, PacketType::kState, header) ==
                DecodeResult::kOk &&
            header->type == type && VerifyMac(received, key)) {
          bytes->assign(received.begin(), received.end());
          return true;
        }
      }
      return false;
    });
  }
  // hello, then the reply; records the server's nonce
  bool Handshake(UdpDeviceServer& server, std::uint64_t nonce) {
    Hello(server, nonce);
    std::vector<std::uint8_t> bytes;
    PacketHeader header;
    if (!ReceiveFrom(server, PacketType::kHelloReply, &bytes, &header)) return false;
    if (header.client_nonce != nonce) return false;
    server_nonce = header.server_nonce;
    sent_counter = 0;
    EXPECT_EQ(DecodeHelloReplyPayload(bytes, &announced), DecodeResult::kOk);
    return true;
  }

  UdpSocket socket;
  DeviceKey key;
  std::uint64_t client_nonce = 0;
  std::uint64_t server_nonce = 0;
  std::uint64_t sent_counter = 0;
  DeviceLimits announced;
};

// steps the server until it has taken `received` datagrams off its socket
void StepUntilReceived(UdpDeviceServer& server, std::uint64_t received) {
  EXPECT_TRUE(PollUntil([&] {
    server.Step();
    return server.counters().received >= received;
  })) << "received "
      << server.counters().received << " of " << received;
}

TEST(UdpDeviceServer, ZeroForceAndNoStreamingUntilAClientSpeaks) {
  FakeDevice device;
  UdpDeviceServer server(device, ServerOptions());
  EXPECT_NE(server.local_endpoint().port, 0);
  server.Step();
  EXPECT_FALSE(server.has_peer());
  EXPECT_EQ(server.counters().sent, 0u);
  EXPECT_EQ(device.reads, 1u);
  EXPECT_EQ(device.writes, 1u);
  EXPECT_TRUE(device.last.safe_fallback);
  EXPECT_EQ(device.last.force_N, Vec3::Zero());
  EXPECT_EQ(server.counters().fallback_writes, 1u);
  EXPECT_EQ(server.counters().watchdog_trips, 0u) << "waiting for a first client is not a trip";
}

TEST(UdpDeviceServer, HandshakeAnnouncesLimitsPinsTheClientAndStreamsStatesToIt) {
  FakeDevice device(3.0);
  UdpDeviceServer server(device, ServerOptions());
  Client client;
  ASSERT_TRUE(client.Handshake(server, 0xabc));
  ASSERT_TRUE(server.has_peer());
  EXPECT_EQ(server.peer(), client.socket.local());
  EXPECT_NE(client.server_nonce, 0u);
  EXPECT_EQ(client.announced.max_force_N, 3.0);
  EXPECT_EQ(client.announced.max_stiffness_N_per_m, 800.0);
  EXPECT_EQ(client.announced.max_damping_Ns_per_m, 1.5);
  EXPECT_EQ(server.counters().handshakes, 1u);
  EXPECT_EQ(server.counters().peer_changes, 1u);

  std::vector<std::uint8_t> bytes;
  PacketHeader header;
  ASSERT_TRUE(client.ReceiveFrom(server, PacketType::kState, &bytes, &header));
  EXPECT_EQ(header.client_nonce, 0xabcu);
  EXPECT_EQ(header.server_nonce, client.server_nonce);
  EXPECT_EQ(header.counter, 1u);
  DeviceState state;
  ASSERT_EQ(DecodeStatePayload(bytes, &state), DecodeResult::kOk);
  EXPECT_EQ(state.sequence, 1u) << "the server numbers states itself, from 1";

  client.Command(server, 1, 1.25);
  StepUntilReceived(server, 2);
  EXPECT_EQ(device.last.force_N, Vec3(1.25, 0.0, 0.0));
  EXPECT_FALSE(device.last.safe_fallback);
  EXPECT_EQ(server.counters().accepted, 1u);
}

TEST(UdpDeviceServer, EveryCommandIsClampedToTheDevicesLimit) {
  FakeDevice device(3.0);
  UdpDeviceServer server(device, ServerOptions());
  Client client;
  ASSERT_TRUE(client.Handshake(server, 1));
  client.Command(server, 1, -1000.0);  // the injected 1000 N of the review
  StepUntilReceived(server, 2);
  EXPECT_NEAR(device.last.force_N.x(), -3.0, 1e-12);
  EXPECT_LE(device.last.force_N.norm(), 3.0);
  EXPECT_EQ(device.last.force_N.tail<2>(), Eigen::Vector2d::Zero());
  EXPECT_TRUE(device.last.clipped);
  client.Command(server, 2, 1e300);  // finite, but its squared norm is not
  StepUntilReceived(server, 3);
  EXPECT_NEAR(device.last.force_N.x(), 3.0, 1e-12);
  client.Command(server, 3, 2.5);  // within the limit: untouched
  StepUntilReceived(server, 4);
  EXPECT_EQ(device.last.force_N.x(), 2.5);
  EXPECT_FALSE(device.last.clipped);
  EXPECT_EQ(server.counters().clamped_commands, 2u);
}

// the clamp lands at or below the limit, never a rounding above it (a plain scale by
// limit / norm did for about a third of these), and scales the torque by the same factor
TEST(UdpDeviceServer, TheClampNeverEndsAboveTheLimitAndScalesTheTorque) {
  constexpr double kLimit_N = 3.3;
  FakeDevice device(kLimit_N, 1e3);  // a torque limit above every torque sent
  UdpDeviceServer server(device, ServerOptions());
  Client client;
  ASSERT_TRUE(client.Handshake(server, 1));
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-50.0, 50.0);
  for (int k = 1; k <= 200; ++k) {
    DeviceCommand command;
    command.sequence = static_cast<std::uint64_t>(k);
    command.force_N = test::Draw3(u, rng);
    command.torque_Nm = test::Draw3(u, rng);
    const PacketHeader header{PacketType::kCommand, client.client_nonce, client.server_nonce,
                              ++client.sent_counter};
    const CommandPacket packet = EncodeCommand(command, header, client.key);
    client.Send(server, packet);
    StepUntilReceived(server, static_cast<std::uint64_t>(k) + 1);
    ASSERT_TRUE(device.last.clipped) << k;
    EXPECT_LE(device.last.force_N.norm(), kLimit_N) << k;
    EXPECT_NEAR(device.last.force_N.norm(), kLimit_N, 1e-12) << k;
    const double scale = device.last.force_N.norm() / command.force_N.norm();
    EXPECT_NEAR((device.last.torque_Nm - scale * command.torque_Nm).norm(), 0.0,
                1e-12 * command.torque_Nm.norm())
        << k;
  }
}

// the device side keeps the torque within its device's torque limit: none for a device that
// displays no torque (max_torque_Nm 0, every preset), at most the limit otherwise (a clamp),
// whatever the renderer sent
TEST(UdpDeviceServer, TheTorqueIsWithinTheDevicesTorqueLimitOrZero) {
  for (const double limit_Nm : {0.0, 0.5}) {
    SCOPED_TRACE(limit_Nm);
    FakeDevice device(0.0, limit_Nm);
    UdpDeviceServer server(device, ServerOptions());
    Client client;
    ASSERT_TRUE(client.Handshake(server, 1));
    const Vec3 sent[] = {{3.0, 0.0, 4.0}, {0.1, 0.2, 0.2}, {1e300, -1e300, 0.0}};
    std::uint64_t k = 0;
    for (const Vec3& torque : sent) {
      ++k;
      DeviceCommand command;
      command.sequence = k;
      command.force_N = Vec3(1.0, 0.0, 0.0);
      command.torque_Nm = torque;
      const PacketHeader header{PacketType::kCommand, client.client_nonce, client.server_nonce,
                                ++client.sent_counter};
      client.Send(server, EncodeCommand(command, header, client.key));
      StepUntilReceived(server, k + 1);
      const Vec3& shown = device.last.torque_Nm;
      EXPECT_EQ(device.last.force_N, Vec3(1.0, 0.0, 0.0));  // the force is not the torque's
      if (limit_Nm == 0.0) {
        EXPECT_EQ(shown, Vec3::Zero());
        EXPECT_FALSE(device.last.clipped);
      } else if (torque.norm() <= limit_Nm) {
        EXPECT_EQ(shown, torque);
        EXPECT_FALSE(device.last.clipped);
      } else {
        EXPECT_LE(shown.norm(), limit_Nm);
        EXPECT_NEAR(shown.norm(), limit_Nm, 1e-12);
        EXPECT_NEAR(shown.normalized().dot(torque.stableNormalized()), 1.0, 1e-12);
        EXPECT_TRUE(device.last.clipped);
      }
    }
    EXPECT_EQ(server.counters().clamped_commands, limit_Nm > 0.0 ? 2u : 0u);
  }
}

// a stopping bridge leaves its device with zero force, and keeps it there until the renderer
// sends a new command (not the last one it had, however fresh)
TEST(UdpDeviceServer, ReleaseWritesZeroUntilANewCommand) {
  FakeDevice device;
  UdpDeviceServer server(device, ServerOptions());
  Client client;
  ASSERT_TRUE(client.Handshake(server, 1));
  client.Command(server, 1, 2.0);
  StepUntilReceived(server, 2);
  ASSERT_EQ(device.last.force_N.x(), 2.0);
  const std::uint64_t writes = device.writes;
  server.Release();
  EXPECT_EQ(device.writes, writes + 1);
  EXPECT_EQ(device.last.force_N, Vec3::Zero());
  EXPECT_TRUE(device.last.safe_fallback);
  for (int k = 0; k < 5; ++k) {
    server.Step();  // well within the watchdog
    EXPECT_EQ(device.last.force_N, Vec3::Zero());
    EXPECT_TRUE(device.last.safe_fallback);
  }
  EXPECT_FALSE(server.watchdog_tripped());
  client.Command(server, 2, 3.0);
  StepUntilReceived(server, 3);
  EXPECT_EQ(device.last.force_N.x(), 3.0);
  EXPECT_FALSE(device.last.safe_fallback);
}

TEST(UdpDeviceServer, AnotherAddressCannotTakeOverALiveSession) {
  FakeDevice device;
  UdpDeviceServer server(device, ServerOptions(0.5, 0.6));
  Client renderer;
  ASSERT_TRUE(renderer.Handshake(server, 1));
  // even a client holding the key waits: one renderer at a time
  Client other;
  other.Hello(server, 2);
  StepUntilReceived(server, 2);
  EXPECT_EQ(server.counters().hellos_refused, 1u);
  EXPECT_EQ(server.peer(), renderer.socket.local());
  EXPECT_EQ(server.counters().handshakes, 1u);
  renderer.Command(server, 1, 1.0);
  StepUntilReceived(server, 3);
  EXPECT_EQ(device.last.force_N.x(), 1.0);

  // the renderer goes silent: its session ends after session_timeout_s, then another may start
  ASSERT_TRUE(PollUntil([&] {
    server.Step();
    return !server.has_peer();
  }));
  EXPECT_EQ(server.counters().session_timeouts, 1u);
  EXPECT_TRUE(device.last.safe_fallback);
  ASSERT_TRUE(other.Handshake(server, 3));
  EXPECT_EQ(server.peer(), other.socket.local());
  EXPECT_EQ(server.counters().peer_changes, 2u);
  // the old renderer's session is gone for good
  renderer.Command(server, 2, 2.0);
  StepUntilReceived(server, 5);
  EXPECT_EQ(server.counters().no_session, 1u);
  EXPECT_TRUE(device.last.safe_fallback);
}

TEST(UdpDeviceServer, TheSameClientRenewsItsSessionAndARepeatedHelloGetsTheSameReply) {
  FakeDevice device;
  UdpDeviceServer server(device, ServerOptions());
  Client client;
  ASSERT_TRUE(client.Handshake(server, 10));
  const std::uint64_t first = client.server_nonce;
  ASSERT_TRUE(client.Handshake(server, 10));  // the reply was lost: the hello again
  EXPECT_EQ(client.server_nonce, first);
  EXPECT_EQ(server.counters().handshakes, 1u);
  client.Command(server, 1, 1.0);
  ASSERT_TRUE(client.Handshake(server, 11));  // after its watchdog: a new handshake
  EXPECT_NE(client.server_nonce, first);
  EXPECT_EQ(server.counters().handshakes, 2u);
  EXPECT_EQ(server.counters().peer_changes, 1u);
  EXPECT_TRUE(device.last.safe_fallback) << "a new session starts from zero force";
  client.Command(server, 1, 4.0);
  StepUntilReceived(server, 5);
  EXPECT_EQ(device.last.force_N.x(), 4.0);
}

TEST(UdpDeviceServer, CommandsOutsideTheSessionAreDropped) {
  FakeDevice device;
  UdpDeviceServer server(device, ServerOptions());
  Client client;
  client.client_nonce = 5;
  client.server_nonce = 6;
  client.Command(server, 1, 9.0);  // authenticated, but no session exists
  StepUntilReceived(server, 1);
  EXPECT_EQ(server.counters().no_session, 1u);
  ASSERT_TRUE(client.Handshake(server, 5));
  const std::uint64_t nonce = client.server_nonce;
  client.server_nonce = nonce + 1;  // a recorded session's command
  client.Command(server, 1, 9.0);
  client.server_nonce = nonce;
  // the session's nonces, sent from another address
  Client stranger;
  stranger.client_nonce = 5;
  stranger.server_nonce = nonce;
  stranger.Command(server, 1, 9.0);
  StepUntilReceived(server, 4);
  EXPECT_EQ(server.counters().no_session, 2u);
  EXPECT_EQ(server.counters().wrong_source, 1u);
  EXPECT_EQ(server.counters().accepted, 0u);
  EXPECT_TRUE(device.last.safe_fallback);
}

TEST(UdpDeviceServer, ReplayedCommandsAreDropped) {
  FakeDevice device;
  UdpDeviceServer server(device, ServerOptions());
  Client client;
  ASSERT_TRUE(client.Handshake(server, 1));
  const std::vector<std::uint8_t> first = client.CommandBytes(1, 1.0, 1);
  const std::vector<std::uint8_t> second = client.CommandBytes(2, 2.0, 2);
  client.Send(server, first);
  client.Send(server, second);
  StepUntilReceived(server, 3);
  EXPECT_EQ(device.last.force_N.x(), 2.0);
  client.Send(server, first);                           // an older counter
  client.Send(server, second);                          // the same datagram again
  client.Send(server, client.CommandBytes(3, 3.0, 2));  // a new payload under an old counter
  StepUntilReceived(server, 6);
  EXPECT_EQ(server.counters().replayed, 3u);
  EXPECT_EQ(server.counters().accepted, 2u);
  EXPECT_EQ(device.last.force_N.x(), 2.0);
}

TEST(UdpDeviceServer, UnauthenticatedAndVersion1DatagramsNeverReachTheDevice) {
  FakeDevice device;
  UdpDeviceServer server(device, ServerOptions());
  Client forger(KeyOf(8));
  forger.Hello(server, 1);  // a hello under the wrong key starts nothing
  StepUntilReceived(server, 1);
  EXPECT_FALSE(server.has_peer());
  EXPECT_EQ(server.counters().unauthenticated, 1u);

  Client client;
  ASSERT_TRUE(client.Handshake(server, 2));
  // the session's nonces, the wrong key
  forger.client_nonce = 2;
  forger.server_nonce = client.server_nonce;
  forger.Command(server, 1, 9.0);
  std::vector<std::uint8_t> flipped = client.CommandBytes(1, 1.0, 1);
  flipped[50] ^= 0x40;
  client.Send(server, flipped);
  // a version 1 command: 16-byte header with CRC-32, as v1 renderers send it
  const std::array<std::uint8_t, 16> v1_header = {0x52, 0x54, 0x43, 0x48, 1, 0, 2, 0, 60, 0};
  std::vector<std::uint8_t> v1(v1_header.begin(), v1_header.end());
  v1.resize(76, 0);
  client.Send(server, v1);
  StepUntilReceived(server, 5);
  EXPECT_EQ(server.counters().unauthenticated, 3u);
  EXPECT_EQ(server.counters().Malformed(DecodeResult::kWrongVersion), 1u);
  EXPECT_EQ(server.counters().accepted, 0u);
  EXPECT_EQ(device.command_writes, 0u);
}

TEST(UdpDeviceServer, FixedPeerRefusesOtherAddresses) {
  FakeDevice device;
  Client renderer;
  Client stranger;
  UdpDeviceServerOptions options = ServerOptions();
  options.peer = renderer.socket.local().ToString();
  UdpDeviceServer server(device, options);
  stranger.Hello(server, 5);
  StepUntilReceived(server, 1);
  EXPECT_EQ(server.counters().wrong_source, 1u);
  EXPECT_FALSE(server.has_peer());
  ASSERT_TRUE(renderer.Handshake(server, 6));
  EXPECT_EQ(server.peer(), renderer.socket.local());
}

TEST(UdpDeviceServer, NewestCommandWinsAndEqualSequenceReplaces) {
  FakeDevice device;
  UdpDeviceServer server(device, ServerOptions());
  Client client;
  ASSERT_TRUE(client.Handshake(server, 1));
  client.Command(server, 5, 5.0);
  StepUntilReceived(server, 2);
  // older: dropped; equal: the later answer to the same state replaces the earlier one
  client.Command(server, 3, 3.0);
  client.Command(server, 5, 5.5);
  StepUntilReceived(server, 4);
  EXPECT_EQ(server.counters().stale, 1u);
  EXPECT_EQ(server.counters().accepted, 2u);
  EXPECT_EQ(device.last.force_N.x(), 5.5);
  EXPECT_EQ(device.last.sequence, 5u);
}

TEST(UdpDeviceServer, MalformedCommandsAreCountedAndNeverApplied) {
  FakeDevice device;
  UdpDeviceServer server(device, ServerOptions());
  Client client;
  ASSERT_TRUE(client.Handshake(server, 1));
  client.Command(server, 1, 1.0);
  StepUntilReceived(server, 2);

  const std::vector<std::uint8_t> good = client.CommandBytes(2, 2.0, 2);
  std::vector<std::uint8_t> truncated(good.begin(), good.begin() + 40);
  std::vector<std::uint8_t> oversized(2000, 0);
  const StatePacket wrong_type = EncodeState(DeviceState{}, PacketHeader{}, client.key);
  for (const std::span<const std::uint8_t> bytes :
       {std::span<const std::uint8_t>(truncated), std::span<const std::uint8_t>(oversized),
        std::span<const std::uint8_t>(wrong_type)}) {
    client.Send(server, bytes);
  }
  StepUntilReceived(server, 5);
  const UdpCounters& counters = server.counters();
  EXPECT_EQ(counters.Malformed(DecodeResult::kTooShort), 1u);
  EXPECT_EQ(counters.Malformed(DecodeResult::kOversized), 1u);
  EXPECT_EQ(counters.Malformed(DecodeResult::kWrongType), 1u);
  EXPECT_EQ(device.last.force_N.x(), 1.0);
}

TEST(UdpDeviceServer, WatchdogWritesZeroForceThenRecovers) {
  constexpr double kWatchdog_s = 0.02;
  FakeDevice device;
  UdpDeviceServer server(device, ServerOptions(kWatchdog_s));
  Client client;
  ASSERT_TRUE(client.Handshake(server, 1));
  const auto sent_at = std::chrono::steady_clock::now();
  client.Command(server, 1, 2.0);
  StepUntilReceived(server, 2);
  ASSERT_FALSE(device.last.safe_fallback);

  ASSERT_TRUE(PollUntil([&] {
    server.Step();
    return device.last.safe_fallback;
  }));
  const double waited_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - sent_at).count();
  EXPECT_GE(waited_s, kWatchdog_s);  // guaranteed by the logic, not a timing measurement
  EXPECT_EQ(device.last.force_N, Vec3::Zero());
  EXPECT_TRUE(server.watchdog_tripped());
  EXPECT_EQ(server.counters().watchdog_trips, 1u);
  server.Step();
  EXPECT_EQ(server.counters().watchdog_trips, 1u);

  client.Command(server, 2, 3.0);
  StepUntilReceived(server, 3);
  EXPECT_FALSE(device.last.safe_fallback);
  EXPECT_EQ(device.last.force_N.x(), 3.0);
  EXPECT_EQ(server.counters().recoveries, 1u);
  EXPECT_FALSE(server.watchdog_tripped());
}

TEST(UdpDeviceServer, InvalidDeviceReadingsAreNotSent) {
  FakeDevice device;
  UdpDeviceServer server(device, ServerOptions());
  Client client;
  ASSERT_TRUE(client.Handshake(server, 1));
  const std::uint64_t sent = server.counters().sent;
  device.valid = false;
  server.Step();
  EXPECT_EQ(server.counters().sent, sent);
  EXPECT_GE(server.counters().invalid_device_states, 1u);
  device.valid = true;
  server.Step();
  EXPECT_EQ(server.counters().sent, sent + 1);
}

TEST(UdpDeviceServer, AddressInUseNamesIt) {
  FakeDevice device;
  UdpDeviceServer first(device, ServerOptions());
  UdpDeviceServerOptions options = ServerOptions();
  options.listen = first.local_endpoint().ToString();
  try {
    UdpDeviceServer second(device, options);
    FAIL() << "expected an Error";
  } catch (const Error& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find(options.listen), std::string::npos) << message;
    EXPECT_NE(message.find("listen"), std::string::npos) << message;
    EXPECT_NE(message.find("in use"), std::string::npos) << message;
  }
}

TEST(UdpDeviceServer, OptionChecks) {
  FakeDevice device;
  UdpDeviceServerOptions options = ServerOptions();
  options.listen = "udp://0.0.0.0:0";
  EXPECT_THROW(UdpDeviceServer(device, options), Error);
  options.listen = "udp://127.0.0.1:0";
  options.peer = "udp://10.0.0.2:47001";
  EXPECT_THROW(UdpDeviceServer(device, options), Error);
  options.peer = "udp://127.0.0.1:0";
  EXPECT_THROW(UdpDeviceServer(device, options), Error);
  options.peer.clear();
  options.watchdog_s = -1.0;
  EXPECT_THROW(UdpDeviceServer(device, options), Error);
  options.watchdog_s = 0.1;
  options.session_timeout_s = 0.05;  // shorter than the watchdog
  EXPECT_THROW(UdpDeviceServer(device, options), Error);
  options.session_timeout_s = 0.5;
  options.key.reset();
  options.key_file = "/nonexistent-rigidtouch-test/device.key";
  EXPECT_THROW(UdpDeviceServer(device, options), Error);
}

TEST(UdpDeviceServer, AFloodIsTakenAtMostAFewDozenDatagramsPerStep) {
  FakeDevice device;
  UdpDeviceServer server(device, ServerOptions());
  Client flooder(KeyOf(3));
  for (int i = 0; i < kMaxDatagramsPerPeriod + 36; ++i) flooder.Hello(server, 1);
  server.Step();
  EXPECT_EQ(server.counters().received, static_cast<std::uint64_t>(kMaxDatagramsPerPeriod));
  EXPECT_EQ(device.writes, 1u) << "the period still ends with its write";
  server.Step();
  EXPECT_EQ(server.counters().received, kMaxDatagramsPerPeriod + 36u);
  EXPECT_EQ(server.counters().unauthenticated, kMaxDatagramsPerPeriod + 36u);
}

TEST(UdpDeviceServer, StepDoesNotAllocate) {
  if (!test::kMallocCounting) GTEST_SKIP() << "malloc is owned by the sanitizer";
  FakeDevice device(3.0);
  UdpDeviceServer server(device, ServerOptions());
  Client client;
  client.Hello(server, 1);
  client.Send(server, std::vector<std::uint8_t>(5, 1));
  Client forger(KeyOf(9));
  forger.Hello(server, 2);
  // the measured region: a handshake (random nonce, reply), malformed and forged datagrams
  {
    test::LimitMalloc guard;
    const bool all = PollUntil([&] {
      server.Step();
      return server.counters().received >= 3;
    });
    const long allocations = guard.allocations();
    ASSERT_TRUE(all);
    EXPECT_EQ(allocations, 0);
  }
  std::vector<std::uint8_t> reply;
  PacketHeader header;
  ASSERT_TRUE(client.ReceiveFrom(server, PacketType::kHelloReply, &reply, &header));
  client.server_nonce = header.server_nonce;
  client.Command(server, 1, 1.0);
  client.Command(server, 2, 200.0);  // clamped
  const std::vector<std::uint8_t> replay = client.CommandBytes(2, 2.0, 2);
  client.Send(server, replay);
  test::LimitMalloc guard;
  const bool all = PollUntil([&] {
    server.Step();
    return server.counters().received >= 6;
  });
  server.Step();
  const long allocations = guard.allocations();
  ASSERT_TRUE(all);
  EXPECT_EQ(allocations, 0);
  EXPECT_EQ(server.counters().clamped_commands, 1u);
  EXPECT_EQ(server.counters().replayed, 1u);
  EXPECT_GE(server.counters().sent, 2u);
}

// client and server end to end, 5 % simulated loss each way on the server, seeded
TEST(UdpDeviceServer, EndToEndWithFivePercentLoss) {
  constexpr int kSteps = 2000;
  FakeDevice device(40.0);
  UdpDeviceServerOptions server_options = ServerOptions(1.0);
  server_options.test_loss = PacketLoss{0.05, 0.05, 12345};
  UdpDeviceServer server(device, server_options);
  UdpDeviceOptions client_options;
  client_options.server = server.local_endpoint().ToString();
  client_options.watchdog_s = 1.0;  // generous: only a stalled machine could trip it
  client_options.key = server_options.key;
  client_options.limits.max_force_N = 50.0;
  UdpDevice client(client_options);

  std::uint64_t valid_reads = 0;
  for (int step = 0; step < kSteps; ++step) {
    server.Step();
    const DeviceState state = client.Read();
    DeviceCommand command;
    command.sequence = state.sequence;
    command.force_N = Vec3(static_cast<double>(state.sequence % 30), 0.0, 0.0);
    command.safe_fallback = !state.valid;
    if (state.valid) ++valid_reads;
    client.Write(command);
  }
  // let the last datagrams land, then account for every one
  ASSERT_TRUE(PollUntil([&] {
    client.Read();
    server.Step();
    return client.counters().received == server.counters().sent &&
           server.counters().received == client.counters().sent;
  }));
  const UdpCounters& s = server.counters();
  const UdpCounters& c = client.counters();
  EXPECT_EQ(client.limits().max_force_N, 40.0) << "the device announced a stricter limit";
  // nothing is lost on loopback except what the simulation drops, nothing is forged
  EXPECT_EQ(c.accepted + c.stale + c.duplicate + c.handshakes + c.replayed + c.no_session, s.sent);
  EXPECT_EQ(c.MalformedTotal() + c.unauthenticated, 0u);
  EXPECT_EQ(s.MalformedTotal() + s.unauthenticated + s.no_session + s.replayed, 0u);
  EXPECT_EQ(c.handshakes, 1u);
  // the drop fraction of 2000 Bernoulli(0.05) draws: mean 100, sd 9.7; [60, 140] is > 4 sd
  const double out_fraction = static_cast<double>(s.test_dropped_outgoing) /
                              static_cast<double>(s.sent + s.test_dropped_outgoing);
  const double in_fraction =
      static_cast<double>(s.test_dropped_incoming) / static_cast<double>(c.sent);
  EXPECT_GT(out_fraction, 0.03);
  EXPECT_LT(out_fraction, 0.07);
  EXPECT_GT(in_fraction, 0.03);
  EXPECT_LT(in_fraction, 0.07);
  // loss never trips a watchdog set far above the period
  EXPECT_EQ(c.watchdog_trips, 0u);
  EXPECT_EQ(s.watchdog_trips, 0u);
  EXPECT_GT(valid_reads, static_cast<std::uint64_t>(0.9 * kSteps));
  // the device keeps getting real commands, each answering a state it produced
  EXPECT_GT(device.command_writes, static_cast<std::uint64_t>(0.9 * kSteps));
  EXPECT_LE(device.last.sequence, server.last_sequence());
  EXPECT_EQ(device.last.force_N.x(), static_cast<double>(device.last.sequence % 30));
}

}  // namespace
}  // namespace rigidtouch::device
