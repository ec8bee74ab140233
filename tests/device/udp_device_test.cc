#include "device/udp_device.h"

#include <gtest/gtest.h>
#include <sodium.h>

#include <bit>
#include <chrono>
#include <limits>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "limit_malloc.h"
#include "loop/test_poll.h"
#include "udp_test_util.h"

namespace rigidtouch::device {
namespace {

using testing::PollUntil;

constexpr std::uint64_t kServerNonce = 0x5e5e5e5e12345678ull;

void ResealWith(std::vector<std::uint8_t>& datagram, const DeviceKey& key) {
  const std::size_t covered = datagram.size() - kMacBytes;
  crypto_auth_hmacsha256(datagram.data() + covered, datagram.data(), covered, key.bytes.data());
}

// a raw socket playing the device server, so tests control every byte that reaches the client
struct Fixture {
  explicit Fixture(double watchdog_s = 0.5, double hello_interval_s = 0.02)
      : server(Loopback0(), "test server"), key(KeyOf(7)) {
    UdpDeviceOptions options;
    options.server = server.local().ToString();
    options.local = "udp://127.0.0.1:0";
    options.watchdog_s = watchdog_s;
    options.hello_interval_s = hello_interval_s;
    options.limits.name = "udp-test";
    options.limits.max_force_N = 3.3;
    options.key = key;
    device = std::make_unique<UdpDevice>(options);
  }

  void SendRaw(std::span<const std::uint8_t> bytes) {
    ASSERT_EQ(server.SendTo(bytes, device->local_endpoint()), 0);
  }

  // the newest datagram the client has sent (waits for a first one)
  std::vector<std::uint8_t> FromClient() {
    std::array<std::uint8_t, kMaxDatagramBytes> buffer{};
    Datagram datagram;
    EXPECT_TRUE(PollUntil([&] { return server.Receive(buffer, &datagram) == 0; }));
    std::vector<std::uint8_t> newest(buffer.begin(), buffer.begin() + datagram.bytes);
    while (server.Receive(buffer, &datagram) == 0) {
      newest.assign(buffer.begin(), buffer.begin() + datagram.bytes);
    }
    return newest;
  }

  // waits for a hello, checks it, and returns its nonce
  std::uint64_t ReceiveHello() {
    const std::vector<std::uint8_t> bytes = FromClient();
    PacketHeader header;
    EXPECT_EQ(CheckFraming(bytes, PacketType::kHello, PacketType::kCommand, &header),
              DecodeResult::kOk);
    EXPECT_EQ(header.type, PacketType::kHello);
    EXPECT_TRUE(VerifyMac(bytes, key));
    return header.client_nonce;
  }

  // answers the client's hello (the newest one, or the nonce already taken from it) and reads
  // until the session stands
  void Handshake(const DeviceLimits& limits = DeviceLimits{"", 2.0, 1000.0, 0.0},
                 std::uint64_t server_nonce = kServerNonce, bool receive_hello = true) {
    if (receive_hello) client_nonce = ReceiveHello();
    this->server_nonce = server_nonce;
    counter = 0;
    const std::uint64_t before = device->counters().handshakes;
    SendRaw(EncodeHelloReply(limits, client_nonce, server_nonce, key));
    EXPECT_TRUE(PollUntil([&] {
      device->Read();
      return device->counters().handshakes > before;
    }));
  }

  std::vector<std::uint8_t> StateBytes(std::uint64_t sequence, std::uint64_t packet_counter) {
    DeviceState state;
    state.sequence = sequence;
    state.time_s = 0.001 * static_cast<double>(sequence);
    state.position_m = Vec3(static_cast<double>(sequence), 0.0, 0.0);
    const StatePacket packet = EncodeState(
        state, PacketHeader{PacketType::kState, client_nonce, server_nonce, packet_counter}, key);
    return {packet.begin(), packet.end()};
  }

  void SendState(std::uint64_t sequence) { SendRaw(StateBytes(sequence, ++counter)); }

