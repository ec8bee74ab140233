#include "device/udp_protocol.h"

#include <sodium.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <string_view>
#include <type_traits>

#include "io/record_fields.h"

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
constexpr std::size_t kReservedOffset = 12;
constexpr std::size_t kClientNonceOffset = 16;
constexpr std::size_t kServerNonceOffset = 24;
constexpr std::size_t kCounterOffset = 32;
static_assert(kCounterOffset + 8 == kHeaderBytes);

// the state's and the command's fields on the wire: the offsets in io/record_fields.h, from the
// start of the datagram (docs/device-protocol.md, "State" and "Command"). The checks below read
// these before decoding; tests/device/udp_protocol_test.cc holds the table to them
constexpr std::size_t kStateTime = 48;         // the first of 14 contiguous f64
constexpr std::size_t kStateOrientation = 80;  // checked for a unit quaternion before decoding
constexpr std::size_t kCommandForce = 48;      // the first of 6 contiguous f64
constexpr std::size_t kCommandFlags = 96;

static_assert(kCommandFlags + 4 + kMacBytes == kCommandPacketBytes);

// one field at its offset (fields without one are not sent); a flag sets its bit of the u32
struct PutWire {
  std::uint8_t* out;
  template <class T>
  void operator()(const io::RecordField& f, const T& v) const {
    if (f.wire_offset < 0) return;
    std::uint8_t* at = out + f.wire_offset;
    if constexpr (std::is_same_v<T, bool>) {
      if (v) PutU32(at, GetU32(at) | f.wire_bit);
    } else if constexpr (std::is_same_v<T, std::uint64_t>) {
      PutU64(at, v);
    } else if constexpr (std::is_same_v<T, std::uint32_t>) {
      PutU32(at, v);
    } else if constexpr (std::is_same_v<T, double>) {
      PutF64(at, v);
    } else if constexpr (std::is_same_v<T, Vec3>) {
      PutVec3(at, v);
    } else {
      static_assert(std::is_same_v<T, Quat>);
      PutF64(at, v.w());
      PutF64(at + 8, v.x());
      PutF64(at + 16, v.y());
      PutF64(at + 24, v.z());
    }
  }
};

// one field from its offset; fields without one are left as they are. A flag is its bit; the
// flags word's other bits are reserved and ignored (they must be sent as zero)
struct GetWire {
  const std::uint8_t* in;
  template <class T>
  void operator()(const io::RecordField& f, T& v) const {
    if (f.wire_offset < 0) return;
    const std::uint8_t* at = in + f.wire_offset;
    if constexpr (std::is_same_v<T, bool>) {
      v = (GetU32(at) & f.wire_bit) != 0;
    } else if constexpr (std::is_same_v<T, std::uint64_t>) {
      v = GetU64(at);
    } else if constexpr (std::is_same_v<T, std::uint32_t>) {
      v = GetU32(at);
    } else if constexpr (std::is_same_v<T, double>) {
      v = GetF64(at);
    } else if constexpr (std::is_same_v<T, Vec3>) {
      v = GetVec3(at);
    } else {
      static_assert(std::is_same_v<T, Quat>);
      v = Quat(GetF64(at), GetF64(at + 8), GetF64(at + 16), GetF64(at + 24));
    }
  }
};

// hello-reply payload offsets
constexpr std::size_t kReplyMaxForce = 40;
constexpr std::size_t kReplyMaxStiffness = 48;
constexpr std::size_t kReplyMaxDamping = 56;
static_assert(kReplyMaxDamping + 8 + kMacBytes == kHelloReplyPacketBytes);

static_assert(crypto_auth_hmacsha256_BYTES == kMacBytes);
static_assert(crypto_auth_hmacsha256_KEYBYTES == kDeviceKeyBytes);

void PutHeader(std::uint8_t* out, PacketType type, std::size_t payload_bytes,
               const PacketHeader& header) {
  PutU32(out + kMagicOffset, kProtocolMagic);
  PutU16(out + kVersionOffset, kProtocolVersion);
  PutU16(out + kTypeOffset, static_cast<std::uint16_t>(type));
  PutU32(out + kPayloadSizeOffset, static_cast<std::uint32_t>(payload_bytes));
  PutU32(out + kReservedOffset, 0);
  PutU64(out + kClientNonceOffset, header.client_nonce);
  PutU64(out + kServerNonceOffset, header.server_nonce);
  PutU64(out + kCounterOffset, header.counter);
}

