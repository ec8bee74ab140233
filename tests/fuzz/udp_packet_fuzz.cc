// libFuzzer: the UDP packet checks and decoders (protocol v2) on arbitrary datagrams. Framing,
// the MAC check and each payload decoder run on whatever framing accepts (the fuzzer cannot forge
// a MAC, so the payload decoders are driven directly); whatever a decoder accepts must encode
// back, under a key, to a datagram that frames, authenticates and decodes again.
#include <cstddef>
#include <cstdint>
#include <span>

#include "device/udp_protocol.h"

namespace {

namespace d = rigidtouch::device;

const d::DeviceKey& FuzzKey() {
  static const d::DeviceKey key = [] {
    d::DeviceKey k;
    for (std::size_t i = 0; i < k.bytes.size(); ++i) k.bytes[i] = static_cast<std::uint8_t>(i);
    return k;
  }();
  return key;
}

// the re-encoded datagram must pass every check a receiver makes
void CheckAgain(std::span<const std::uint8_t> datagram, d::PacketType type) {
  d::PacketHeader header;
  if (d::CheckFraming(datagram, type, type, &header) != d::DecodeResult::kOk) __builtin_trap();
  if (!d::VerifyMac(datagram, FuzzKey())) __builtin_trap();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::span<const std::uint8_t> datagram(data, size);
  d::PacketHeader header;
  if (d::CheckFraming(datagram, d::PacketType::kState, d::PacketType::kHelloReply, &header) ==
      d::DecodeResult::kOk) {
    static_cast<void>(d::VerifyMac(datagram, FuzzKey()));
    rigidtouch::DeviceState state;
    if (header.type == d::PacketType::kState &&
        d::DecodeStatePayload(datagram, &state) == d::DecodeResult::kOk) {
      const d::StatePacket again = d::EncodeState(state, header, FuzzKey());
      CheckAgain(again, d::PacketType::kState);
      if (d::DecodeStatePayload(again, &state) != d::DecodeResult::kOk) __builtin_trap();
    }
    d::DeviceLimits limits;
    if (header.type == d::PacketType::kHelloReply &&
        d::DecodeHelloReplyPayload(datagram, &limits) == d::DecodeResult::kOk) {
      const d::HelloReplyPacket again =
          d::EncodeHelloReply(limits, header.client_nonce, header.server_nonce, FuzzKey());
      CheckAgain(again, d::PacketType::kHelloReply);
    }
  }
  if (d::CheckFraming(datagram, d::PacketType::kCommand, d::PacketType::kHello, &header) ==
      d::DecodeResult::kOk) {
    static_cast<void>(d::VerifyMac(datagram, FuzzKey()));
    rigidtouch::DeviceCommand command;
    if (header.type == d::PacketType::kCommand &&
        d::DecodeCommandPayload(datagram, &command) == d::DecodeResult::kOk) {
      const d::CommandPacket again = d::EncodeCommand(command, header, FuzzKey());
      CheckAgain(again, d::PacketType::kCommand);
      if (d::DecodeCommandPayload(again, &command) != d::DecodeResult::kOk) __builtin_trap();
    }
  }
  return 0;
}
