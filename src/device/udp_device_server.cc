#include "rigidtouch/bridge.h"

#include <array>
#include <cerrno>
#include <cmath>
#include <memory>

#include "device/udp_link.h"
#include "device/udp_protocol.h"
#include "device/udp_socket.h"

namespace rigidtouch::device {
namespace {

constexpr std::string_view kWhat = "udp device server";

UdpEndpoint ParseListen(const UdpDeviceServerOptions& options) {
  ValidatePacketLoss(options.test_loss, kWhat);
  const UdpEndpoint listen = ParseUdpAddress(options.listen, "udp device server: listen");
  RequireLoopbackUnlessAllowed(listen, "udp device server: listen", options.allow_non_loopback);
  return listen;
}

UdpEndpoint ParsePeer(const UdpDeviceServerOptions& options) {
  if (options.peer.empty()) return UdpEndpoint{};
  const UdpEndpoint peer = ParseUdpAddress(options.peer, "udp device server: peer");
  if (peer.port == 0) {
    throw Error("udp device server: peer '" + options.peer + "' needs a port in [1, 65535]");
  }
  RequireLoopbackUnlessAllowed(peer, "udp device server: peer", options.allow_non_loopback);
  return peer;
}

}  // namespace

struct UdpDeviceServer::Impl {
  Impl(Device& served, const UdpDeviceServerOptions& options)
      : device(served),
        watchdog_ns(WatchdogNs(options.watchdog_s, kWhat)),
        fixed_peer(!options.peer.empty()),
        has_peer(fixed_peer),
        peer(ParsePeer(options)),
        socket(ParseListen(options), "udp device server: listen"),
        loss(options.test_loss) {}

  void Step();
  void SendState();
  void DrainCommands(std::int64_t now_ns);

  Device& device;
  std::int64_t watchdog_ns = 0;
  bool fixed_peer = false;
  bool has_peer = false;
  UdpEndpoint peer;
  UdpSocket socket;
  LossSimulator loss;
  UdpCounters counters;
  std::uint64_t sequence = 0;  // the server numbers states itself: strictly increasing on the wire
  DeviceCommand command;       // newest accepted command
  bool has_command = false;
  bool tripped = false;
  std::int64_t last_fresh_ns = 0;
  std::array<std::uint8_t, kMaxDatagramBytes> buffer{};
};

UdpDeviceServer::UdpDeviceServer(Device& device, const UdpDeviceServerOptions& options)
    : impl_(std::make_unique<Impl>(device, options)) {}
UdpDeviceServer::~UdpDeviceServer() = default;
UdpDeviceServer::UdpDeviceServer(UdpDeviceServer&&) noexcept = default;
UdpDeviceServer& UdpDeviceServer::operator=(UdpDeviceServer&&) noexcept = default;

void UdpDeviceServer::Step() {
  impl_->Step();
}
const UdpCounters& UdpDeviceServer::counters() const {
  return impl_->counters;
}
bool UdpDeviceServer::watchdog_tripped() const {
  return impl_->tripped;
}
const UdpEndpoint& UdpDeviceServer::local_endpoint() const {
  return impl_->socket.local();
}
bool UdpDeviceServer::has_peer() const {
  return impl_->has_peer;
}
const UdpEndpoint& UdpDeviceServer::peer() const {
  return impl_->peer;
}
std::uint64_t UdpDeviceServer::last_sequence() const {
  return impl_->sequence;
}

void UdpDeviceServer::Impl::Step() {
  const std::int64_t now_ns = MonotonicNowNs();
  // Device order: Read, (renderer computes), Write
  SendState();
  DrainCommands(now_ns);
  if (has_command && !tripped && now_ns - last_fresh_ns > watchdog_ns) {
    tripped = true;
    ++counters.watchdog_trips;
  }
  if (has_command && !tripped) {
    device.Write(command);
    return;
  }
  DeviceCommand zero;
  zero.sequence = sequence;
  zero.safe_fallback = true;
  device.Write(zero);
  ++counters.fallback_writes;
}

void UdpDeviceServer::Impl::SendState() {
  DeviceState state = device.Read();
  // an invalid reading is not sent: the client's watchdog covers a device that stops reporting
  if (!state.valid) {
    ++counters.invalid_device_states;
    return;
  }
  if (!has_peer) return;
  state.sequence = ++sequence;
  const StatePacket packet = EncodeState(state);
  SendCounted(socket, loss, counters, packet, peer);
}

void UdpDeviceServer::Impl::DrainCommands(std::int64_t now_ns) {
  for (;;) {
    Datagram datagram;
    const int status = socket.Receive(buffer, &datagram);
    if (status == EAGAIN) return;
    if (status != 0) {
      ++counters.receive_errors;
      counters.last_errno = status;
      return;
    }
    ++counters.received;
    if (fixed_peer && datagram.source != peer) {
      ++counters.wrong_source;
      continue;
    }
    if (loss.DropIncoming()) {
      ++counters.test_dropped_incoming;
      continue;
    }
    DecodeResult result = DecodeResult::kOversized;
    DeviceCommand decoded;
    if (datagram.full_bytes == datagram.bytes) {
      result =
          DecodeCommand(std::span<const std::uint8_t>(buffer.data(), datagram.bytes), &decoded);
    }
    if (result != DecodeResult::kOk) {
      ++counters.malformed[static_cast<std::size_t>(result)];
      continue;
    }
    if (!has_peer || datagram.source != peer) {
      // a new client takes over; its sequence numbers are unrelated to the old one's
      peer = datagram.source;
      has_peer = true;
      ++counters.peer_changes;
    } else if (has_command && !tripped && decoded.sequence < command.sequence) {
      ++counters.stale;
      continue;
    }
    // an equal sequence replaces the command: a renderer ticking faster than the device answers
    // one state several times, and the later answer is the newer one
    command = decoded;
    has_command = true;
    ++counters.accepted;
    last_fresh_ns = now_ns;
    if (tripped) {
      tripped = false;
      ++counters.recoveries;
    }
  }
}

}  // namespace rigidtouch::device
