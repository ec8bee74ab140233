#include "device/udp_protocol.h"

#include <gtest/gtest.h>
#include <sodium.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <type_traits>
#include <vector>

#include "io/record_fields.h"

namespace rigidtouch::device {
namespace {

// golden datagrams written independently with Python's struct.pack('<...') and
// hmac.new(key, header + payload, hashlib.sha256), key = bytes(range(32)), client nonce
// 0x1111111111111111, server nonce 0x2222222222222222: they pin the little-endian layout and the
// MAC of docs/device-protocol.md
constexpr const char* kGoldenStateHex =
    "52544348020001007c0000000000000011111111111111112222222222222222070000000000000008070605"
    "040302010000000000002940000000000000f03f00000000000000c0000000000000d03f000000000000e03f"
    "000000000000e0bf000000000000e03f000000000000e03f000000000000c03f000000000000b0bf00000000"
    "00000840000000000000f8bf00000000000004400000000000001040a50000007f8433503a83d488d5d5e9c2"
    "6eda7e39adb944639d59a1861d68639d2c514923";
constexpr const char* kGoldenCommandHex =
    "52544348020002003c000000000000001111111111111111222222222222222209000000000000002a000000"
    "00000000000000000000f83f00000000000002c000000000000008400000000000000000000000000000e03f"
    "000000000000e8bf030000000b05231e8e123892dfb3318fedbfc8854862b6127257dff82fd7cf40a390c4b9";
constexpr const char* kGoldenHelloHex =
    "525443480200030000000000000000001111111111111111000000000000000000000000000000009e77dc3d"
    "4fc144e29cf75469df24403d0898ad88bf890052528b409f67025bef";
constexpr const char* kGoldenHelloReplyHex =
    "525443480200040018000000000000001111111111111111222222222222222200000000000000006666666666"
    "660a400000000000408f40000000000000044058f98ba3d131aab17c2fead31edb4b4ae593e23de2a29ace685d"
    "e261d8609522";
// a version 1 state as version 1 senders put it on the wire (CRC-32, 16-byte header)
constexpr const char* kVersion1StateHex =
    "52544348010001007c00000068fe2a8208070605040302010000000000002940000000000000f03f0000000000"
    "0000c0000000000000d03f000000000000e03f000000000000e0bf000000000000e03f000000000000e03f0000"
    "00000000c03f000000000000b0bf0000000000000840000000000000f8bf00000000000004400000000000001040"
    "a5000000";

constexpr std::uint64_t kClientNonce = 0x1111111111111111ull;
constexpr std::uint64_t kProtocolServerNonce = 0x2222222222222222ull;

DeviceKey TestKey() {
  DeviceKey key;
  for (std::size_t i = 0; i < key.bytes.size(); ++i) key.bytes[i] = static_cast<std::uint8_t>(i);
  return key;
}

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

// recomputes the MAC after a test edits a datagram, so the receiver reaches the later checks
void Reseal(std::vector<std::uint8_t>& datagram, const DeviceKey& key = TestKey()) {
  const std::size_t covered = datagram.size() - kMacBytes;
  crypto_auth_hmacsha256(datagram.data() + covered, datagram.data(), covered, key.bytes.data());
}

void PutF64(std::vector<std::uint8_t>& datagram, std::size_t offset, double value) {
  const auto bits = std::bit_cast<std::uint64_t>(value);
  for (int i = 0; i < 8; ++i) datagram[offset + i] = static_cast<std::uint8_t>(bits >> (8 * i));
}

std::vector<std::uint8_t> StateBytes() {
  const StatePacket packet = EncodeState(
      GoldenState(), PacketHeader{PacketType::kState, kClientNonce, kProtocolServerNonce, 7},
      TestKey());
  return {packet.begin(), packet.end()};
}

std::vector<std::uint8_t> CommandBytes() {
  const CommandPacket packet = EncodeCommand(
      GoldenCommand(), PacketHeader{PacketType::kCommand, kClientNonce, kProtocolServerNonce, 9},
      TestKey());
  return {packet.begin(), packet.end()};
}

// what a client does with a datagram before session checks: framing, MAC, payload
enum class Verdict { kAccepted, kMalformed, kUnauthenticated };

Verdict ReceiveState(std::span<const std::uint8_t> bytes, DeviceState* state,
                     const DeviceKey& key = TestKey()) {
  PacketHeader header;
  if (CheckFraming(bytes, PacketType::kHelloReply, PacketType::kState, &header) !=
      DecodeResult::kOk) {
    return Verdict::kMalformed;
  }
  if (!VerifyMac(bytes, key)) return Verdict::kUnauthenticated;
  if (header.type != PacketType::kState) return Verdict::kMalformed;
  return DecodeStatePayload(bytes, state) == DecodeResult::kOk ? Verdict::kAccepted
                                                               : Verdict::kMalformed;
}

DecodeResult Framing(std::span<const std::uint8_t> bytes, PacketType a = PacketType::kHelloReply,
                     PacketType b = PacketType::kState) {
  PacketHeader header;
  return CheckFraming(bytes, a, b, &header);
}

TEST(UdpProtocol, EncodingsMatchGoldenBytes) {
  EXPECT_EQ(StateBytes(), FromHex(kGoldenStateHex));
  EXPECT_EQ(StateBytes().size(), kStatePacketBytes);
  EXPECT_EQ(CommandBytes(), FromHex(kGoldenCommandHex));
  EXPECT_EQ(CommandBytes().size(), kCommandPacketBytes);
  const HelloPacket hello = EncodeHello(kClientNonce, TestKey());
  EXPECT_EQ(std::vector<std::uint8_t>(hello.begin(), hello.end()), FromHex(kGoldenHelloHex));
  const HelloReplyPacket reply = EncodeHelloReply(DeviceLimits{"", 3.3, 1000.0, 2.5}, kClientNonce,
                                                  kProtocolServerNonce, TestKey());
  EXPECT_EQ(std::vector<std::uint8_t>(reply.begin(), reply.end()), FromHex(kGoldenHelloReplyHex));
}

// the bytes each wire field of a record's table takes: every payload byte is one field's, and
// the f64 values lie where the decoder checks them for finite numbers (docs/device-protocol.md:
// the state's 14 from offset 48, the command's 6 from offset 48)
template <class Record, class Table>
void ExpectTheTableTilesThePayload(Table visit_fields, std::size_t payload_bytes,
                                   std::size_t f64_begin, std::size_t f64_count) {
  std::vector<int> owners(kHeaderBytes + payload_bytes, 0);
  Record record;
  int field = 0;
  visit_fields(record, [&](const io::RecordField& f, const auto& value) {
    ++field;
    if (f.wire_offset < 0) return;
    using T = std::remove_cvref_t<decltype(value)>;
    const std::size_t size = std::is_same_v<T, std::uint64_t> || std::is_same_v<T, double> ? 8
                             : std::is_same_v<T, Vec3>                                     ? 24
                             : std::is_same_v<T, Quat>                                     ? 32
                                                                                           : 4;
    const auto begin = static_cast<std::size_t>(f.wire_offset);
    ASSERT_LE(begin + size, owners.size()) << f.name;
    if (std::is_floating_point_v<T> || std::is_same_v<T, Vec3> || std::is_same_v<T, Quat>) {
      EXPECT_GE(begin, f64_begin) << f.name;
      EXPECT_LE(begin + size, f64_begin + 8 * f64_count) << f.name;
    }
    for (std::size_t b = begin; b < begin + size; ++b) {
      // the flags of one word share it, each with its own bit
      const bool shared_flag_word = std::is_same_v<T, bool>;
      EXPECT_TRUE(owners[b] == 0 || shared_flag_word) << f.name << " byte " << b;
      owners[b] = field;
    }
  });
  for (std::size_t b = kHeaderBytes; b < owners.size(); ++b) {
    EXPECT_NE(owners[b], 0) << "payload byte " << b << " belongs to no field";
  }
}

TEST(UdpProtocol, TheStateAndCommandTablesTileTheirPayloads) {
  ExpectTheTableTilesThePayload<DeviceState>(
      [](DeviceState& s, auto&& visit) { io::VisitStateFields(s, visit); }, kStatePayloadBytes, 48,
      14);
  ExpectTheTableTilesThePayload<DeviceCommand>(
      [](DeviceCommand& c, auto&& visit) { io::VisitCommandFields(c, visit); },
      kCommandPayloadBytes, 48, 6);
}

TEST(UdpProtocol, HeaderFieldsAreRead) {
  PacketHeader header;
  ASSERT_EQ(
      CheckFraming(FromHex(kGoldenCommandHex), PacketType::kHello, PacketType::kCommand, &header),
      DecodeResult::kOk);
  EXPECT_EQ(header.type, PacketType::kCommand);
  EXPECT_EQ(header.client_nonce, kClientNonce);
  EXPECT_EQ(header.server_nonce, kProtocolServerNonce);
  EXPECT_EQ(header.counter, 9u);
  DeviceLimits limits;
  const std::vector<std::uint8_t> reply = FromHex(kGoldenHelloReplyHex);
  ASSERT_EQ(Framing(reply), DecodeResult::kOk);
  ASSERT_TRUE(VerifyMac(reply, TestKey()));
  ASSERT_EQ(DecodeHelloReplyPayload(reply, &limits), DecodeResult::kOk);
  EXPECT_EQ(limits.max_force_N, 3.3);
  EXPECT_EQ(limits.max_stiffness_N_per_m, 1000.0);
  EXPECT_EQ(limits.max_damping_Ns_per_m, 2.5);
}

TEST(UdpProtocol, StateRoundTripIsBitExact) {
  DeviceState decoded;
  decoded.valid = false;
  ASSERT_EQ(ReceiveState(FromHex(kGoldenStateHex), &decoded), Verdict::kAccepted);
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
  const std::vector<std::uint8_t> bytes = FromHex(kGoldenCommandHex);
  ASSERT_TRUE(VerifyMac(bytes, TestKey()));
  ASSERT_EQ(DecodeCommandPayload(bytes, &decoded), DecodeResult::kOk);
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
      const CommandPacket packet = EncodeCommand(command, PacketHeader{}, TestKey());
      EXPECT_EQ(packet[96], (safe ? 1 : 0) | (clipped ? 2 : 0));
      DeviceCommand decoded;
      ASSERT_EQ(DecodeCommandPayload(packet, &decoded), DecodeResult::kOk);
      EXPECT_EQ(decoded.safe_fallback, safe);
      EXPECT_EQ(decoded.clipped, clipped);
    }
  }
}

