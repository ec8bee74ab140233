// What the UDP bridge's tests share: a loopback address on a port the system picks, and keys.
#pragma once

#include <cstdint>

#include "device/udp_socket.h"
#include "rigidtouch/bridge.h"

namespace rigidtouch::device {

/// 127.0.0.1 on a port the system picks.
inline UdpEndpoint Loopback0() {
  return ParseUdpAddress("udp://127.0.0.1:0", "test");
}

/// A key whose every byte is `fill`.
inline DeviceKey KeyOf(std::uint8_t fill) {
  DeviceKey key;
  key.bytes.fill(fill);
  return key;
}

}  // namespace rigidtouch::device
