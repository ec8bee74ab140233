// The rigidtouch device protocol over UDP, version 2: fixed-size little-endian packets (hello,
// hello-reply, state, command), each closed by an HMAC-SHA-256 under a pre-shared key over
// everything before it. docs/device-protocol.md is the reference; the offsets below and the state's
// and command's in io/record_fields.h must match its tables.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>

#include "io/record_fields.h"
#include "rigidtouch/bridge.h"
#include "rigidtouch/types.h"

namespace rigidtouch::device {

/// Magic number at offset 0; on the wire (little-endian) its bytes read "RTCH".
inline constexpr std::uint32_t kProtocolMagic = 0x48435452u;
/// Protocol version at offset 4. Any change of layout or meaning increments it.
inline constexpr std::uint16_t kProtocolVersion = 2;
/// Header bytes before every payload: magic, version, type, payload size, reserved, the two
/// session nonces and the counter.
inline constexpr std::size_t kHeaderBytes = 40;
/// Bytes of the MAC after the payload (HMAC-SHA-256, untruncated).
inline constexpr std::size_t kMacBytes = 32;
/// Payload bytes of a state packet.
inline constexpr std::size_t kStatePayloadBytes = 124;
/// Payload bytes of a command packet.
inline constexpr std::size_t kCommandPayloadBytes = 60;
/// Payload bytes of a hello (everything it says is in the header).
inline constexpr std::size_t kHelloPayloadBytes = 0;
/// Payload bytes of a hello-reply: the device's three limits.
inline constexpr std::size_t kHelloReplyPayloadBytes = 24;
/// Total bytes of a state datagram.
inline constexpr std::size_t kStatePacketBytes = kHeaderBytes + kStatePayloadBytes + kMacBytes;
/// Total bytes of a command datagram.
inline constexpr std::size_t kCommandPacketBytes = kHeaderBytes + kCommandPayloadBytes + kMacBytes;
/// Total bytes of a hello datagram.
inline constexpr std::size_t kHelloPacketBytes = kHeaderBytes + kHelloPayloadBytes + kMacBytes;
/// Total bytes of a hello-reply datagram.
inline constexpr std::size_t kHelloReplyPacketBytes =
    kHeaderBytes + kHelloReplyPayloadBytes + kMacBytes;
/// Largest datagram a receiver reads in full; anything longer is oversized by definition.
inline constexpr std::size_t kMaxDatagramBytes = 512;

/// Command flag bit 0: the renderer detected an error and the wrench is zero (safe fallback).
inline constexpr std::uint32_t kCommandFlagSafeFallback = io::kWireFlagSafeFallback;
/// Command flag bit 1: the renderer clipped the force to the device limit.
inline constexpr std::uint32_t kCommandFlagClipped = io::kWireFlagClipped;

/// Packet type at offset 6.
enum class PacketType : std::uint16_t {
  kState = 1,       // device -> renderer, in a session
  kCommand = 2,     // renderer -> device, in a session
  kHello = 3,       // renderer -> device: asks for a session
  kHelloReply = 4,  // device -> renderer: grants it and announces the device's limits
};

// DecodeResult and kDecodeResultCount are in rigidtouch/bridge.h: the server's counters use them.

/// Largest accepted deviation of the received quaternion's norm from 1 (it is renormalised).
inline constexpr double kQuaternionNormTolerance = 1e-3;

/// Short stable name of a decode result (e.g. "wrong_version"), used as a JSON key.
std::string_view ToString(DecodeResult result);

/// The session fields of the header. A hello carries the client's fresh nonce and server_nonce
/// 0; every later packet of the session carries both nonces. `counter` is strictly increasing
/// per direction within a session (hellos and hello-replies send 0).
struct PacketHeader {
  PacketType type = PacketType::kState;
  std::uint64_t client_nonce = 0;
  std::uint64_t server_nonce = 0;
  std::uint64_t counter = 0;
};

/// A state datagram ready to send.
using StatePacket = std::array<std::uint8_t, kStatePacketBytes>;
/// A command datagram ready to send.
using CommandPacket = std::array<std::uint8_t, kCommandPacketBytes>;
/// A hello datagram ready to send.
using HelloPacket = std::array<std::uint8_t, kHelloPacketBytes>;
/// A hello-reply datagram ready to send.
using HelloReplyPacket = std::array<std::uint8_t, kHelloReplyPacketBytes>;

/// Encodes a device state (`valid` is not sent: a server sends only valid states). `header.type`
/// is ignored.
StatePacket EncodeState(const DeviceState& state, const PacketHeader& header, const DeviceKey& key);

/// Encodes a command: sequence, force, torque, and the safe-fallback and clipped flags. The
/// penalty and impulsive parts are not sent.
CommandPacket EncodeCommand(const DeviceCommand& command, const PacketHeader& header,
                            const DeviceKey& key);

/// Encodes a hello with the client's nonce.
HelloPacket EncodeHello(std::uint64_t client_nonce, const DeviceKey& key);

/// Encodes a hello-reply granting the session (client_nonce, server_nonce) and announcing the
/// device's force, stiffness and damping limits (its name and torque limit are not sent).
HelloReplyPacket EncodeHelloReply(const DeviceLimits& limits, std::uint64_t client_nonce,
                                  std::uint64_t server_nonce, const DeviceKey& key);

/// Framing checks 1 to 6 of docs/device-protocol.md ("Receiving") for a receiver that expects
/// the types `first` or `second`. On kOk writes `*header`. Does not check the MAC.
DecodeResult CheckFraming(std::span<const std::uint8_t> datagram, PacketType first,
                          PacketType second, PacketHeader* header);

/// Returns true when the last kMacBytes of a framed datagram are the HMAC-SHA-256 under `key` of
/// every byte before them. Constant time in the MAC's value. `datagram` must hold at least
/// kHeaderBytes + kMacBytes bytes (CheckFraming guarantees it).
bool VerifyMac(std::span<const std::uint8_t> datagram, const DeviceKey& key);

/// Decodes the payload of a framed, authenticated state. On kOk writes `*state` (with `valid =
/// true` and the orientation renormalised); otherwise leaves it untouched.
DecodeResult DecodeStatePayload(std::span<const std::uint8_t> datagram, DeviceState* state);

/// Decodes the payload of a framed, authenticated command. On kOk writes `*command` (penalty
/// and impulsive parts zero); otherwise leaves it untouched.
DecodeResult DecodeCommandPayload(std::span<const std::uint8_t> datagram, DeviceCommand* command);

/// Decodes the payload of a framed, authenticated hello-reply: finite limits >= 0 (name empty,
/// torque limit 0).
DecodeResult DecodeHelloReplyPayload(std::span<const std::uint8_t> datagram, DeviceLimits* limits);

/// Initialises libsodium (idempotent, thread-safe). Throws Error if it cannot start.
void InitSodium();

/// Returns a uniformly random 64-bit nonce that is never 0 (0 means "none" on the wire). Never
/// allocates or throws (getrandom).
std::uint64_t RandomNonce() noexcept;

/// Returns the stricter of two limits where 0 means "none": the smaller positive one.
double StricterLimit(double a, double b);

}  // namespace rigidtouch::device