TEST(UdpProtocol, EveryTruncatedStateIsTooShort) {
  const std::vector<std::uint8_t> bytes = StateBytes();
  for (std::size_t length = 0; length < bytes.size(); ++length) {
    EXPECT_EQ(Framing(std::span(bytes.data(), length)), DecodeResult::kTooShort)
        << "length " << length;
  }
}

TEST(UdpProtocol, EveryTruncatedCommandIsTooShort) {
  const std::vector<std::uint8_t> bytes = CommandBytes();
  for (std::size_t length = 0; length < bytes.size(); ++length) {
    EXPECT_EQ(Framing(std::span(bytes.data(), length), PacketType::kHello, PacketType::kCommand),
              DecodeResult::kTooShort)
        << "length " << length;
  }
}

TEST(UdpProtocol, Version1DatagramsAreRefusedAsWrongVersion) {
  const std::vector<std::uint8_t> v1 = FromHex(kVersion1StateHex);
  EXPECT_EQ(Framing(v1), DecodeResult::kWrongVersion);
  DeviceState state;
  EXPECT_EQ(ReceiveState(v1, &state), Verdict::kMalformed);
  // whatever else a version 1 sender puts after the version field
  std::vector<std::uint8_t> v1_sized = StateBytes();
  v1_sized[4] = 1;
  Reseal(v1_sized);
  EXPECT_EQ(Framing(v1_sized), DecodeResult::kWrongVersion);
}

