#include "device/udp_device_server.h"

#include <cerrno>
#include <cmath>

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

UdpDeviceServer::UdpDeviceServer(Device& device, const UdpDeviceServerOptions& options)
    : device_(device),
      watchdog_ns_(WatchdogNs(options.watchdog_s, kWhat)),
      fixed_peer_(!options.peer.empty()),
      has_peer_(fixed_peer_),
      peer_(ParsePeer(options)),
      socket_(ParseListen(options), "udp device server: listen"),
      loss_(options.test_loss) {}

void UdpDeviceServer::Step() {
  const std::int64_t now_ns = MonotonicNowNs();
  // Device order: Read, (renderer computes), Write
  SendState();
  DrainCommands(now_ns);
  if (has_command_ && !tripped_ && now_ns - last_fresh_ns_ > watchdog_ns_) {
    tripped_ = true;
    ++counters_.watchdog_trips;
  }
  if (has_command_ && !tripped_) {
    device_.Write(command_);
    return;
  }
  DeviceCommand zero;
  zero.sequence = sequence_;
  zero.safe_fallback = true;
  device_.Write(zero);
  ++counters_.fallback_writes;
}

void UdpDeviceServer::SendState() {
  DeviceState state = device_.Read();
  // an invalid reading is not sent: the client's watchdog covers a device that stops reporting
  if (!state.valid) {
    ++counters_.invalid_device_states;
    return;
  }
  if (!has_peer_) return;
  state.sequence = ++sequence_;
  const StatePacket packet = EncodeState(state);
  SendCounted(socket_, loss_, counters_, packet, peer_);
}

void UdpDeviceServer::DrainCommands(std::int64_t now_ns) {
  for (;;) {
    Datagram datagram;
    const int status = socket_.Receive(buffer_, &datagram);
    if (status == EAGAIN) return;
    if (status != 0) {
      ++counters_.receive_errors;
      counters_.last_errno = status;
      return;
    }
    ++counters_.received;
    if (fixed_peer_ && datagram.source != peer_) {
      ++counters_.wrong_source;
      continue;
    }
    if (loss_.DropIncoming()) {
      ++counters_.test_dropped_incoming;
      continue;
    }
    DecodeResult result = DecodeResult::kOversized;
    DeviceCommand decoded;
    if (datagram.full_bytes == datagram.bytes) {
      result =
          DecodeCommand(std::span<const std::uint8_t>(buffer_.data(), datagram.bytes), &decoded);
    }
    if (result != DecodeResult::kOk) {
      ++counters_.malformed[static_cast<std::size_t>(result)];
      continue;
    }
    if (!has_peer_ || datagram.source != peer_) {
      // a new client takes over; its sequence numbers are unrelated to the old one's
      peer_ = datagram.source;
      has_peer_ = true;
      ++counters_.peer_changes;
    } else if (has_command_ && !tripped_ && decoded.sequence < command_.sequence) {
      ++counters_.stale;
      continue;
    }
    // an equal sequence replaces the command: a renderer ticking faster than the device answers
    // one state several times, and the later answer is the newer one
    command_ = decoded;
    has_command_ = true;
    ++counters_.accepted;
    last_fresh_ns_ = now_ns;
    if (tripped_) {
      tripped_ = false;
      ++counters_.recoveries;
    }
  }
}

}  // namespace rigidtouch::device