// writes the MAC over every byte before it into the last kMacBytes
void Seal(std::span<std::uint8_t> datagram, const DeviceKey& key) {
  const std::size_t covered = datagram.size() - kMacBytes;
  crypto_auth_hmacsha256(datagram.data() + covered, datagram.data(), covered, key.bytes.data());
}

std::size_t PayloadBytes(PacketType type) {
  switch (type) {
    case PacketType::kState:
      return kStatePayloadBytes;
    case PacketType::kCommand:
      return kCommandPayloadBytes;
    case PacketType::kHello:
      return kHelloPayloadBytes;
    case PacketType::kHelloReply:
      return kHelloReplyPayloadBytes;
  }
  return 0;
}

bool AllFiniteDoubles(const std::uint8_t* first_f64, std::size_t count) {
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
    case DecodeResult::kNonFinite:
      return "non_finite";
    case DecodeResult::kBadQuaternion:
      return "bad_quaternion";
    case DecodeResult::kBadLimits:
      return "bad_limits";
  }
  return "unknown";
}

// checks 1 to 6 of docs/device-protocol.md, in its order; the MAC (7) is checked by the caller
DecodeResult CheckFraming(std::span<const std::uint8_t> datagram, PacketType first,
                          PacketType second, PacketHeader* header) {
  if (datagram.size() < kHeaderBytes) return DecodeResult::kTooShort;
  const std::uint8_t* bytes = datagram.data();
  if (GetU32(bytes + kMagicOffset) != kProtocolMagic) return DecodeResult::kBadMagic;
  if (GetU16(bytes + kVersionOffset) != kProtocolVersion) return DecodeResult::kWrongVersion;
  const std::uint16_t type = GetU16(bytes + kTypeOffset);
  if (type != static_cast<std::uint16_t>(first) && type != static_cast<std::uint16_t>(second)) {
    return DecodeResult::kWrongType;
  }
  const std::size_t expected = PayloadBytes(static_cast<PacketType>(type));
  const std::size_t declared = GetU32(bytes + kPayloadSizeOffset);
  if (declared > expected) return DecodeResult::kOversized;
  if (declared < expected) return DecodeResult::kTooShort;
  if (datagram.size() < kHeaderBytes + declared + kMacBytes) return DecodeResult::kTooShort;
  if (datagram.size() > kHeaderBytes + declared + kMacBytes) return DecodeResult::kOversized;
  header->type = static_cast<PacketType>(type);
  header->client_nonce = GetU64(bytes + kClientNonceOffset);
  header->server_nonce = GetU64(bytes + kServerNonceOffset);
  header->counter = GetU64(bytes + kCounterOffset);
  return DecodeResult::kOk;
}

bool VerifyMac(std::span<const std::uint8_t> datagram, const DeviceKey& key) {
  if (datagram.size() < kHeaderBytes + kMacBytes) return false;
  const std::size_t covered = datagram.size() - kMacBytes;
  // libsodium compares in constant time, so timing reveals nothing about the right MAC
  return crypto_auth_hmacsha256_verify(datagram.data() + covered, datagram.data(), covered,
                                       key.bytes.data()) == 0;
}

StatePacket EncodeState(const DeviceState& state, const PacketHeader& header,
                        const DeviceKey& key) {
  StatePacket packet{};
  std::uint8_t* out = packet.data();
  PutHeader(out, PacketType::kState, kStatePayloadBytes, header);
  io::VisitStateFields(state, PutWire{out});
  Seal(packet, key);
  return packet;
}

CommandPacket EncodeCommand(const DeviceCommand& command, const PacketHeader& header,
                            const DeviceKey& key) {
  CommandPacket packet{};
  std::uint8_t* out = packet.data();
  PutHeader(out, PacketType::kCommand, kCommandPayloadBytes, header);
  io::VisitCommandFields(command, PutWire{out});
  Seal(packet, key);
  return packet;
}