TEST(UdpProtocol, BadMagicWrongVersionWrongType) {
  std::vector<std::uint8_t> bytes = StateBytes();
  bytes[0] ^= 0x01;
  EXPECT_EQ(Framing(bytes), DecodeResult::kBadMagic);

  for (const std::uint8_t version : {0, 1, 3, 255}) {
    bytes = StateBytes();
    bytes[4] = version;
    Reseal(bytes);
    EXPECT_EQ(Framing(bytes), DecodeResult::kWrongVersion) << int{version};
  }

  // a command where a client expects states and replies, a state at a server, unknown types
  EXPECT_EQ(Framing(CommandBytes()), DecodeResult::kWrongType);
  EXPECT_EQ(Framing(StateBytes(), PacketType::kHello, PacketType::kCommand),
            DecodeResult::kWrongType);
  for (const std::uint8_t type : {0, 5, 7}) {
    bytes = StateBytes();
    bytes[6] = type;
    Reseal(bytes);
    EXPECT_EQ(Framing(bytes), DecodeResult::kWrongType) << int{type};
  }
}

TEST(UdpProtocol, OversizedPackets) {
  // one trailing byte beyond the MAC
  std::vector<std::uint8_t> bytes = StateBytes();
  bytes.push_back(0);
  EXPECT_EQ(Framing(bytes), DecodeResult::kOversized);
  // a header announcing a larger payload than the type has, with the bytes to match
  bytes = StateBytes();
  bytes[8] = static_cast<std::uint8_t>(kStatePayloadBytes + 8);
  bytes.resize(kStatePacketBytes + 8, 0);
  Reseal(bytes);
  EXPECT_EQ(Framing(bytes), DecodeResult::kOversized);
  // a huge datagram
  std::vector<std::uint8_t> huge = StateBytes();
  huge.resize(4000, 0);
  EXPECT_EQ(Framing(huge), DecodeResult::kOversized);
  std::vector<std::uint8_t> long_command = CommandBytes();
  long_command.push_back(0);
  EXPECT_EQ(Framing(long_command, PacketType::kHello, PacketType::kCommand),
            DecodeResult::kOversized);
}

