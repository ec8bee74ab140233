#include "device/udp_device.h"

#include <gtest/gtest.h>

#include <bit>
#include <chrono>
#include <limits>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "limit_malloc.h"
#include "loop/test_poll.h"

namespace rigidtouch::device {
namespace {

using testing::PollUntil;

UdpEndpoint Loopback0() {
  return ParseUdpAddress("udp://127.0.0.1:0", "test");
}

// a raw socket playing the device server, so tests control every byte that reaches the client
struct Fixture {
  explicit Fixture(double watchdog_s = 0.5) : server(Loopback0(), "test server") {
    UdpDeviceOptions options;
    options.server = server.local().ToString();
    options.local = "udp://127.0.0.1:0";
    options.watchdog_s = watchdog_s;
    options.limits.name = "udp-test";
    options.limits.max_force_N = 3.3;
    device = std::make_unique<UdpDevice>(options);
  }

  void SendRaw(std::span<const std::uint8_t> bytes) {
    ASSERT_EQ(server.SendTo(bytes, device->local_endpoint()), 0);
  }

  void SendState(std::uint64_t sequence) {
    DeviceState state;
    state.sequence = sequence;
    state.time_s = 0.001 * static_cast<double>(sequence);
    state.position_m = Vec3(static_cast<double>(sequence), 0.0, 0.0);
    SendRaw(EncodeState(state));
  }

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
  std::unique_ptr<UdpDevice> device;
};

std::vector<std::uint8_t> StateBytes(std::uint64_t sequence) {
  DeviceState state;
  state.sequence = sequence;
  const StatePacket packet = EncodeState(state);
  return {packet.begin(), packet.end()};
}

void Reseal(std::vector<std::uint8_t>& datagram) {
  const std::uint32_t crc = PacketChecksum(datagram);
  for (int i = 0; i < 4; ++i) datagram[12 + i] = static_cast<std::uint8_t>(crc >> (8 * i));
}

TEST(UdpDevice, AnnouncesItselfWithASafeZeroCommand) {
  Fixture f;
  std::array<std::uint8_t, kMaxDatagramBytes> buffer{};
  Datagram datagram;
  ASSERT_TRUE(PollUntil([&] { return f.server.Receive(buffer, &datagram) == 0; }));
  EXPECT_EQ(datagram.source, f.device->local_endpoint());
  DeviceCommand hello;
  ASSERT_EQ(DecodeCommand(std::span(buffer.data(), datagram.bytes), &hello), DecodeResult::kOk);
  EXPECT_TRUE(hello.safe_fallback);
  EXPECT_EQ(hello.force_N, Vec3::Zero());
  EXPECT_EQ(f.device->counters().sent, 1u);
}

TEST(UdpDevice, InvalidUntilTheFirstStateThenValid) {
  Fixture f;
  EXPECT_FALSE(f.device->Read().valid);
  f.SendState(7);
  const DeviceState state = f.ReadUntilReceived(1);
  EXPECT_TRUE(state.valid);
  EXPECT_EQ(state.sequence, 7u);
  EXPECT_EQ(state.position_m, Vec3(7.0, 0.0, 0.0));
  EXPECT_EQ(f.device->counters().accepted, 1u);
  EXPECT_EQ(f.device->limits().name, "udp-test");
  EXPECT_EQ(f.device->limits().max_force_N, 3.3);
}

TEST(UdpDevice, WriteSendsTheCommand) {
  Fixture f;
  std::array<std::uint8_t, kMaxDatagramBytes> buffer{};
  Datagram datagram;
  ASSERT_TRUE(PollUntil([&] { return f.server.Receive(buffer, &datagram) == 0; }));  // hello
  DeviceCommand command;
  command.sequence = 12;
  command.force_N = Vec3(0.5, -1.0, 2.0);
  command.clipped = true;
  f.device->Write(command);
  ASSERT_TRUE(PollUntil([&] { return f.server.Receive(buffer, &datagram) == 0; }));
  DeviceCommand received;
  ASSERT_EQ(DecodeCommand(std::span(buffer.data(), datagram.bytes), &received), DecodeResult::kOk);
  EXPECT_EQ(received.sequence, 12u);
  EXPECT_EQ(received.force_N, command.force_N);
  EXPECT_TRUE(received.clipped);
  EXPECT_EQ(f.device->counters().sent, 2u);
}

TEST(UdpDevice, NewestSequenceWinsOverReorderedAndDuplicatedPackets) {
  Fixture f;
  // arrival order 1 3 2 3 5 4 5: 1, 3, 5 are fresh; 2, 4 stale; the second 3 and 5 duplicates
  const std::vector<std::uint64_t> arrivals = {1, 3, 2, 3, 5, 4, 5};
  for (const std::uint64_t sequence : arrivals) f.SendState(sequence);
  const DeviceState state = f.ReadUntilReceived(arrivals.size());
  EXPECT_TRUE(state.valid);
  EXPECT_EQ(state.sequence, 5u);
  EXPECT_EQ(state.position_m.x(), 5.0);
  const UdpCounters& counters = f.device->counters();
  EXPECT_EQ(counters.received, 7u);
  EXPECT_EQ(counters.accepted, 3u);
  EXPECT_EQ(counters.stale, 2u);
  EXPECT_EQ(counters.duplicate, 2u);
  EXPECT_EQ(counters.MalformedTotal(), 0u);
}

TEST(UdpDevice, EveryMalformedDatagramIsDroppedAndCountedByReason) {
  Fixture f;
  f.SendState(100);
  f.ReadUntilReceived(1);
  std::uint64_t sent = 1;

  // truncated at every length, including the empty datagram
  const std::vector<std::uint8_t> good = StateBytes(200);
  for (std::size_t length = 0; length < good.size(); ++length) {
    f.SendRaw(std::span(good.data(), length));
    // drain as we go so the socket's receive buffer never overflows
    f.ReadUntilReceived(++sent);
  }
  std::vector<std::uint8_t> bad_magic = good;
  bad_magic[3] = 'X';
  std::vector<std::uint8_t> wrong_version = good;
  wrong_version[4] = 2;
  Reseal(wrong_version);
  DeviceCommand command;
  const CommandPacket wrong_type = EncodeCommand(command);
  std::vector<std::uint8_t> one_byte_more = good;
  one_byte_more.push_back(0);
  std::vector<std::uint8_t> larger_than_buffer = good;
  larger_than_buffer.resize(kMaxDatagramBytes + 100, 0);
  std::vector<std::uint8_t> bad_checksum = good;
  bad_checksum[40] ^= 0x10;
  std::vector<std::uint8_t> nan_payload = good;
  const auto nan_bits = std::bit_cast<std::uint64_t>(std::numeric_limits<double>::quiet_NaN());
  for (int i = 0; i < 8; ++i) nan_payload[32 + i] = static_cast<std::uint8_t>(nan_bits >> (8 * i));
  Reseal(nan_payload);
  std::vector<std::uint8_t> zero_quaternion = good;
  std::fill(zero_quaternion.begin() + 56, zero_quaternion.begin() + 88, 0);
  Reseal(zero_quaternion);

  for (const std::span<const std::uint8_t> bytes :
       {std::span<const std::uint8_t>(bad_magic), std::span<const std::uint8_t>(wrong_version),
        std::span<const std::uint8_t>(wrong_type), std::span<const std::uint8_t>(one_byte_more),
        std::span<const std::uint8_t>(larger_than_buffer),
        std::span<const std::uint8_t>(bad_checksum), std::span<const std::uint8_t>(nan_payload),
        std::span<const std::uint8_t>(zero_quaternion)}) {
    f.SendRaw(bytes);
    f.ReadUntilReceived(++sent);
  }

  const DeviceState state = f.device->Read();
  const UdpCounters& counters = f.device->counters();
  EXPECT_EQ(counters.Malformed(DecodeResult::kTooShort), good.size());
  EXPECT_EQ(counters.Malformed(DecodeResult::kBadMagic), 1u);
  EXPECT_EQ(counters.Malformed(DecodeResult::kWrongVersion), 1u);
  EXPECT_EQ(counters.Malformed(DecodeResult::kWrongType), 1u);
  EXPECT_EQ(counters.Malformed(DecodeResult::kOversized), 2u);
  EXPECT_EQ(counters.Malformed(DecodeResult::kBadChecksum), 1u);
  EXPECT_EQ(counters.Malformed(DecodeResult::kNonFinite), 1u);
  EXPECT_EQ(counters.Malformed(DecodeResult::kBadQuaternion), 1u);
  EXPECT_EQ(counters.Malformed(DecodeResult::kOk), 0u);
  EXPECT_EQ(counters.MalformedTotal(), good.size() + 8);
  EXPECT_EQ(counters.accepted, 1u);
  // the good state survives all of it
  EXPECT_TRUE(state.valid);
  EXPECT_EQ(state.sequence, 100u);
}

TEST(UdpDevice, DatagramsFromOtherAddressesAreIgnored) {
  Fixture f;
  UdpSocket stranger(Loopback0(), "stranger");
  ASSERT_EQ(stranger.SendTo(StateBytes(9), f.device->local_endpoint()), 0);
  const DeviceState state = f.ReadUntilReceived(1);
  EXPECT_FALSE(state.valid);
  EXPECT_EQ(f.device->counters().wrong_source, 1u);
  EXPECT_EQ(f.device->counters().accepted, 0u);
}

TEST(UdpDevice, WatchdogTripsWithinItsTimeAndRecovers) {
  constexpr double kWatchdog_s = 0.02;
  Fixture f(kWatchdog_s);
  const auto sent_at = std::chrono::steady_clock::now();
  f.SendState(1);
  ASSERT_TRUE(f.ReadUntilReceived(1).valid);

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
  EXPECT_EQ(f.device->counters().watchdog_trips, 1u);
  EXPECT_EQ(state.position_m.x(), 1.0) << "the last pose is kept, only flagged invalid";
  // repeated reads while stale count one trip, not one per read
  f.device->Read();
  EXPECT_EQ(f.device->counters().watchdog_trips, 1u);

  // fresh state: recovery
  f.SendState(2);
  state = f.ReadUntilReceived(2);
  EXPECT_TRUE(state.valid);
  EXPECT_EQ(state.sequence, 2u);
  EXPECT_FALSE(f.device->watchdog_tripped());
  EXPECT_EQ(f.device->counters().recoveries, 1u);
}

TEST(UdpDevice, AfterATripAnySequenceResynchronises) {
  Fixture f(0.02);
  f.SendState(1000);
  ASSERT_TRUE(f.ReadUntilReceived(1).valid);
  ASSERT_TRUE(PollUntil([&] { return !f.device->Read().valid; }));
  // a restarted server numbers from 1 again
  f.SendState(1);
  f.SendState(2);
  const DeviceState state = f.ReadUntilReceived(3);
  EXPECT_TRUE(state.valid);
  EXPECT_EQ(state.sequence, 2u);
  EXPECT_EQ(f.device->counters().stale, 0u);
  EXPECT_EQ(f.device->counters().recoveries, 1u);
}

TEST(UdpDevice, ReadAndWriteDoNotAllocate) {
  if (!test::kMallocCounting) GTEST_SKIP() << "malloc is owned by the sanitizer";
  Fixture f;
  f.SendState(1);
  f.ReadUntilReceived(1);
  for (std::uint64_t sequence = 2; sequence <= 20; ++sequence) f.SendState(sequence);
  f.SendRaw(std::vector<std::uint8_t>(3, 0));  // a malformed one too
  // the measured region: Read (draining good, malformed and no datagrams) and Write, repeated
  test::LimitMalloc guard;
  DeviceState state;
  const bool all_read = PollUntil([&] {
    state = f.device->Read();
    DeviceCommand command;
    command.sequence = state.sequence;
    f.device->Write(command);
    return f.device->counters().received >= 21;
  });
  const long allocations = guard.allocations();
  ASSERT_TRUE(all_read);
  EXPECT_EQ(allocations, 0);
  EXPECT_EQ(state.sequence, 20u);
  EXPECT_EQ(f.device->counters().Malformed(DecodeResult::kTooShort), 1u);
}

TEST(UdpDevice, OptionErrorsNameTheField) {
  const auto message_of = [](const UdpDeviceOptions& options) -> std::string {
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
  options.test_loss.incoming_fraction = 1.5;
  EXPECT_NE(message_of(options).find("test_loss.incoming_fraction"), std::string::npos);
}

TEST(UdpDevice, LocalAddressInUseNamesIt) {
  UdpSocket taken(Loopback0(), "taken");
  UdpDeviceOptions options;
  options.local = taken.local().ToString();
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
