// IPv4 UDP endpoint parsing and a small non-blocking socket shared by UdpDevice and
// UdpDeviceServer. Construction and binding throw rigidtouch::Error; sending and receiving never
// throw and never allocate (they return an errno-style status for the caller to count).
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>

#include "rigidtouch/bridge.h"

namespace rigidtouch::device {

// UdpEndpoint is in rigidtouch/bridge.h: the server's public accessors return it.

/// Parses "udp://HOST:PORT" where HOST is a dotted IPv4 address or "localhost" and PORT is in
/// [0, 65535]. Throws Error naming `what` (e.g. "--listen") and the text when it is malformed.
UdpEndpoint ParseUdpAddress(std::string_view text, std::string_view what);

/// Parses the address of the other end, as ParseUdpAddress does; it needs a port in [1, 65535]
/// and, unless `allow_non_loopback`, a loopback address. Throws Error naming `what` otherwise.
UdpEndpoint ParseRemoteAddress(std::string_view text, std::string_view what,
                               bool allow_non_loopback);

/// Throws Error naming `what` unless the endpoint is loopback or `allow_non_loopback` is set.
void RequireLoopbackUnlessAllowed(const UdpEndpoint& endpoint, std::string_view what,
                                  bool allow_non_loopback);

/// Result of one non-blocking receive.
struct Datagram {
  std::size_t bytes = 0;       // bytes copied into the caller's buffer
  std::size_t full_bytes = 0;  // length of the datagram on the wire (> bytes when truncated)
  UdpEndpoint source;
};

/// A bound, non-blocking IPv4 UDP socket (close-on-exec). Move-only.
class UdpSocket {
 public:
  /// Binds to `local`. Throws Error naming `what`, the address and the system's reason when the
  /// socket cannot be created or bound (e.g. the port is in use).
  UdpSocket(const UdpEndpoint& local, std::string_view what);
  ~UdpSocket();
  UdpSocket(UdpSocket&& other) noexcept;
  UdpSocket& operator=(UdpSocket&& other) noexcept;
  UdpSocket(const UdpSocket&) = delete;
  UdpSocket& operator=(const UdpSocket&) = delete;

  /// The bound address, with the port the system chose when binding to port 0.
  const UdpEndpoint& local() const { return local_; }

  /// Sends one datagram. Returns 0 on success, else the errno value. Never blocks.
  int SendTo(std::span<const std::uint8_t> bytes, const UdpEndpoint& destination) noexcept;

  /// Receives one pending datagram into `buffer`. Returns 0 and fills `*datagram` when one was
  /// read, EAGAIN when none is pending, else the errno value. Never blocks.
  int Receive(std::span<std::uint8_t> buffer, Datagram* datagram) noexcept;

 private:
  int fd_ = -1;
  UdpEndpoint local_;
};

}  // namespace rigidtouch::device