TEST(UdpProtocol, ShorterAnnouncedPayloadIsTooShort) {
  std::vector<std::uint8_t> bytes = StateBytes();
  bytes[8] = static_cast<std::uint8_t>(kStatePayloadBytes - 4);
  bytes.resize(kStatePacketBytes - 4);
  Reseal(bytes);
  EXPECT_EQ(Framing(bytes), DecodeResult::kTooShort);
}

TEST(UdpProtocol, AnyFlippedBitAnywhereIsRejected) {
  for (const std::vector<std::uint8_t>& original : {StateBytes(), FromHex(kGoldenHelloReplyHex)}) {
    for (std::size_t byte = 0; byte < original.size(); ++byte) {
      for (int bit = 0; bit < 8; ++bit) {
        std::vector<std::uint8_t> bytes = original;
        bytes[byte] ^= static_cast<std::uint8_t>(1u << bit);
        PacketHeader header;
        const bool framed = CheckFraming(bytes, PacketType::kHelloReply, PacketType::kState,
                                         &header) == DecodeResult::kOk;
        // a flip that keeps the framing valid (reserved field, nonces, counter, payload, MAC,
        // even state <-> reply type bits) must fail the MAC
        ASSERT_FALSE(framed && VerifyMac(bytes, TestKey())) << "byte " << byte << " bit " << bit;
      }
    }
  }
}

TEST(UdpProtocol, CommandUnderAnotherKeyIsRejected) {
  DeviceKey other = TestKey();
  other.bytes[31] ^= 0x80;
  const CommandPacket forged = EncodeCommand(
      GoldenCommand(), PacketHeader{PacketType::kCommand, kClientNonce, kProtocolServerNonce, 9},
      other);
  EXPECT_EQ(Framing(forged, PacketType::kHello, PacketType::kCommand), DecodeResult::kOk);
  EXPECT_FALSE(VerifyMac(forged, TestKey()));
  EXPECT_TRUE(VerifyMac(forged, other));
  DeviceState state;
  EXPECT_EQ(ReceiveState(StateBytes(), &state, other), Verdict::kUnauthenticated);
  // an all-zero MAC (what an unkeyed sender might leave) is not a MAC either
  std::vector<std::uint8_t> zero_mac = CommandBytes();
  std::fill(zero_mac.end() - kMacBytes, zero_mac.end(), 0);
  EXPECT_FALSE(VerifyMac(zero_mac, TestKey()));
}

