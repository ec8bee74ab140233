#include "device/udp_protocol.h"

#include <bit>
#include <boost/crc.hpp>
#include <cmath>
#include <limits>

namespace rigidtouch::device {
namespace {

// the wire format is IEEE-754 binary64; bit_cast below relies on the host using it too
static_assert(std::numeric_limits<double>::is_iec559);

// explicit little-endian byte order, independent of the host's
void PutU16(std::uint8_t* out, std::uint16_t value) {
  out[0] = static_cast<std::uint8_t>(value);
  out[1] = static_cast<std::uint8_t>(value >> 8);
}

void PutU32(std::uint8_t* out, std::uint32_t value) {
  for (int i = 0; i < 4; ++i) out[i] = static_cast<std::uint8_t>(value >> (8 * i));
}

void PutU64(std::uint8_t* out, std::uint64_t value) {
  for (int i = 0; i < 8; ++i) out[i] = static_cast<std::uint8_t>(value >> (8 * i));
}

void PutF64(std::uint8_t* out, double value) {
  PutU64(out, std::bit_cast<std::uint64_t>(value));
}

void PutVec3(std::uint8_t* out, const Vec3& value) {
  for (Eigen::Index i = 0; i < 3; ++i) PutF64(out + 8 * i, value[i]);
}

std::uint16_t GetU16(const std::uint8_t* in) {
  return static_cast<std::uint16_t>(in[0] | (static_cast<unsigned>(in[1]) << 8));
}

std::uint32_t GetU32(const std::uint8_t* in) {
  std::uint32_t value = 0;
  for (int i = 0; i < 4; ++i) value |= static_cast<std::uint32_t>(in[i]) << (8 * i);
  return value;
}

std::uint64_t GetU64(const std::uint8_t* in) {
  std::uint64_t value = 0;
  for (int i = 0; i < 8; ++i) value |= static_cast<std::uint64_t>(in[i]) << (8 * i);
  return value;
}

double GetF64(const std::uint8_t* in) {
  return std::bit_cast<double>(GetU64(in));
}

Vec3 GetVec3(const std::uint8_t* in) {
  return Vec3(GetF64(in), GetF64(in + 8), GetF64(in + 16));
}

// header offsets (docs/device-protocol.md, "Header")
constexpr std::size_t kMagicOffset = 0;
constexpr std::size_t kVersionOffset = 4;
constexpr std::size_t kTypeOffset = 6;
constexpr std::size_t kPayloadSizeOffset = 8;
constexpr std::size_t kChecksumOffset = 12;

// state payload offsets from the start of the datagram
constexpr std::size_t kStateSequence = 16;
constexpr std::size_t kStateTime = 24;
constexpr std::size_t kStatePosition = 32;
constexpr std::size_t kStateOrientation = 56;
constexpr std::size_t kStateVelocity = 88;
constexpr std::size_t kStateAngularVelocity = 112;
constexpr std::size_t kStateButtons = 136;
static_assert(kStateButtons + 4 == kStatePacketBytes);

// command payload offsets from the start of the datagram
constexpr std::size_t kCommandSequence = 16;
constexpr std::size_t kCommandForce = 24;
constexpr std::size_t kCommandTorque = 48;
constexpr std::size_t kCommandFlags = 72;
static_assert(kCommandFlags + 4 == kCommandPacketBytes);

void PutHeader(std::uint8_t* out, PacketType type, std::size_t payload_bytes) {
  PutU32(out + kMagicOffset, kProtocolMagic);
  PutU16(out + kVersionOffset, kProtocolVersion);
  PutU16(out + kTypeOffset, static_cast<std::uint16_t>(type));
  PutU32(out + kPayloadSizeOffset, static_cast<std::uint32_t>(payload_bytes));
  PutU32(out + kChecksumOffset, 0);
}

void Seal(std::span<std::uint8_t> datagram) {
  PutU32(datagram.data() + kChecksumOffset, PacketChecksum(datagram));
}

// checks shared by both packet types, in the order the protocol document lists them
DecodeResult CheckFraming(std::span<const std::uint8_t> datagram, PacketType expected_type,
                          std::size_t expected_payload_bytes) {
  if (datagram.size() < kHeaderBytes) return DecodeResult::kTooShort;
  const std::uint8_t* bytes = datagram.data();
  if (GetU32(bytes + kMagicOffset) != kProtocolMagic) return DecodeResult::kBadMagic;
  if (GetU16(bytes + kVersionOffset) != kProtocolVersion) return DecodeResult::kWrongVersion;
  if (GetU16(bytes + kTypeOffset) != static_cast<std::uint16_t>(expected_type)) {
    return DecodeResult::kWrongType;
  }
  const std::size_t declared = GetU32(bytes + kPayloadSizeOffset);
  if (declared > expected_payload_bytes) return DecodeResult::kOversized;
  if (declared < expected_payload_bytes) return DecodeResult::kTooShort;
  if (datagram.size() < kHeaderBytes + declared) return DecodeResult::kTooShort;
  if (datagram.size() > kHeaderBytes + declared) return DecodeResult::kOversized;
  if (GetU32(bytes + kChecksumOffset) != PacketChecksum(datagram)) {
    return DecodeResult::kBadChecksum;
  }
  return DecodeResult::kOk;
}

bool AllFinite(const std::uint8_t* first_f64, std::size_t count) {
  for (std::size_t i = 0; i < count; ++i) {
    if (!std::isfinite(GetF64(first_f64 + 8 * i))) return false;
  }
  return true;
}

}  // namespace

std::string_view ToString(DecodeResult result) {
  switch (result) {
    case DecodeResult::kOk:
      return "ok";
    case DecodeResult::kTooShort:
      return "too_short";
    case DecodeResult::kBadMagic:
      return "bad_magic";
    case DecodeResult::kWrongVersion:
      return "wrong_version";
    case DecodeResult::kWrongType:
      return "wrong_type";
    case DecodeResult::kOversized:
      return "oversized";
    case DecodeResult::kBadChecksum:
      return "bad_checksum";
    case DecodeResult::kNonFinite:
      return "non_finite";
    case DecodeResult::kBadQuaternion:
      return "bad_quaternion";
  }
  return "unknown";
}

std::uint32_t PacketChecksum(std::span<const std::uint8_t> datagram) {
  boost::crc_32_type crc;
  crc.process_bytes(datagram.data(), kChecksumOffset);
  crc.process_bytes(datagram.data() + kHeaderBytes, datagram.size() - kHeaderBytes);
  return crc.checksum();
}

StatePacket EncodeState(const DeviceState& state) {
  StatePacket packet{};
  std::uint8_t* out = packet.data();
  PutHeader(out, PacketType::kState, kStatePayloadBytes);
  PutU64(out + kStateSequence, state.sequence);
  PutF64(out + kStateTime, state.time_s);
  PutVec3(out + kStatePosition, state.position_m);
  PutF64(out + kStateOrientation, state.orientation.w());
  PutF64(out + kStateOrientation + 8, state.orientation.x());
  PutF64(out + kStateOrientation + 16, state.orientation.y());
  PutF64(out + kStateOrientation + 24, state.orientation.z());
  PutVec3(out + kStateVelocity, state.velocity_mps);
  PutVec3(out + kStateAngularVelocity, state.angular_velocity_radps);
  PutU32(out + kStateButtons, state.buttons);
  Seal(packet);
  return packet;
}

CommandPacket EncodeCommand(const DeviceCommand& command) {
  CommandPacket packet{};
  std::uint8_t* out = packet.data();
  PutHeader(out, PacketType::kCommand, kCommandPayloadBytes);
  PutU64(out + kCommandSequence, command.sequence);
  PutVec3(out + kCommandForce, command.force_N);
  PutVec3(out + kCommandTorque, command.torque_Nm);
  std::uint32_t flags = 0;
  if (command.safe_fallback) flags |= kCommandFlagSafeFallback;
  if (command.clipped) flags |= kCommandFlagClipped;
  PutU32(out + kCommandFlags, flags);
  Seal(packet);
  return packet;
}

DecodeResult DecodeState(std::span<const std::uint8_t> datagram, DeviceState* state) {
  const DecodeResult framing = CheckFraming(datagram, PacketType::kState, kStatePayloadBytes);
  if (framing != DecodeResult::kOk) return framing;
  const std::uint8_t* in = datagram.data();
  // time, position, quaternion, velocity, angular velocity: 14 contiguous f64
  if (!AllFinite(in + kStateTime, 14)) return DecodeResult::kNonFinite;
  const Quat orientation(GetF64(in + kStateOrientation), GetF64(in + kStateOrientation + 8),
                         GetF64(in + kStateOrientation + 16), GetF64(in + kStateOrientation + 24));
  if (std::abs(orientation.norm() - 1.0) > kQuaternionNormTolerance) {
    return DecodeResult::kBadQuaternion;
  }
  state->sequence = GetU64(in + kStateSequence);
  state->time_s = GetF64(in + kStateTime);
  state->position_m = GetVec3(in + kStatePosition);
  state->orientation = orientation.normalized();
  state->velocity_mps = GetVec3(in + kStateVelocity);
  state->angular_velocity_radps = GetVec3(in + kStateAngularVelocity);
  state->buttons = GetU32(in + kStateButtons);
  state->valid = true;
  return DecodeResult::kOk;
}

DecodeResult DecodeCommand(std::span<const std::uint8_t> datagram, DeviceCommand* command) {
  const DecodeResult framing = CheckFraming(datagram, PacketType::kCommand, kCommandPayloadBytes);
  if (framing != DecodeResult::kOk) return framing;
  const std::uint8_t* in = datagram.data();
  // force and torque: 6 contiguous f64
  if (!AllFinite(in + kCommandForce, 6)) return DecodeResult::kNonFinite;
  const std::uint32_t flags = GetU32(in + kCommandFlags);
  *command = DeviceCommand{};
  command->sequence = GetU64(in + kCommandSequence);
  command->force_N = GetVec3(in + kCommandForce);
  command->torque_Nm = GetVec3(in + kCommandTorque);
  // reserved flag bits are ignored (they must be sent as zero)
  command->safe_fallback = (flags & kCommandFlagSafeFallback) != 0;
  command->clipped = (flags & kCommandFlagClipped) != 0;
  return DecodeResult::kOk;
}

}  // namespace rigidtouch::device
