#include "device/udp_device.h"

#include <algorithm>
#include <cerrno>
#include <cmath>

namespace rigidtouch::device {
namespace {

constexpr std::string_view kUdpDeviceWhat = "udp device";

UdpEndpoint ParseServer(const UdpDeviceOptions& options) {
  return ParseRemoteAddress(options.server, "udp device: server", options.allow_non_loopback);
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

std::int64_t MaxStateAgeNs(const UdpDeviceOptions& options) {
  const double age_s = options.max_state_age_s;
  if (!(std::isfinite(age_s) && age_s > 0.0 && age_s <= 10.0)) {
    throw Error("udp device: max_state_age_s = " + std::to_string(age_s) + " is outside (0, 10] s");
  }
  // a state older than the watchdog is never fresh anyway
  return std::llround(std::min(age_s, options.watchdog_s) * 1e9);
}

}  // namespace

UdpDevice::UdpDevice(const UdpDeviceOptions& options)
    : own_limits_(options.limits),
      limits_(options.limits),
      server_(ParseServer(options)),
      watchdog_ns_(WatchdogNs(options.watchdog_s, kUdpDeviceWhat)),
      hello_interval_ns_(HelloIntervalNs(options.hello_interval_s)),
      max_state_age_ns_(MaxStateAgeNs(options)),
      key_(ResolveDeviceKey(options.key, options.key_file)),
      socket_(ParseLocal(options), "udp device: local"),
      loss_(options.test_loss) {
  state_.valid = false;
  const std::int64_t now_ns = MonotonicNowNs();
  last_emptied_ns_ = now_ns;
  SendHello(now_ns, /*new_handshake=*/true);
}

void UdpDevice::SendHello(std::int64_t now_ns, bool new_handshake) {
  // a fresh nonce per handshake, so a reply recorded from an earlier one cannot be replayed;
  // resends keep it, so a reply slower than the resend period is still taken
  session_.Close();
  if (new_handshake) client_nonce_ = RandomNonce();
  last_hello_ns_ = now_ns;
  const HelloPacket packet = EncodeHello(client_nonce_, key_);
  SendCounted(socket_, loss_, counters_, packet, server_);
}

void UdpDevice::SendConfirm(std::int64_t now_ns) {
  // the server's challenge under our key: only a holder of the key can open the session
  last_hello_ns_ = now_ns;
  const HelloPacket packet = EncodeHello(client_nonce_, key_, session_.server_nonce());
  SendCounted(socket_, loss_, counters_, packet, server_);
}

DeviceState UdpDevice::Read() {
  const std::int64_t now_ns = MonotonicNowNs();
  // states pending now arrived after the newest Read that emptied the socket began: when that
  // was longer ago than max_state_age_s (the renderer stalled), none is known to be recent, so
  // the backlog is dropped unread and this Read renders nothing
  const bool recent = now_ns - last_emptied_ns_ <= max_state_age_ns_;
  const LinkInbox inbox{socket_, buffer_, loss_, counters_, key_};
  states_this_read_ = 0;
  const bool emptied = DrainAuthenticated(
      inbox, &server_, PacketType::kHelloReply, PacketType::kState,
      DrainBudget{kMaxBacklogDatagrams, kMaxDatagramsPerPeriod},
      [&](const PacketHeader& header) { return !recent && header.type == PacketType::kState; },
      [&](const PacketHeader& header, std::span<const std::uint8_t> bytes,
          const UdpEndpoint& /*source*/) {
        if (header.type == PacketType::kHelloReply) {
          HandleReply(header, bytes, now_ns);
        } else {
          HandleState(header, bytes, now_ns);
        }
      });
  if (emptied) last_emptied_ns_ = now_ns;
  if (states_this_read_ > 0) {
    // only the newest state this Read took is rendered; the ones before it are stale
    ++counters_.accepted;
    counters_.stale += static_cast<std::uint64_t>(states_this_read_ - 1);
  }
  if (session_.live() && now_ns - last_fresh_ns_ > watchdog_ns_) {
    if (has_state_ && !tripped_) {
      tripped_ = true;
      ++counters_.watchdog_trips;
    }
    // the server stalled, restarted or lost us: ask for a new session at once
    SendHello(now_ns, /*new_handshake=*/true);
  } else if (now_ns - last_hello_ns_ >= hello_interval_ns_) {
    if (!session_.live()) {
      SendHello(now_ns, /*new_handshake=*/false);
    } else if (!session_.has_sequence()) {
      SendConfirm(now_ns);  // no state yet: the confirmation may have been lost
    }
  }
  DeviceState out = state_;
  out.valid = has_state_ && !tripped_ && recent;
  return out;
}

void UdpDevice::HandleReply(const PacketHeader& header, std::span<const std::uint8_t> datagram,
                            std::int64_t now_ns) {
  if (session_.live() || header.client_nonce != client_nonce_ || header.server_nonce == 0) {
    // an answer to an older hello, the same challenge again, or a recorded reply: a reply
    // opens a session only for the hello we are waiting for, once
    ++counters_.replayed_handshakes;
    return;
  }
  DeviceLimits announced;
  const DecodeResult result = DecodeHelloReplyPayload(datagram, &announced);
  if (result != DecodeResult::kOk) {
    ++counters_.malformed[static_cast<std::size_t>(result)];
    return;
  }
  session_.Open(client_nonce_, header.server_nonce);
  SendConfirm(now_ns);
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
  DeviceState decoded;
  if (!session_.Receive(header, datagram, &DecodeStatePayload, &decoded, counters_)) return;
  // newest sequence wins within the session; a new session numbers from 1 again
  switch (session_.Order(decoded.sequence)) {
    case SequenceOrder::kEqual:
      ++counters_.duplicate;
      return;
    case SequenceOrder::kOlder:
      ++counters_.stale;
      return;
    case SequenceOrder::kFirst:
    case SequenceOrder::kNewer:
      break;
  }
  session_.Accept(decoded.sequence);
  state_ = decoded;
  ++states_this_read_;
  last_fresh_ns_ = now_ns;
  has_state_ = true;
  if (tripped_) {
    tripped_ = false;
    ++counters_.recoveries;
  }
}

void UdpDevice::Write(const DeviceCommand& command) {
  if (!session_.live()) return;  // the server would drop it; the hello is what it needs
  const CommandPacket packet =
      EncodeCommand(command, session_.NextHeader(PacketType::kCommand), key_);
  SendCounted(socket_, loss_, counters_, packet, server_);
}

}  // namespace rigidtouch::device
