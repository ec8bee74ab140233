// libFuzzer: the UDP packet decoders on arbitrary datagrams; whatever they accept must encode
// back to a packet they accept again.
#include <cstddef>
#include <cstdint>
#include <span>

#include "device/udp_protocol.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  namespace d = rigidtouch::device;
  const std::span<const std::uint8_t> datagram(data, size);
  rigidtouch::DeviceState state;
  if (d::DecodeState(datagram, &state) == d::DecodeResult::kOk) {
    const d::StatePacket again = d::EncodeState(state);
    if (d::DecodeState(again, &state) != d::DecodeResult::kOk) __builtin_trap();
  }
  rigidtouch::DeviceCommand command;
  if (d::DecodeCommand(datagram, &command) == d::DecodeResult::kOk) {
    const d::CommandPacket again = d::EncodeCommand(command);
    if (d::DecodeCommand(again, &command) != d::DecodeResult::kOk) __builtin_trap();
  }
  return 0;
}
