#include "rigidtouch/bridge.h"

#include <gtest/gtest.h>

#include <array>
#include <chrono>
#include <string>
#include <vector>

#include "device/udp_device.h"
#include "limit_malloc.h"
#include "loop/test_poll.h"

namespace rigidtouch::device {
namespace {

using testing::PollUntil;

UdpEndpoint Loopback0() {
  return ParseUdpAddress("udp://127.0.0.1:0", "test");
}

// a device that moves along x one millimetre per read and remembers the last command
class FakeDevice final : public Device {
 public:
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

UdpDeviceServerOptions ServerOptions(double watchdog_s = 0.5) {
  UdpDeviceServerOptions options;
  options.listen = "udp://127.0.0.1:0";
  options.watchdog_s = watchdog_s;
  return options;
}

void SendCommand(UdpSocket& client, const UdpEndpoint& server, std::uint64_t sequence,
                 double force_x_N) {
  DeviceCommand command;
  command.sequence = sequence;
  command.force_N = Vec3(force_x_N, 0.0, 0.0);
  ASSERT_EQ(client.SendTo(EncodeCommand(command), server), 0);
}

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

TEST(UdpDeviceServer, LearnsTheClientAppliesItsCommandAndStreamsStatesToIt) {
  FakeDevice device;
  UdpDeviceServer server(device, ServerOptions());
  UdpSocket client(Loopback0(), "client");
  SendCommand(client, server.local_endpoint(), 0, 1.25);
  StepUntilReceived(server, 1);
  ASSERT_TRUE(server.has_peer());
  EXPECT_EQ(server.peer(), client.local());
  EXPECT_EQ(server.counters().peer_changes, 1u);
  EXPECT_EQ(device.last.force_N, Vec3(1.25, 0.0, 0.0));
  EXPECT_FALSE(device.last.safe_fallback);

  server.Step();  // now the state goes out
  std::array<std::uint8_t, kMaxDatagramBytes> buffer{};
  Datagram datagram;
  ASSERT_TRUE(PollUntil([&] { return client.Receive(buffer, &datagram) == 0; }));
  EXPECT_EQ(datagram.source, server.local_endpoint());
  DeviceState state;
  ASSERT_EQ(DecodeState(std::span(buffer.data(), datagram.bytes), &state), DecodeResult::kOk);
  EXPECT_EQ(state.sequence, server.last_sequence());
  EXPECT_EQ(state.sequence, 1u) << "the server numbers states itself, from 1";
  EXPECT_DOUBLE_EQ(state.position_m.x(), 0.001 * static_cast<double>(device.reads));
}

TEST(UdpDeviceServer, FixedPeerGetsStatesAtOnceAndOthersAreIgnored) {
  FakeDevice device;
  UdpSocket renderer(Loopback0(), "renderer");
  UdpSocket stranger(Loopback0(), "stranger");
  UdpDeviceServerOptions options = ServerOptions();
  options.peer = renderer.local().ToString();
  UdpDeviceServer server(device, options);
  server.Step();
  EXPECT_EQ(server.counters().sent, 1u);
  SendCommand(stranger, server.local_endpoint(), 5, 9.0);
  StepUntilReceived(server, 1);
  EXPECT_EQ(server.counters().wrong_source, 1u);
  EXPECT_TRUE(device.last.safe_fallback) << "the stranger's command must not reach the device";
  EXPECT_EQ(server.peer(), renderer.local());
}

TEST(UdpDeviceServer, NewestCommandWinsAndEqualSequenceReplaces) {
  FakeDevice device;
  UdpDeviceServer server(device, ServerOptions());
  UdpSocket client(Loopback0(), "client");
  SendCommand(client, server.local_endpoint(), 5, 5.0);
  StepUntilReceived(server, 1);
  // older: dropped; equal: the later answer to the same state replaces the earlier one
  SendCommand(client, server.local_endpoint(), 3, 3.0);
  SendCommand(client, server.local_endpoint(), 5, 5.5);
  StepUntilReceived(server, 3);
  EXPECT_EQ(server.counters().stale, 1u);
  EXPECT_EQ(server.counters().accepted, 2u);
  EXPECT_EQ(device.last.force_N.x(), 5.5);
  EXPECT_EQ(device.last.sequence, 5u);
}

TEST(UdpDeviceServer, MalformedCommandsAreCountedAndNeverApplied) {
  FakeDevice device;
  UdpDeviceServer server(device, ServerOptions());
  UdpSocket client(Loopback0(), "client");
  SendCommand(client, server.local_endpoint(), 1, 1.0);
  StepUntilReceived(server, 1);

  DeviceCommand command;
  command.sequence = 2;
  command.force_N = Vec3(2.0, 0.0, 0.0);
  const CommandPacket good = EncodeCommand(command);
  std::vector<std::uint8_t> truncated(good.begin(), good.begin() + 40);
  std::vector<std::uint8_t> bad_checksum(good.begin(), good.end());
  bad_checksum[30] ^= 1;
  std::vector<std::uint8_t> oversized(2000, 0);
  const StatePacket wrong_type = EncodeState(DeviceState{});
  for (const std::span<const std::uint8_t> bytes :
       {std::span<const std::uint8_t>(truncated), std::span<const std::uint8_t>(bad_checksum),
        std::span<const std::uint8_t>(oversized), std::span<const std::uint8_t>(wrong_type)}) {
    ASSERT_EQ(client.SendTo(bytes, server.local_endpoint()), 0);
  }
  StepUntilReceived(server, 5);
  const UdpCounters& counters = server.counters();
  EXPECT_EQ(counters.Malformed(DecodeResult::kTooShort), 1u);
  EXPECT_EQ(counters.Malformed(DecodeResult::kBadChecksum), 1u);
  EXPECT_EQ(counters.Malformed(DecodeResult::kOversized), 1u);
  EXPECT_EQ(counters.Malformed(DecodeResult::kWrongType), 1u);
  EXPECT_EQ(device.last.force_N.x(), 1.0);
}

TEST(UdpDeviceServer, WatchdogWritesZeroForceThenRecovers) {
  constexpr double kWatchdog_s = 0.02;
  FakeDevice device;
  UdpDeviceServer server(device, ServerOptions(kWatchdog_s));
  UdpSocket client(Loopback0(), "client");
  const auto sent_at = std::chrono::steady_clock::now();
  SendCommand(client, server.local_endpoint(), 1, 2.0);
  StepUntilReceived(server, 1);
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

  SendCommand(client, server.local_endpoint(), 2, 3.0);
  StepUntilReceived(server, 2);
  EXPECT_FALSE(device.last.safe_fallback);
  EXPECT_EQ(device.last.force_N.x(), 3.0);
  EXPECT_EQ(server.counters().recoveries, 1u);
  EXPECT_FALSE(server.watchdog_tripped());
}

TEST(UdpDeviceServer, InvalidDeviceReadingsAreNotSent) {
  FakeDevice device;
  UdpSocket renderer(Loopback0(), "renderer");
  UdpDeviceServerOptions options = ServerOptions();
  options.peer = renderer.local().ToString();
  UdpDeviceServer server(device, options);
  device.valid = false;
  server.Step();
  EXPECT_EQ(server.counters().sent, 0u);
  EXPECT_EQ(server.counters().invalid_device_states, 1u);
  device.valid = true;
  server.Step();
  EXPECT_EQ(server.counters().sent, 1u);
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

TEST(UdpDeviceServer, NonLoopbackListenNeedsTheExplicitOption) {
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
}

TEST(UdpDeviceServer, StepDoesNotAllocate) {
  if (!test::kMallocCounting) GTEST_SKIP() << "malloc is owned by the sanitizer";
  FakeDevice device;
  UdpDeviceServer server(device, ServerOptions());
  UdpSocket client(Loopback0(), "client");
  SendCommand(client, server.local_endpoint(), 1, 1.0);
  SendCommand(client, server.local_endpoint(), 2, 2.0);
  ASSERT_EQ(client.SendTo(std::vector<std::uint8_t>(5, 1), server.local_endpoint()), 0);
  test::LimitMalloc guard;
  const bool all = PollUntil([&] {
    server.Step();
    return server.counters().received >= 3;
  });
  server.Step();
  const long allocations = guard.allocations();
  ASSERT_TRUE(all);
  EXPECT_EQ(allocations, 0);
  EXPECT_GE(server.counters().sent, 1u);
}

// client and server end to end, 5 % simulated loss each way on the server, seeded
TEST(UdpDeviceServer, EndToEndWithFivePercentLoss) {
  constexpr int kSteps = 2000;
  FakeDevice device;
  UdpDeviceServerOptions server_options = ServerOptions(1.0);
  server_options.test_loss = PacketLoss{0.05, 0.05, 12345};
  UdpDeviceServer server(device, server_options);
  UdpDeviceOptions client_options;
  client_options.server = server.local_endpoint().ToString();
  client_options.watchdog_s = 1.0;  // generous: only a stalled machine could trip it
  UdpDevice client(client_options);

  std::uint64_t valid_reads = 0;
  for (int step = 0; step < kSteps; ++step) {
    server.Step();
    const DeviceState state = client.Read();
    DeviceCommand command;
    command.sequence = state.sequence;
    command.force_N = Vec3(static_cast<double>(state.sequence), 0.0, 0.0);
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
  // states: nothing is lost on loopback except what the simulation drops
  EXPECT_EQ(c.accepted + c.stale + c.duplicate, s.sent);
  EXPECT_EQ(c.MalformedTotal(), 0u);
  EXPECT_EQ(s.accepted + s.stale + s.test_dropped_incoming, c.sent);
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
  EXPECT_EQ(device.last.force_N.x(), static_cast<double>(device.last.sequence));
}

}  // namespace
}  // namespace rigidtouch::device