TEST(UdpProtocol, NonFiniteStateFieldsAreRejected) {
  // 14 f64 fields from offset 48 (time, position, quaternion, velocities)
  for (std::size_t field = 0; field < 14; ++field) {
    for (const double bad :
         {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity(),
          -std::numeric_limits<double>::infinity()}) {
      std::vector<std::uint8_t> bytes = StateBytes();
      PutF64(bytes, 48 + 8 * field, bad);
      Reseal(bytes);
      DeviceState state;
      state.sequence = 77;
      ASSERT_TRUE(VerifyMac(bytes, TestKey()));
      EXPECT_EQ(DecodeStatePayload(bytes, &state), DecodeResult::kNonFinite) << "field " << field;
      EXPECT_EQ(state.sequence, 77u) << "a failed decode leaves the output untouched";
    }
  }
}

TEST(UdpProtocol, NonFiniteCommandFieldsAreRejected) {
  for (std::size_t field = 0; field < 6; ++field) {
    std::vector<std::uint8_t> bytes = CommandBytes();
    PutF64(bytes, 48 + 8 * field, std::numeric_limits<double>::quiet_NaN());
    Reseal(bytes);
    DeviceCommand command;
    EXPECT_EQ(DecodeCommandPayload(bytes, &command), DecodeResult::kNonFinite) << "field " << field;
  }
}

TEST(UdpProtocol, AnnouncedLimitsMustBeFiniteAndNonNegative) {
  for (std::size_t field = 0; field < 3; ++field) {
    std::vector<std::uint8_t> bytes = FromHex(kGoldenHelloReplyHex);
    PutF64(bytes, 40 + 8 * field, -1.0);
    DeviceLimits limits;
    EXPECT_EQ(DecodeHelloReplyPayload(bytes, &limits), DecodeResult::kBadLimits);
    PutF64(bytes, 40 + 8 * field, std::numeric_limits<double>::infinity());
    EXPECT_EQ(DecodeHelloReplyPayload(bytes, &limits), DecodeResult::kNonFinite);
  }
}

TEST(UdpProtocol, QuaternionNormIsChecked) {
  DeviceState state;
  // zero quaternion: no rotation can be read from it
  std::vector<std::uint8_t> bytes = StateBytes();
  for (std::size_t i = 0; i < 4; ++i) PutF64(bytes, 80 + 8 * i, 0.0);
  EXPECT_EQ(DecodeStatePayload(bytes, &state), DecodeResult::kBadQuaternion);
  // within the tolerance: accepted and renormalised (|q| = 1 to 1e-15)
  bytes = StateBytes();
  const double scale = 1.0 + 0.5 * kQuaternionNormTolerance;
  for (std::size_t i = 0; i < 4; ++i) PutF64(bytes, 80 + 8 * i, 0.5 * scale);
  ASSERT_EQ(DecodeStatePayload(bytes, &state), DecodeResult::kOk);
  EXPECT_NEAR(state.orientation.norm(), 1.0, 1e-15);
  // beyond it
  bytes = StateBytes();
  const double too_far = 1.0 + 2.0 * kQuaternionNormTolerance;
  for (std::size_t i = 0; i < 4; ++i) PutF64(bytes, 80 + 8 * i, 0.5 * too_far);
  EXPECT_EQ(DecodeStatePayload(bytes, &state), DecodeResult::kBadQuaternion);
}

TEST(UdpProtocol, NoncesAreRandomAndNeverZero) {
  InitSodium();
  const std::uint64_t a = RandomNonce();
  const std::uint64_t b = RandomNonce();
  EXPECT_NE(a, 0u);
  EXPECT_NE(a, b);  // 2^-64 chance of a false failure
}

TEST(UdpProtocol, StricterLimitTreatsZeroAsNone) {
  EXPECT_EQ(StricterLimit(0.0, 3.3), 3.3);
  EXPECT_EQ(StricterLimit(8.5, 0.0), 8.5);
  EXPECT_EQ(StricterLimit(8.5, 3.3), 3.3);
  EXPECT_EQ(StricterLimit(3.3, 8.5), 3.3);
  EXPECT_EQ(StricterLimit(0.0, 0.0), 0.0);
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
