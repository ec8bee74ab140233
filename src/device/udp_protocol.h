// The rigidtouch device protocol over UDP, version 1: fixed-size little-endian packets for the
// device state (device -> renderer) and the command (renderer -> device). docs/device-protocol.md
// is the reference; the offsets below must match its tables.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>

#include "rigidtouch/bridge.h"
#include "rigidtouch/types.h"

namespace rigidtouch::device {

/// Magic number at offset 0; on the wire (little-endian) its bytes read "RTCH".
inline constexpr std::uint32_t kProtocolMagic = 0x48435452u;
/// Protocol version at offset 4. Any change of layout or meaning increments it.
inline constexpr std::uint16_t kProtocolVersion = 1;
/// Header bytes before every payload: magic, version, type, payload size, CRC-32.
inline constexpr std::size_t kHeaderBytes = 16;
/// Payload bytes of a state packet.
inline constexpr std::size_t kStatePayloadBytes = 124;
/// Payload bytes of a command packet.
inline constexpr std::size_t kCommandPayloadBytes = 60;
/// Total bytes of a state datagram.
inline constexpr std::size_t kStatePacketBytes = kHeaderBytes + kStatePayloadBytes;
/// Total bytes of a command datagram.
inline constexpr std::size_t kCommandPacketBytes = kHeaderBytes + kCommandPayloadBytes;
/// Largest datagram a receiver reads in full; anything longer is oversized by definition.
inline constexpr std::size_t kMaxDatagramBytes = 512;

/// Command flag bit 0: the renderer detected an error and the wrench is zero (safe fallback).
inline constexpr std::uint32_t kCommandFlagSafeFallback = 1u << 0;
/// Command flag bit 1: the renderer clipped the force to the device limit.
inline constexpr std::uint32_t kCommandFlagClipped = 1u << 1;

/// Packet type at offset 6.
enum class PacketType : std::uint16_t {
  kState = 1,    // device -> renderer
  kCommand = 2,  // renderer -> device
};

// DecodeResult and kDecodeResultCount are in rigidtouch/bridge.h: the server's counters use them.

/// Largest accepted deviation of the received quaternion's norm from 1 (it is renormalised).
inline constexpr double kQuaternionNormTolerance = 1e-3;

/// Short stable name of a decode result (e.g. "bad_checksum"), used as a JSON key.
std::string_view ToString(DecodeResult result);

/// A state datagram ready to send.
using StatePacket = std::array<std::uint8_t, kStatePacketBytes>;
/// A command datagram ready to send.
using CommandPacket = std::array<std::uint8_t, kCommandPacketBytes>;

/// Encodes a device state (`valid` is not sent: a server sends only valid states).
StatePacket EncodeState(const DeviceState& state);

/// Encodes a command: sequence, force, torque, and the safe-fallback and clipped flags. The
/// penalty and impulsive parts are not sent.
CommandPacket EncodeCommand(const DeviceCommand& command);

/// Decodes a state datagram. On kOk writes `*state` (with `valid = true` and the orientation
/// renormalised); otherwise leaves it untouched. Never throws, never allocates.
DecodeResult DecodeState(std::span<const std::uint8_t> datagram, DeviceState* state);

/// Decodes a command datagram. On kOk writes `*command` (penalty and impulsive parts zero);
/// otherwise leaves it untouched. Never throws, never allocates.
DecodeResult DecodeCommand(std::span<const std::uint8_t> datagram, DeviceCommand* command);

/// CRC-32 (IEEE 802.3, as zlib's crc32) of header bytes [0, 12) followed by the payload: the value
/// stored at offset 12. `datagram` must hold at least kHeaderBytes bytes.
std::uint32_t PacketChecksum(std::span<const std::uint8_t> datagram);

}  // namespace rigidtouch::device
