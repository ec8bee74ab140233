#include "device/udp_protocol.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

namespace rigidtouch::device {
namespace {

// golden datagrams written independently with Python's struct.pack('<...') and zlib.crc32, so
// they pin the little-endian layout and the checksum of docs/device-protocol.md
constexpr const char* kGoldenStateHex =
    "52544348010001007c00000068fe2a8208070605040302010000000000002940000000000000f03f0000000000"
    "0000c0000000000000d03f000000000000e03f000000000000e0bf000000000000e03f000000000000e03f0000"
    "00000000c03f000000000000b0bf0000000000000840000000000000f8bf00000000000004400000000000001040"
    "a5000000";
constexpr const char* kGoldenCommandHex =
    "52544348010002003c0000008d2333ef2a00000000000000000000000000f83f00000000000002c00000000000"
    "0008400000000000000000000000000000e03f000000000000e8bf03000000";

std::vector<std::uint8_t> FromHex(const std::string& hex) {
  std::vector<std::uint8_t> bytes;
  for (std::size_t i = 0; i + 1 < hex.size(); i += 2) {
    bytes.push_back(static_cast<std::uint8_t>(std::stoi(hex.substr(i, 2), nullptr, 16)));
  }
  return bytes;
}

DeviceState GoldenState() {
  DeviceState state;
  state.sequence = 0x0102030405060708ull;
  state.time_s = 12.5;
  state.position_m = Vec3(1.0, -2.0, 0.25);
  state.orientation = Quat(0.5, -0.5, 0.5, 0.5);  // exactly unit: renormalising keeps the bits
  state.velocity_mps = Vec3(0.125, -0.0625, 3.0);
  state.angular_velocity_radps = Vec3(-1.5, 2.5, 4.0);
  state.buttons = 0xA5;
  return state;
}

DeviceCommand GoldenCommand() {
  DeviceCommand command;
  command.sequence = 42;
  command.force_N = Vec3(1.5, -2.25, 3.0);
  command.torque_Nm = Vec3(0.0, 0.5, -0.75);
  command.safe_fallback = true;
  command.clipped = true;
  return command;
}

// rewrites the CRC after a test edits a datagram, so the decoder reaches the later checks
void Reseal(std::vector<std::uint8_t>& datagram) {
  const std::uint32_t crc = PacketChecksum(datagram);
  for (int i = 0; i < 4; ++i) datagram[12 + i] = static_cast<std::uint8_t>(crc >> (8 * i));
}

void PutF64(std::vector<std::uint8_t>& datagram, std::size_t offset, double value) {
  const auto bits = std::bit_cast<std::uint64_t>(value);
  for (int i = 0; i < 8; ++i) datagram[offset + i] = static_cast<std::uint8_t>(bits >> (8 * i));
}

std::vector<std::uint8_t> StateBytes() {
  const StatePacket packet = EncodeState(GoldenState());
  return {packet.begin(), packet.end()};
}

std::vector<std::uint8_t> CommandBytes() {
  const CommandPacket packet = EncodeCommand(GoldenCommand());
  return {packet.begin(), packet.end()};
}

TEST(UdpProtocol, EncodeStateMatchesGoldenBytes) {
  EXPECT_EQ(StateBytes(), FromHex(kGoldenStateHex));
  EXPECT_EQ(StateBytes().size(), kStatePacketBytes);
}

TEST(UdpProtocol, EncodeCommandMatchesGoldenBytes) {
  EXPECT_EQ(CommandBytes(), FromHex(kGoldenCommandHex));
  EXPECT_EQ(CommandBytes().size(), kCommandPacketBytes);
}

TEST(UdpProtocol, StateRoundTripIsBitExact) {
  DeviceState decoded;
  decoded.valid = false;
  ASSERT_EQ(DecodeState(FromHex(kGoldenStateHex), &decoded), DecodeResult::kOk);
  const DeviceState expected = GoldenState();
  // exact comparisons: every field travels as its IEEE-754 bit pattern
  EXPECT_EQ(decoded.sequence, expected.sequence);
  EXPECT_EQ(decoded.time_s, expected.time_s);
  EXPECT_EQ(decoded.position_m, expected.position_m);
  EXPECT_EQ(decoded.orientation.coeffs(), expected.orientation.coeffs());
  EXPECT_EQ(decoded.velocity_mps, expected.velocity_mps);
  EXPECT_EQ(decoded.angular_velocity_radps, expected.angular_velocity_radps);
  EXPECT_EQ(decoded.buttons, expected.buttons);
  EXPECT_TRUE(decoded.valid);
}

TEST(UdpProtocol, CommandRoundTripIsBitExact) {
  DeviceCommand decoded;
  decoded.penalty_force_N = Vec3(9, 9, 9);
  ASSERT_EQ(DecodeCommand(FromHex(kGoldenCommandHex), &decoded), DecodeResult::kOk);
  const DeviceCommand expected = GoldenCommand();
  EXPECT_EQ(decoded.sequence, expected.sequence);
  EXPECT_EQ(decoded.force_N, expected.force_N);
  EXPECT_EQ(decoded.torque_Nm, expected.torque_Nm);
  EXPECT_TRUE(decoded.safe_fallback);
  EXPECT_TRUE(decoded.clipped);
  // the split into penalty and impulsive parts is not on the wire
  EXPECT_EQ(decoded.penalty_force_N, Vec3::Zero());
  EXPECT_EQ(decoded.impulsive_force_N, Vec3::Zero());
}

TEST(UdpProtocol, CommandFlagsAreIndependentBits) {
  for (const bool safe : {false, true}) {
    for (const bool clipped : {false, true}) {
      DeviceCommand command;
      command.safe_fallback = safe;
      command.clipped = clipped;
      const CommandPacket packet = EncodeCommand(command);
      EXPECT_EQ(packet[72], (safe ? 1 : 0) | (clipped ? 2 : 0));
      DeviceCommand decoded;
      ASSERT_EQ(DecodeCommand(packet, &decoded), DecodeResult::kOk);
      EXPECT_EQ(decoded.safe_fallback, safe);
      EXPECT_EQ(decoded.clipped, clipped);
    }
  }
}

TEST(UdpProtocol, ReservedCommandFlagBitsAreIgnored) {
  std::vector<std::uint8_t> bytes = CommandBytes();
  bytes[75] = 0x80;  // bit 31
  Reseal(bytes);
  DeviceCommand decoded;
  EXPECT_EQ(DecodeCommand(bytes, &decoded), DecodeResult::kOk);
}

TEST(UdpProtocol, ChecksumIsZlibCrc32OverHeadAndPayload) {
  // header bytes [0, 12) zero, checksum field ignored, payload "123456789":
  // zlib.crc32(b"\0" * 12 + b"123456789") = 0x6CF9E803
  std::vector<std::uint8_t> datagram(16, 0);
  datagram[12] = 0xFF;  // the checksum field itself is not covered
  for (const char c : std::string("123456789")) datagram.push_back(static_cast<std::uint8_t>(c));
  EXPECT_EQ(PacketChecksum(datagram), 0x6CF9E803u);
}

TEST(UdpProtocol, EveryTruncatedStateIsTooShort) {
  const std::vector<std::uint8_t> bytes = StateBytes();
  for (std::size_t length = 0; length < bytes.size(); ++length) {
    DeviceState decoded;
    EXPECT_EQ(DecodeState(std::span(bytes.data(), length), &decoded), DecodeResult::kTooShort)
        << "length " << length;
  }
}

TEST(UdpProtocol, EveryTruncatedCommandIsTooShort) {
  const std::vector<std::uint8_t> bytes = CommandBytes();
  for (std::size_t length = 0; length < bytes.size(); ++length) {
    DeviceCommand decoded;
    EXPECT_EQ(DecodeCommand(std::span(bytes.data(), length), &decoded), DecodeResult::kTooShort)
        << "length " << length;
  }
}

TEST(UdpProtocol, BadMagicWrongVersionWrongType) {
  DeviceState state;
  std::vector<std::uint8_t> bytes = StateBytes();
  bytes[0] ^= 0x01;
  EXPECT_EQ(DecodeState(bytes, &state), DecodeResult::kBadMagic);

  for (const std::uint8_t version : {0, 2, 255}) {
    bytes = StateBytes();
    bytes[4] = version;
    Reseal(bytes);
    EXPECT_EQ(DecodeState(bytes, &state), DecodeResult::kWrongVersion) << int{version};
  }

  // a command where a state is expected, and the reverse, and an unknown type
  EXPECT_EQ(DecodeState(CommandBytes(), &state), DecodeResult::kWrongType);
  DeviceCommand command;
  EXPECT_EQ(DecodeCommand(StateBytes(), &command), DecodeResult::kWrongType);
  bytes = StateBytes();
  bytes[6] = 7;
  Reseal(bytes);
  EXPECT_EQ(DecodeState(bytes, &state), DecodeResult::kWrongType);
}

TEST(UdpProtocol, OversizedPackets) {
  DeviceState state;
  // one trailing byte beyond the announced payload
  std::vector<std::uint8_t> bytes = StateBytes();
  bytes.push_back(0);
  EXPECT_EQ(DecodeState(bytes, &state), DecodeResult::kOversized);
  // a header announcing a larger payload than the type has, with the bytes to match
  bytes = StateBytes();
  bytes[8] = static_cast<std::uint8_t>(kStatePayloadBytes + 8);
  bytes.resize(kStatePacketBytes + 8, 0);
  Reseal(bytes);
  EXPECT_EQ(DecodeState(bytes, &state), DecodeResult::kOversized);
  // a huge datagram
  std::vector<std::uint8_t> huge = StateBytes();
  huge.resize(4000, 0);
  EXPECT_EQ(DecodeState(huge, &state), DecodeResult::kOversized);
  DeviceCommand command;
  std::vector<std::uint8_t> long_command = CommandBytes();
  long_command.push_back(0);
  EXPECT_EQ(DecodeCommand(long_command, &command), DecodeResult::kOversized);
}

TEST(UdpProtocol, ShorterAnnouncedPayloadIsTooShort) {
  std::vector<std::uint8_t> bytes = StateBytes();
  bytes[8] = static_cast<std::uint8_t>(kStatePayloadBytes - 4);
  bytes.resize(kStatePacketBytes - 4);
  Reseal(bytes);
  DeviceState state;
  EXPECT_EQ(DecodeState(bytes, &state), DecodeResult::kTooShort);
}

TEST(UdpProtocol, AnyFlippedBitIsABadChecksum) {
  const std::vector<std::uint8_t> original = StateBytes();
  // header bytes past the type and size checks (checksum itself) and every payload byte
  for (std::size_t byte = 12; byte < original.size(); ++byte) {
    for (int bit = 0; bit < 8; ++bit) {
      std::vector<std::uint8_t> bytes = original;
      bytes[byte] ^= static_cast<std::uint8_t>(1u << bit);
      DeviceState state;
      ASSERT_EQ(DecodeState(bytes, &state), DecodeResult::kBadChecksum)
          << "byte " << byte << " bit " << bit;
    }
  }
}

TEST(UdpProtocol, NonFiniteStateFieldsAreRejected) {
  // 14 f64 fields from offset 24 (time, position, quaternion, velocities)
  for (std::size_t field = 0; field < 14; ++field) {
    for (const double bad :
         {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity(),
          -std::numeric_limits<double>::infinity()}) {
      std::vector<std::uint8_t> bytes = StateBytes();
      PutF64(bytes, 24 + 8 * field, bad);
      Reseal(bytes);
      DeviceState state;
      state.sequence = 77;
      EXPECT_EQ(DecodeState(bytes, &state), DecodeResult::kNonFinite) << "field " << field;
      EXPECT_EQ(state.sequence, 77u) << "a failed decode leaves the output untouched";
    }
  }
}

TEST(UdpProtocol, NonFiniteCommandFieldsAreRejected) {
  for (std::size_t field = 0; field < 6; ++field) {
    std::vector<std::uint8_t> bytes = CommandBytes();
    PutF64(bytes, 24 + 8 * field, std::numeric_limits<double>::quiet_NaN());
    Reseal(bytes);
    DeviceCommand command;
    EXPECT_EQ(DecodeCommand(bytes, &command), DecodeResult::kNonFinite) << "field " << field;
  }
}

TEST(UdpProtocol, QuaternionNormIsChecked) {
  DeviceState state;
  // zero quaternion: no rotation can be read from it
  std::vector<std::uint8_t> bytes = StateBytes();
  for (std::size_t i = 0; i < 4; ++i) PutF64(bytes, 56 + 8 * i, 0.0);
  Reseal(bytes);
  EXPECT_EQ(DecodeState(bytes, &state), DecodeResult::kBadQuaternion);
  // within the tolerance: accepted and renormalised (|q| = 1 to 1e-15)
  bytes = StateBytes();
  const double scale = 1.0 + 0.5 * kQuaternionNormTolerance;
  for (std::size_t i = 0; i < 4; ++i) PutF64(bytes, 56 + 8 * i, 0.5 * scale);
  Reseal(bytes);
  ASSERT_EQ(DecodeState(bytes, &state), DecodeResult::kOk);
  EXPECT_NEAR(state.orientation.norm(), 1.0, 1e-15);
  // beyond it
  bytes = StateBytes();
  const double too_far = 1.0 + 2.0 * kQuaternionNormTolerance;
  for (std::size_t i = 0; i < 4; ++i) PutF64(bytes, 56 + 8 * i, 0.5 * too_far);
  Reseal(bytes);
  EXPECT_EQ(DecodeState(bytes, &state), DecodeResult::kBadQuaternion);
}

TEST(UdpProtocol, ResultNamesAreDistinct) {
  std::vector<std::string> names;
  for (std::size_t i = 0; i < kDecodeResultCount; ++i) {
    names.emplace_back(ToString(static_cast<DecodeResult>(i)));
    EXPECT_NE(names.back(), "unknown");
  }
  std::sort(names.begin(), names.end());
  EXPECT_EQ(std::unique(names.begin(), names.end()), names.end());
}

}  // namespace
}  // namespace rigidtouch::device
