#include "device/udp_device.h"

#include <cerrno>
#include <cmath>

namespace rigidtouch::device {
namespace {

constexpr std::string_view kWhat = "udp device";

UdpEndpoint ParseServer(const UdpDeviceOptions& options) {
  const UdpEndpoint server = ParseUdpAddress(options.server, "udp device: server");
  if (server.port == 0) {
    throw Error("udp device: server '" + options.server + "' needs a port in [1, 65535]");
  }
  RequireLoopbackUnlessAllowed(server, "udp device: server", options.allow_non_loopback);
  return server;
}

UdpEndpoint ParseLocal(const UdpDeviceOptions& options) {
  ValidatePacketLoss(options.test_loss, kWhat);
  const UdpEndpoint local = ParseUdpAddress(options.local, "udp device: local");
  // 0.0.0.0 (any interface) is not loopback either, so it also needs the explicit option
  RequireLoopbackUnlessAllowed(local, "udp device: local", options.allow_non_loopback);
  return local;
}

}  // namespace

UdpDevice::UdpDevice(const UdpDeviceOptions& options)
    : limits_(options.limits),
      server_(ParseServer(options)),
      watchdog_ns_(WatchdogNs(options.watchdog_s, kWhat)),
      socket_(ParseLocal(options), "udp device: local"),
      loss_(options.test_loss) {
  state_.valid = false;
  // announce ourselves: a server streams states to the last client that sent a command
  DeviceCommand hello;
  hello.safe_fallback = true;
  Write(hello);
}

DeviceState UdpDevice::Read() {
  const std::int64_t now_ns = MonotonicNowNs();
  for (;;) {
    Datagram datagram;
    const int status = socket_.Receive(buffer_, &datagram);
    if (status == EAGAIN) break;
    if (status != 0) {
      // a persistent socket error must not spin the loop: stop draining for this tick
      ++counters_.receive_errors;
      counters_.last_errno = status;
      break;
    }
    ++counters_.received;
    if (datagram.source != server_) {
      ++counters_.wrong_source;
      continue;
    }
    if (loss_.DropIncoming()) {
      ++counters_.test_dropped_incoming;
      continue;
    }
    DecodeResult result = DecodeResult::kOversized;
    DeviceState decoded;
    if (datagram.full_bytes == datagram.bytes) {
      result = DecodeState(std::span<const std::uint8_t>(buffer_.data(), datagram.bytes), &decoded);
    }
    if (result != DecodeResult::kOk) {
      ++counters_.malformed[static_cast<std::size_t>(result)];
      continue;
    }
    // newest sequence wins; after a watchdog trip any sequence resynchronises (server restart)
    if (has_state_ && !tripped_) {
      if (decoded.sequence == state_.sequence) {
        ++counters_.duplicate;
        continue;
      }
      if (decoded.sequence < state_.sequence) {
        ++counters_.stale;
        continue;
      }
    }
    state_ = decoded;
    ++counters_.accepted;
    last_fresh_ns_ = now_ns;
    has_state_ = true;
    if (tripped_) {
      tripped_ = false;
      ++counters_.recoveries;
    }
  }
  if (has_state_ && !tripped_ && now_ns - last_fresh_ns_ > watchdog_ns_) {
    tripped_ = true;
    ++counters_.watchdog_trips;
  }
  DeviceState out = state_;
  out.valid = has_state_ && !tripped_;
  return out;
}

void UdpDevice::Write(const DeviceCommand& command) {
  const CommandPacket packet = EncodeCommand(command);
  SendCounted(socket_, loss_, counters_, packet, server_);
}

}  // namespace rigidtouch::device