HelloPacket EncodeHello(std::uint64_t client_nonce, const DeviceKey& key) {
  HelloPacket packet{};
  PutHeader(packet.data(), PacketType::kHello, kHelloPayloadBytes,
            PacketHeader{PacketType::kHello, client_nonce, 0, 0});
  Seal(packet, key);
  return packet;
}

HelloReplyPacket EncodeHelloReply(const DeviceLimits& limits, std::uint64_t client_nonce,
                                  std::uint64_t server_nonce, const DeviceKey& key) {
  HelloReplyPacket packet{};
  std::uint8_t* out = packet.data();
  PutHeader(out, PacketType::kHelloReply, kHelloReplyPayloadBytes,
            PacketHeader{PacketType::kHelloReply, client_nonce, server_nonce, 0});
  PutF64(out + kReplyMaxForce, limits.max_force_N);
  PutF64(out + kReplyMaxStiffness, limits.max_stiffness_N_per_m);
  PutF64(out + kReplyMaxDamping, limits.max_damping_Ns_per_m);
  Seal(packet, key);
  return packet;
}

DecodeResult DecodeStatePayload(std::span<const std::uint8_t> datagram, DeviceState* state) {
  if (datagram.size() != kStatePacketBytes) return DecodeResult::kTooShort;
  const std::uint8_t* in = datagram.data();
  // time, position, quaternion, velocity, angular velocity: 14 contiguous f64
  if (!AllFiniteDoubles(in + kStateTime, 14)) return DecodeResult::kNonFinite;
  const Quat orientation(GetF64(in + kStateOrientation), GetF64(in + kStateOrientation + 8),
                         GetF64(in + kStateOrientation + 16), GetF64(in + kStateOrientation + 24));
  if (std::abs(orientation.norm() - 1.0) > kQuaternionNormTolerance) {
    return DecodeResult::kBadQuaternion;
  }
  io::VisitStateFields(*state, GetWire{in});
  state->orientation.normalize();
  state->valid = true;
  return DecodeResult::kOk;
}

DecodeResult DecodeCommandPayload(std::span<const std::uint8_t> datagram, DeviceCommand* command) {
  if (datagram.size() != kCommandPacketBytes) return DecodeResult::kTooShort;
  const std::uint8_t* in = datagram.data();
  // force and torque: 6 contiguous f64
  if (!AllFiniteDoubles(in + kCommandForce, 6)) return DecodeResult::kNonFinite;
  *command = DeviceCommand{};
  io::VisitCommandFields(*command, GetWire{in});
  return DecodeResult::kOk;
}

DecodeResult DecodeHelloReplyPayload(std::span<const std::uint8_t> datagram, DeviceLimits* limits) {
  if (datagram.size() != kHelloReplyPacketBytes) return DecodeResult::kTooShort;
  const std::uint8_t* in = datagram.data();
  if (!AllFiniteDoubles(in + kReplyMaxForce, 3)) return DecodeResult::kNonFinite;
  DeviceLimits decoded;
  decoded.max_force_N = GetF64(in + kReplyMaxForce);
  decoded.max_stiffness_N_per_m = GetF64(in + kReplyMaxStiffness);
  decoded.max_damping_Ns_per_m = GetF64(in + kReplyMaxDamping);
  if (decoded.max_force_N < 0.0 || decoded.max_stiffness_N_per_m < 0.0 ||
      decoded.max_damping_Ns_per_m < 0.0) {
    return DecodeResult::kBadLimits;
  }
  *limits = decoded;
  return DecodeResult::kOk;
}

void InitSodium() {
  if (sodium_init() < 0) throw Error("libsodium could not be initialised");
}

std::uint64_t RandomNonce() noexcept {
  std::uint64_t nonce = 0;
  while (nonce == 0) randombytes_buf(&nonce, sizeof nonce);
  return nonce;
}

double StricterLimit(double a, double b) {
  if (a <= 0.0) return b;
  if (b <= 0.0) return a;
  return std::min(a, b);
}

}  // namespace rigidtouch::device
