#include "device/udp_device.h"

#include <cerrno>
#include <cmath>

namespace rigidtouch::device {
namespace {

constexpr std::string_view kUdpDeviceWhat = "udp device";

UdpEndpoint ParseServer(const UdpDeviceOptions& options) {
  const UdpEndpoint server = ParseUdpAddress(options.server, "udp device: server");
  if (server.port == 0) {
    throw Error("udp device: server '" + options.server + "' needs a port in [1, 65535]");
  }
  RequireLoopbackUnlessAllowed(server, "udp device: server", options.allow_non_loopback);
  return server;
}

UdpEndpoint ParseLocal(const UdpDeviceOptions& options) {
  ValidatePacketLoss(options.test_loss, kUdpDeviceWhat);
  const UdpEndpoint local = ParseUdpAddress(options.local, "udp device: local");
  // 0.0.0.0 (any interface) is not loopback either, so it also needs the explicit option
  RequireLoopbackUnlessAllowed(local, "udp device: local", options.allow_non_loopback);
  return local;
}

std::int64_t HelloIntervalNs(double interval_s) {
  if (!(std::isfinite(interval_s) && interval_s > 0.0 && interval_s <= 10.0)) {
    throw Error("udp device: hello_interval_s = " + std::to_string(interval_s) +
                " is outside (0, 10] s");
  }
  return std::llround(interval_s * 1e9);
}

}  // namespace

UdpDevice::UdpDevice(const UdpDeviceOptions& options)
    : own_limits_(options.limits),
      limits_(options.limits),
      server_(ParseServer(options)),
      watchdog_ns_(WatchdogNs(options.watchdog_s, kUdpDeviceWhat)),
      hello_interval_ns_(HelloIntervalNs(options.hello_interval_s)),
      key_(ResolveDeviceKey(options.key, options.key_file)),
      socket_(ParseLocal(options), "udp device: local"),
      loss_(options.test_loss) {
  state_.valid = false;
  SendHello(MonotonicNowNs(), /*new_handshake=*/true);
}

void UdpDevice::SendHello(std::int64_t now_ns, bool new_handshake) {
  // a fresh nonce per handshake, so a reply recorded from an earlier one cannot be replayed;
  // resends keep it, so a reply slower than the resend period is still taken
  session_ = false;
  if (new_handshake) client_nonce_ = RandomNonce();
  last_hello_ns_ = now_ns;
  const HelloPacket packet = EncodeHello(client_nonce_, key_);
  SendCounted(socket_, loss_, counters_, packet, server_);
}

DeviceState UdpDevice::Read() {
  const std::int64_t now_ns = MonotonicNowNs();
  const LinkInbox inbox{socket_, buffer_, loss_, counters_, key_};
  DrainAuthenticated(inbox, &server_, PacketType::kHelloReply, PacketType::kState,
                     [&](const PacketHeader& header, std::span<const std::uint8_t> bytes,
                         const UdpEndpoint& /*source*/) {
                       if (header.type == PacketType::kHelloReply) {
                         HandleReply(header, bytes, now_ns);
                       } else {
                         HandleState(header, bytes, now_ns);
                       }
                     });
  if (session_ && now_ns - last_fresh_ns_ > watchdog_ns_) {
    if (has_state_ && !tripped_) {
      tripped_ = true;
      ++counters_.watchdog_trips;
    }
    // the server stalled, restarted or lost us: ask for a new session at once
    SendHello(now_ns, /*new_handshake=*/true);
  } else if (!session_ && now_ns - last_hello_ns_ >= hello_interval_ns_) {
    SendHello(now_ns, /*new_handshake=*/false);
  }
  DeviceState out = state_;
  out.valid = has_state_ && !tripped_;
  return out;
}

void UdpDevice::HandleReply(const PacketHeader& header, std::span<const std::uint8_t> datagram,
                            std::int64_t now_ns) {
  if (session_) {
    // the server answered a resent hello of this handshake twice; anything else is foreign
    if (header.client_nonce == client_nonce_ && header.server_nonce == server_nonce_) {
      ++counters_.replayed;
    } else {
      ++counters_.no_session;
    }
    return;
  }
  if (header.client_nonce != client_nonce_ || header.server_nonce == 0) {
    ++counters_.no_session;  // an answer to another (older) hello
    return;
  }
  DeviceLimits announced;
  const DecodeResult result = DecodeHelloReplyPayload(datagram, &announced);
  if (result != DecodeResult::kOk) {
    ++counters_.malformed[static_cast<std::size_t>(result)];
    return;
  }
  session_ = true;
  server_nonce_ = header.server_nonce;
  sent_counter_ = 0;
  received_counter_ = 0;
  has_session_state_ = false;
  last_fresh_ns_ = now_ns;  // the watchdog also covers a server that never streams
  ++counters_.handshakes;
  announced_ = announced;
  // in place: the name string is untouched, so nothing allocates
  limits_.max_force_N = StricterLimit(own_limits_.max_force_N, announced.max_force_N);
  limits_.max_stiffness_N_per_m =
      StricterLimit(own_limits_.max_stiffness_N_per_m, announced.max_stiffness_N_per_m);
  limits_.max_damping_Ns_per_m =
      StricterLimit(own_limits_.max_damping_Ns_per_m, announced.max_damping_Ns_per_m);
}

void UdpDevice::HandleState(const PacketHeader& header, std::span<const std::uint8_t> datagram,
                            std::int64_t now_ns) {
  if (!session_ || header.client_nonce != client_nonce_ || header.server_nonce != server_nonce_) {
    ++counters_.no_session;
    return;
  }
  if (header.counter <= received_counter_) {
    ++counters_.replayed;
    return;
  }
  DeviceState decoded;
  const DecodeResult result = DecodeStatePayload(datagram, &decoded);
  if (result != DecodeResult::kOk) {
    ++counters_.malformed[static_cast<std::size_t>(result)];
    return;
  }
  received_counter_ = header.counter;
  // newest sequence wins within the session; a new session numbers from 1 again
  if (has_session_state_) {
    if (decoded.sequence == state_.sequence) {
      ++counters_.duplicate;
      return;
    }
    if (decoded.sequence < state_.sequence) {
      ++counters_.stale;
      return;
    }
  }
  state_ = decoded;
  ++counters_.accepted;
  last_fresh_ns_ = now_ns;
  has_state_ = true;
  has_session_state_ = true;
  if (tripped_) {
    tripped_ = false;
    ++counters_.recoveries;
  }
}

void UdpDevice::Write(const DeviceCommand& command) {
  if (!session_) return;  // the server would drop it; the hello is what it needs
  const PacketHeader header{PacketType::kCommand, client_nonce_, server_nonce_, ++sent_counter_};
  const CommandPacket packet = EncodeCommand(command, header, key_);
  SendCounted(socket_, loss_, counters_, packet, server_);
}

}  // namespace rigidtouch::device