  // reads until the client has taken `received` datagrams off its socket; returns the last state
  DeviceState ReadUntilReceived(std::uint64_t received) {
    DeviceState state;
    EXPECT_TRUE(PollUntil([&] {
      state = device->Read();
      return device->counters().received >= received;
    })) << "received "
        << device->counters().received << " of " << received;
    return state;
  }

  UdpSocket server;
  DeviceKey key;
  std::unique_ptr<UdpDevice> device;
  std::uint64_t client_nonce = 0;
  std::uint64_t server_nonce = 0;
  std::uint64_t counter = 0;  // server -> client, this session
};

TEST(UdpDevice, StartsWithAnAuthenticatedHelloAndSendsNoCommandWithoutASession) {
  Fixture f;
  const std::uint64_t nonce = f.ReceiveHello();
  EXPECT_NE(nonce, 0u);
  EXPECT_FALSE(f.device->has_session());
  const std::uint64_t sent = f.device->counters().sent;
  DeviceCommand command;
  command.force_N = Vec3(1.0, 0.0, 0.0);
  f.device->Write(command);
  EXPECT_EQ(f.device->counters().sent, sent) << "a command outside a session is not sent";
}

TEST(UdpDevice, ResendsItsHelloWithTheSameNonceUntilAnswered) {
  Fixture f(0.5, 0.005);
  const std::uint64_t first = f.ReceiveHello();
  ASSERT_TRUE(PollUntil([&] {
    f.device->Read();
    return f.device->counters().sent >= 3;
  }));
  EXPECT_EQ(f.ReceiveHello(), first) << "a slow reply to the first hello must still be taken";
  // another client starts its own handshake with its own nonce
  Fixture g;
  EXPECT_NE(g.ReceiveHello(), first);
}

TEST(UdpDevice, HandshakeCombinesAnnouncedLimitsWithItsOwn) {
  Fixture f;
  EXPECT_EQ(f.device->limits().max_force_N, 3.3);
  f.Handshake(DeviceLimits{"", 2.0, 1000.0, 0.0});
  EXPECT_TRUE(f.device->has_session());
  EXPECT_EQ(f.device->counters().handshakes, 1u);
  EXPECT_EQ(f.device->limits().name, "udp-test");
  EXPECT_EQ(f.device->limits().max_force_N, 2.0);               // the device's is stricter
  EXPECT_EQ(f.device->limits().max_stiffness_N_per_m, 1000.0);  // ours was unknown (0)
  EXPECT_EQ(f.device->limits().max_damping_Ns_per_m, 0.0);
  EXPECT_EQ(f.device->announced_limits().max_force_N, 2.0);
}

TEST(UdpDevice, OwnLimitStaysWhenTheDeviceAnnouncesALooserOne) {
  Fixture f;
  f.Handshake(DeviceLimits{"", 40.0, 0.0, 0.0});
  EXPECT_EQ(f.device->limits().max_force_N, 3.3);
}

TEST(UdpDevice, InvalidUntilTheFirstStateThenValid) {
  Fixture f;
  EXPECT_FALSE(f.device->Read().valid);
  f.Handshake();
  EXPECT_FALSE(f.device->Read().valid);
  f.SendState(7);
  const DeviceState state = f.ReadUntilReceived(2);
  EXPECT_TRUE(state.valid);
  EXPECT_EQ(state.sequence, 7u);
  EXPECT_EQ(state.position_m, Vec3(7.0, 0.0, 0.0));
  EXPECT_EQ(f.device->counters().accepted, 1u);
}

TEST(UdpDevice, WriteSendsAuthenticatedCommandsWithIncreasingCounters) {
  Fixture f;
  f.Handshake();
  for (std::uint64_t i = 1; i <= 2; ++i) {
    DeviceCommand command;
    command.sequence = 12;
    command.force_N = Vec3(0.5, -1.0, 2.0);
    command.clipped = true;
    f.device->Write(command);
    const std::vector<std::uint8_t> bytes = f.FromClient();
    PacketHeader header;
    ASSERT_EQ(CheckFraming(bytes, PacketType::kHello, PacketType::kCommand, &header),
              DecodeResult::kOk);
    ASSERT_TRUE(VerifyMac(bytes, f.key));
    EXPECT_EQ(header.type, PacketType::kCommand);
    EXPECT_EQ(header.client_nonce, f.client_nonce);
    EXPECT_EQ(header.server_nonce, kServerNonce);
    EXPECT_EQ(header.counter, i);
    DeviceCommand received;
    ASSERT_EQ(DecodeCommandPayload(bytes, &received), DecodeResult::kOk);
    EXPECT_EQ(received.sequence, 12u);
    EXPECT_EQ(received.force_N, command.force_N);
    EXPECT_TRUE(received.clipped);
  }
}

TEST(UdpDevice, ReplayedAndOlderCountersAreDropped) {
  Fixture f;
  f.Handshake();
  const std::vector<std::uint8_t> five = f.StateBytes(5, 5);
  f.SendRaw(five);
  f.ReadUntilReceived(2);
  f.SendRaw(five);                // the same datagram again: a replay
  f.SendRaw(f.StateBytes(9, 3));  // an older counter, whatever its sequence
  f.SendRaw(f.StateBytes(9, 5));  // an equal counter with a new payload
  const DeviceState state = f.ReadUntilReceived(5);
  EXPECT_EQ(f.device->counters().replayed, 3u);
  EXPECT_EQ(f.device->counters().accepted, 1u);
  EXPECT_EQ(state.sequence, 5u);
  f.SendRaw(f.StateBytes(6, 6));
  EXPECT_EQ(f.ReadUntilReceived(6).sequence, 6u);
}

TEST(UdpDevice, NewestSequenceWinsWithinTheSession) {
  Fixture f;
  f.Handshake();
  // counters increase; sequences arrive 1 3 2 3 5 4 5: 2, 4 stale; the second 3 and 5 duplicates
  const std::vector<std::uint64_t> arrivals = {1, 3, 2, 3, 5, 4, 5};
  for (const std::uint64_t sequence : arrivals) f.SendState(sequence);
  const DeviceState state = f.ReadUntilReceived(1 + arrivals.size());
  EXPECT_TRUE(state.valid);
  EXPECT_EQ(state.sequence, 5u);
  const UdpCounters& counters = f.device->counters();
  EXPECT_EQ(counters.accepted, 3u);
  EXPECT_EQ(counters.stale, 2u);
  EXPECT_EQ(counters.duplicate, 2u);
  EXPECT_EQ(counters.MalformedTotal(), 0u);
}

TEST(UdpDevice, StatesOutsideTheSessionAreDropped) {
  Fixture f;
  // before any session: authenticated, but nothing to belong to
  f.client_nonce = f.ReceiveHello();
  f.server_nonce = kServerNonce;
  f.SendRaw(f.StateBytes(1, 1));
  f.ReadUntilReceived(1);
  EXPECT_EQ(f.device->counters().no_session, 1u);
  // a reply to a hello the client never sent (or an old one): no session either
  f.SendRaw(EncodeHelloReply(DeviceLimits{}, f.client_nonce ^ 1, kServerNonce, f.key));
  f.ReadUntilReceived(2);
  EXPECT_EQ(f.device->counters().no_session, 2u);
  EXPECT_FALSE(f.device->has_session());

  f.Handshake(DeviceLimits{}, kServerNonce, /*receive_hello=*/false);
  // another server nonce (a recorded session), another client nonce
  const std::uint64_t nonce = f.client_nonce;
  f.server_nonce = kServerNonce + 1;
  f.SendRaw(f.StateBytes(2, 2));
  f.server_nonce = kServerNonce;
  f.client_nonce = nonce + 1;
  f.SendRaw(f.StateBytes(3, 3));
  // a second reply in the session, with another server nonce, does not replace it
  f.SendRaw(EncodeHelloReply(DeviceLimits{}, nonce, kServerNonce + 2, f.key));
  const DeviceState state = f.ReadUntilReceived(6);
  EXPECT_EQ(f.device->counters().no_session, 5u);
  EXPECT_FALSE(state.valid);
  EXPECT_EQ(f.device->counters().accepted, 0u);
  EXPECT_EQ(f.device->counters().handshakes, 1u);
}

TEST(UdpDevice, UnauthenticatedStatesAreDroppedAndCounted) {
  Fixture f;
  f.Handshake();
  // the right session, the wrong key: an attacker who saw the nonces still cannot forge
  const DeviceKey right = f.key;
  f.key = KeyOf(8);
  f.SendRaw(f.StateBytes(1, 1));
  f.SendRaw(EncodeHelloReply(DeviceLimits{}, f.client_nonce, kServerNonce, f.key));
  f.key = right;
  std::vector<std::uint8_t> flipped = f.StateBytes(2, 2);
  flipped[60] ^= 0x04;
  f.SendRaw(flipped);
  const DeviceState state = f.ReadUntilReceived(4);
  EXPECT_EQ(f.device->counters().unauthenticated, 3u);
  EXPECT_EQ(f.device->counters().accepted, 0u);
  EXPECT_FALSE(state.valid);
}

TEST(UdpDevice, EveryMalformedDatagramIsDroppedAndCountedByReason) {
  Fixture f;
  f.Handshake();
  f.SendState(100);
  f.ReadUntilReceived(2);
  std::uint64_t received = 2;

  // truncated at every length, including the empty datagram
  const std::vector<std::uint8_t> good = f.StateBytes(200, 1000);
  for (std::size_t length = 0; length < good.size(); ++length) {
    f.SendRaw(std::span(good.data(), length));
    // drain as we go so the socket's receive buffer never overflows
    f.ReadUntilReceived(++received);
  }
  std::vector<std::uint8_t> bad_magic = good;
  bad_magic[3] = 'X';
  std::vector<std::uint8_t> version_1 = good;
  version_1[4] = 1;
  ResealWith(version_1, f.key);
  const CommandPacket wrong_type = EncodeCommand(DeviceCommand{}, PacketHeader{}, f.key);
  std::vector<std::uint8_t> one_byte_more = good;
  one_byte_more.push_back(0);
  std::vector<std::uint8_t> larger_than_buffer = good;
  larger_than_buffer.resize(kMaxDatagramBytes + 100, 0);
  std::vector<std::uint8_t> nan_payload = f.StateBytes(201, 1001);
  const auto nan_bits = std::bit_cast<std::uint64_t>(std::numeric_limits<double>::quiet_NaN());
  for (int i = 0; i < 8; ++i) nan_payload[56 + i] = static_cast<std::uint8_t>(nan_bits >> (8 * i));
  ResealWith(nan_payload, f.key);
  std::vector<std::uint8_t> zero_quaternion = f.StateBytes(202, 1002);
  std::fill(zero_quaternion.begin() + 80, zero_quaternion.begin() + 112, 0);
  ResealWith(zero_quaternion, f.key);

  for (const std::span<const std::uint8_t> bytes :
       {std::span<const std::uint8_t>(bad_magic), std::span<const std::uint8_t>(version_1),
        std::span<const std::uint8_t>(wrong_type), std::span<const std::uint8_t>(one_byte_more),
        std::span<const std::uint8_t>(larger_than_buffer),
        std::span<const std::uint8_t>(nan_payload),
        std::span<const std::uint8_t>(zero_quaternion)}) {
    f.SendRaw(bytes);
    f.ReadUntilReceived(++received);
  }

  const DeviceState state = f.device->Read();
  const UdpCounters& counters = f.device->counters();
  EXPECT_EQ(counters.Malformed(DecodeResult::kTooShort), good.size());
  EXPECT_EQ(counters.Malformed(DecodeResult::kBadMagic), 1u);
  EXPECT_EQ(counters.Malformed(DecodeResult::kWrongVersion), 1u);
  EXPECT_EQ(counters.Malformed(DecodeResult::kWrongType), 1u);
  EXPECT_EQ(counters.Malformed(DecodeResult::kOversized), 2u);
  EXPECT_EQ(counters.Malformed(DecodeResult::kNonFinite), 1u);
  EXPECT_EQ(counters.Malformed(DecodeResult::kBadQuaternion), 1u);
  EXPECT_EQ(counters.Malformed(DecodeResult::kOk), 0u);
  EXPECT_EQ(counters.MalformedTotal(), good.size() + 7);
  EXPECT_EQ(counters.unauthenticated, 0u);
  EXPECT_EQ(counters.accepted, 1u);
  // the good state survives all of it
  EXPECT_TRUE(state.valid);
  EXPECT_EQ(state.sequence, 100u);
}

TEST(UdpDevice, DatagramsFromOtherAddressesAreIgnored) {
  Fixture f;
  f.Handshake();
  UdpSocket stranger(Loopback0(), "stranger");
  ASSERT_EQ(stranger.SendTo(f.StateBytes(9, 1), f.device->local_endpoint()), 0);
  const DeviceState state = f.ReadUntilReceived(2);
  EXPECT_FALSE(state.valid);
  EXPECT_EQ(f.device->counters().wrong_source, 1u);
  EXPECT_EQ(f.device->counters().accepted, 0u);
}

TEST(UdpDevice, WatchdogTripsStartsANewHandshakeAndRecovers) {
  constexpr double kWatchdog_s = 0.02;
  Fixture f(kWatchdog_s);
  f.Handshake();
  const std::uint64_t first_nonce = f.client_nonce;
  const auto sent_at = std::chrono::steady_clock::now();
  f.SendState(1);
  ASSERT_TRUE(f.ReadUntilReceived(2).valid);

  // stale: the watchdog trips, and not before its time (a lower bound the logic guarantees)
  DeviceState state;
  ASSERT_TRUE(PollUntil([&] {
    state = f.device->Read();
    return !state.valid;
  }));
  const double waited_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - sent_at).count();
  EXPECT_GE(waited_s, kWatchdog_s);
  EXPECT_TRUE(f.device->watchdog_tripped());
  EXPECT_FALSE(f.device->has_session());
  EXPECT_EQ(f.device->counters().watchdog_trips, 1u);
  EXPECT_EQ(state.position_m.x(), 1.0) << "the last pose is kept, only flagged invalid";
  f.device->Read();
  EXPECT_EQ(f.device->counters().watchdog_trips, 1u);

