#include "device/udp_socket.h"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <cstring>
#include <utility>

#include "rigidtouch/types.h"

namespace rigidtouch::device {
namespace {

constexpr std::string_view kScheme = "udp://";

sockaddr_in ToSockaddr(const UdpEndpoint& endpoint) {
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(endpoint.address);
  address.sin_port = htons(endpoint.port);
  return address;
}

[[noreturn]] void ThrowMalformed(std::string_view text, std::string_view what) {
  throw Error(std::string(what) + ": malformed UDP address '" + std::string(text) +
              "': expected udp://HOST:PORT with HOST a dotted IPv4 address or localhost and "
              "PORT in [0, 65535]");
}

}  // namespace

std::string UdpEndpoint::ToString() const {
  return std::string(kScheme) + std::to_string((address >> 24) & 0xff) + "." +
         std::to_string((address >> 16) & 0xff) + "." + std::to_string((address >> 8) & 0xff) +
         "." + std::to_string(address & 0xff) + ":" + std::to_string(port);
}

UdpEndpoint ParseUdpAddress(std::string_view text, std::string_view what) {
  if (!text.starts_with(kScheme)) ThrowMalformed(text, what);
  const std::string_view rest = text.substr(kScheme.size());
  const std::size_t colon = rest.rfind(':');
  if (colon == std::string_view::npos || colon == 0 || colon + 1 == rest.size()) {
    ThrowMalformed(text, what);
  }
  const std::string host(rest.substr(0, colon));
  const std::string_view port_text = rest.substr(colon + 1);
  unsigned port = 0;
  const auto [end, error] =
      std::from_chars(port_text.data(), port_text.data() + port_text.size(), port);
  if (error != std::errc() || end != port_text.data() + port_text.size() || port > 65535) {
    ThrowMalformed(text, what);
  }
  in_addr parsed{};
  if (host == "localhost") {
    parsed.s_addr = htonl(INADDR_LOOPBACK);
  } else if (inet_pton(AF_INET, host.c_str(), &parsed) != 1) {
    ThrowMalformed(text, what);
  }
  return UdpEndpoint{ntohl(parsed.s_addr), static_cast<std::uint16_t>(port)};
}

void RequireLoopbackUnlessAllowed(const UdpEndpoint& endpoint, std::string_view what,
                                  bool allow_non_loopback) {
  if (endpoint.IsLoopback() || allow_non_loopback) return;
  throw Error(std::string(what) + ": " + endpoint.ToString() +
              " is not a loopback address (127.0.0.0/8); other addresses need the explicit "
              "allow_non_loopback option (and a key shared by both ends, --key: "
              "docs/device-protocol.md, Security)");
}

UdpEndpoint ParseRemoteAddress(std::string_view text, std::string_view what,
                               bool allow_non_loopback) {
  const UdpEndpoint remote = ParseUdpAddress(text, what);
  if (remote.port == 0) {
    throw Error(std::string(what) + " '" + std::string(text) + "' needs a port in [1, 65535]");
  }
  RequireLoopbackUnlessAllowed(remote, what, allow_non_loopback);
  return remote;
}

UdpSocket::UdpSocket(const UdpEndpoint& local, std::string_view what) : local_(local) {
  fd_ = ::socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd_ < 0) {
    throw Error(std::string(what) + ": cannot create a UDP socket for " + local.ToString() + ": " +
                std::strerror(errno));
  }
  const sockaddr_in address = ToSockaddr(local);
  if (::bind(fd_, reinterpret_cast<const sockaddr*>(&address), sizeof(address)) != 0) {
    const int bind_errno = errno;
    ::close(fd_);
    fd_ = -1;
    throw Error(std::string(what) + ": cannot bind " + local.ToString() + ": " +
                std::strerror(bind_errno));
  }
  sockaddr_in bound{};
  socklen_t length = sizeof(bound);
  if (::getsockname(fd_, reinterpret_cast<sockaddr*>(&bound), &length) == 0) {
    local_.port = ntohs(bound.sin_port);
  }
}

UdpSocket::~UdpSocket() {
  if (fd_ >= 0) ::close(fd_);
}

UdpSocket::UdpSocket(UdpSocket&& other) noexcept
    : fd_(std::exchange(other.fd_, -1)), local_(other.local_) {}

UdpSocket& UdpSocket::operator=(UdpSocket&& other) noexcept {
  if (this != &other) {
    if (fd_ >= 0) ::close(fd_);
    fd_ = std::exchange(other.fd_, -1);
    local_ = other.local_;
  }
  return *this;
}

int UdpSocket::SendTo(std::span<const std::uint8_t> bytes,
                      const UdpEndpoint& destination) noexcept {
  const sockaddr_in address = ToSockaddr(destination);
  const ssize_t sent = ::sendto(fd_, bytes.data(), bytes.size(), MSG_DONTWAIT | MSG_NOSIGNAL,
                                reinterpret_cast<const sockaddr*>(&address), sizeof(address));
  if (sent < 0) return errno;
  return static_cast<std::size_t>(sent) == bytes.size() ? 0 : EMSGSIZE;
}

int UdpSocket::Receive(std::span<std::uint8_t> buffer, Datagram* datagram) noexcept {
  sockaddr_in source{};
  socklen_t length = sizeof(source);
  // MSG_TRUNC makes recvfrom return the datagram's real length even when it did not fit
  const ssize_t received = ::recvfrom(fd_, buffer.data(), buffer.size(), MSG_DONTWAIT | MSG_TRUNC,
                                      reinterpret_cast<sockaddr*>(&source), &length);
  if (received < 0) return errno == EWOULDBLOCK ? EAGAIN : errno;
  datagram->full_bytes = static_cast<std::size_t>(received);
  datagram->bytes = std::min(datagram->full_bytes, buffer.size());
  datagram->source = UdpEndpoint{ntohl(source.sin_addr.s_addr), ntohs(source.sin_port)};
  return 0;
}

}  // namespace rigidtouch::device