  // the old session's states no longer count
  f.SendState(2);
  f.ReadUntilReceived(3);
  EXPECT_EQ(f.device->counters().no_session, 1u);

  // a new session (a restarted server numbers from 1 again) recovers
  f.Handshake(DeviceLimits{}, kServerNonce + 1);
  EXPECT_NE(f.client_nonce, first_nonce) << "each handshake has a fresh nonce";
  f.SendState(1);
  state = f.ReadUntilReceived(5);
  EXPECT_TRUE(state.valid);
  EXPECT_EQ(state.sequence, 1u);
  EXPECT_FALSE(f.device->watchdog_tripped());
  EXPECT_EQ(f.device->counters().recoveries, 1u);
  EXPECT_EQ(f.device->counters().stale, 0u);
}

TEST(UdpDevice, AFloodIsTakenAtMostAFewDozenDatagramsPerRead) {
  Fixture f;
  const std::vector<std::uint8_t> forged(kStatePacketBytes, 0);
  for (int i = 0; i < kMaxDatagramsPerPeriod + 36; ++i) f.SendRaw(forged);
  f.device->Read();
  EXPECT_EQ(f.device->counters().received, static_cast<std::uint64_t>(kMaxDatagramsPerPeriod));
  f.device->Read();
  EXPECT_EQ(f.device->counters().received, kMaxDatagramsPerPeriod + 36u);
}

TEST(UdpDevice, ReadAndWriteDoNotAllocate) {
  if (!test::kMallocCounting) GTEST_SKIP() << "malloc is owned by the sanitizer";
  Fixture f;
  f.Handshake();
  f.SendState(1);
  f.ReadUntilReceived(2);
  for (std::uint64_t sequence = 2; sequence <= 20; ++sequence) f.SendState(sequence);
  f.SendRaw(std::vector<std::uint8_t>(3, 0));  // a malformed one too
  f.SendRaw(f.StateBytes(3, 3));               // a replayed one
  // the measured region: Read (draining good, malformed and no datagrams) and Write, repeated
  test::LimitMalloc guard;
  DeviceState state;
  const bool all_read = PollUntil([&] {
    state = f.device->Read();
    DeviceCommand command;
    command.sequence = state.sequence;
    f.device->Write(command);
    return f.device->counters().received >= 23;
  });
  const long allocations = guard.allocations();
  ASSERT_TRUE(all_read);
  EXPECT_EQ(allocations, 0);
  EXPECT_EQ(state.sequence, 20u);
  EXPECT_EQ(f.device->counters().Malformed(DecodeResult::kTooShort), 1u);
  EXPECT_EQ(f.device->counters().replayed, 1u);
}

TEST(UdpDevice, HelloAfterAWatchdogTripDoesNotAllocate) {
  if (!test::kMallocCounting) GTEST_SKIP() << "malloc is owned by the sanitizer";
  Fixture f(0.01, 0.002);
  f.Handshake();
  f.SendState(1);
  f.ReadUntilReceived(2);
  // the measured region: the trip, a new nonce, and hello resends
  test::LimitMalloc guard;
  const bool resent = PollUntil([&] {
    f.device->Read();
    return f.device->counters().watchdog_trips == 1 && f.device->counters().sent >= 4;
  });
  const long allocations = guard.allocations();
  ASSERT_TRUE(resent);
  EXPECT_EQ(allocations, 0);
}

TEST(UdpDevice, OptionErrorsNameTheField) {
  const auto message_of = [](UdpDeviceOptions options) -> std::string {
    options.key = KeyOf(1);
    try {
      UdpDevice device(options);
    } catch (const Error& error) {
      return error.what();
    }
    return "";
  };
  UdpDeviceOptions options;
  options.server = "udp://127.0.0.1";
  EXPECT_NE(message_of(options).find("'udp://127.0.0.1'"), std::string::npos);
  options.server = "udp://127.0.0.1:0";
  EXPECT_NE(message_of(options).find("[1, 65535]"), std::string::npos);
  options.server = "udp://10.1.2.3:47000";
  EXPECT_NE(message_of(options).find("loopback"), std::string::npos);
  options.server = "udp://127.0.0.1:47000";
  options.local = "udp://0.0.0.0:0";
  EXPECT_NE(message_of(options).find("loopback"), std::string::npos);
  options.local = "udp://127.0.0.1:0";
  options.watchdog_s = 0.0;
  EXPECT_NE(message_of(options).find("watchdog_s"), std::string::npos);
  options.watchdog_s = 0.05;
  options.hello_interval_s = 0.0;
  EXPECT_NE(message_of(options).find("hello_interval_s"), std::string::npos);
  options.hello_interval_s = 0.02;
  options.test_loss.incoming_fraction = 1.5;
  EXPECT_NE(message_of(options).find("test_loss.incoming_fraction"), std::string::npos);
}

TEST(UdpDevice, AMissingKeyFileNamesItAndHowToMakeOne) {
  UdpDeviceOptions options;
  options.key_file = "/nonexistent-rigidtouch-test/device.key";
  try {
    UdpDevice device(options);
    FAIL() << "expected an Error";
  } catch (const Error& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find(options.key_file), std::string::npos) << message;
    EXPECT_NE(message.find("keygen"), std::string::npos) << message;
  }
}

TEST(UdpDevice, LocalAddressInUseNamesIt) {
  UdpSocket taken(Loopback0(), "taken");
  UdpDeviceOptions options;
  options.local = taken.local().ToString();
  options.key = KeyOf(1);
  try {
    UdpDevice device(options);
    FAIL() << "expected an Error";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find(taken.local().ToString()), std::string::npos)
        << error.what();
  }
}

}  // namespace
}  // namespace rigidtouch::device
