// Pieces shared by both ends of the UDP device link: the checks every received datagram passes,
// the counters they report and the test-only packet-loss simulation.
#pragma once

#include <array>
#include <cerrno>
#include <cstdint>
#include <random>
#include <span>
#include <string_view>

#include "device/udp_protocol.h"
#include "device/udp_socket.h"
#include "rigidtouch/bridge.h"
#include "rigidtouch/device.h"

namespace rigidtouch::device {

// UdpCounters and PacketLoss are in rigidtouch/bridge.h: the server's options and counters
// use them.

/// Most datagrams one Read (client) or Step (server) takes off its socket; the rest wait for the
/// next period. Bounds the time a flood can take from a period (each costs an HMAC), so the loop
/// keeps its rate and its watchdog; 64 per period is far above the one datagram a peer sends.
inline constexpr int kMaxDatagramsPerPeriod = 64;

/// Throws Error naming `what` and the field when a fraction is outside [0, 1].
void ValidatePacketLoss(const PacketLoss& loss, std::string_view what);

/// Throws Error naming `what` unless watchdog_s is finite and in (0, 10] s.
void ValidateWatchdog(double watchdog_s, std::string_view what);

/// Validates watchdog_s as ValidateWatchdog does and returns it in nanoseconds.
std::int64_t WatchdogNs(double watchdog_s, std::string_view what);

/// Draws the drop decisions of a PacketLoss. Allocation-free.
class LossSimulator {
 public:
  /// Seeds the generator from `loss.seed`.
  explicit LossSimulator(const PacketLoss& loss);
  /// True when the next incoming datagram is to be discarded.
  bool DropIncoming() { return Draw(loss_.incoming_fraction); }
  /// True when the next outgoing datagram is to be discarded.
  bool DropOutgoing() { return Draw(loss_.outgoing_fraction); }

 private:
  bool Draw(double fraction);

  PacketLoss loss_;
  std::mt19937_64 generator_;
  std::uniform_real_distribution<double> uniform_{0.0, 1.0};
};

/// Where one end of the link reads from: its socket, receive buffer, test-only loss, counters
/// and key.
struct LinkInbox {
  UdpSocket& socket;
  std::span<std::uint8_t> buffer;
  LossSimulator& loss;
  UdpCounters& counters;
  const DeviceKey& key;
};

/// Most datagrams one client Read takes off its socket, so that a backlog queued while the
/// renderer stalled (a few hundred states at most: the socket's default buffer holds about 250)
/// is emptied in one or two periods. Those beyond kMaxDatagramsPerPeriod cost a receive but no
/// MAC: only datagrams from the server, framed and not expired, are verified.
inline constexpr int kMaxBacklogDatagrams = 512;

/// What one drain may take: receives and MAC verifications.
struct DrainBudget {
  int receives = kMaxDatagramsPerPeriod;
  int verifications = kMaxDatagramsPerPeriod;
};

/// Takes datagrams off the socket, within `budget`, and calls `admit(header, bytes, source)`
/// for each that comes from `required_source` (any source when it is null), survives the
/// test-only loss, arrived whole, is framed as `first` or `second`, is not `expired(header)`
/// (counted in `counters.expired` and dropped before the MAC) and carries a valid MAC; every
/// other one is counted in `counters` by why it was refused. Stops at the first EAGAIN or socket
/// error (counted: a persistent error must not spin the loop). Returns true when it stopped at
/// EAGAIN: the socket was emptied. Never blocks or allocates; throws only what `admit` throws.
template <typename Expired, typename Admit>
bool DrainAuthenticated(const LinkInbox& inbox, const UdpEndpoint* required_source,
                        PacketType first, PacketType second, DrainBudget budget, Expired&& expired,
                        Admit&& admit) {
  UdpCounters& counters = inbox.counters;
  int verified = 0;
  for (int taken = 0; taken < budget.receives && verified < budget.verifications; ++taken) {
    Datagram datagram;
    const int status = inbox.socket.Receive(inbox.buffer, &datagram);
    if (status == EAGAIN) return true;
    if (status != 0) {
      ++counters.receive_errors;
      counters.last_errno = status;
      return false;
    }
    ++counters.received;
    if (required_source != nullptr && datagram.source != *required_source) {
      ++counters.wrong_source;
      continue;
    }
    if (inbox.loss.DropIncoming()) {
      ++counters.test_dropped_incoming;
      continue;
    }
    if (datagram.full_bytes != datagram.bytes) {
      ++counters.malformed[static_cast<std::size_t>(DecodeResult::kOversized)];
      continue;
    }
    const std::span<const std::uint8_t> bytes(inbox.buffer.data(), datagram.bytes);
    PacketHeader header;
    const DecodeResult framing = CheckFraming(bytes, first, second, &header);
    if (framing != DecodeResult::kOk) {
      ++counters.malformed[static_cast<std::size_t>(framing)];
      continue;
    }
    if (expired(header)) {
      ++counters.expired;
      continue;
    }
    ++verified;
    if (!VerifyMac(bytes, inbox.key)) {
      ++counters.unauthenticated;
      continue;
    }
    admit(header, bytes, datagram.source);
  }
  return false;
}

/// Sends one datagram unless the test-only loss drops it, and counts the outcome in `counters`
/// (sent, send_errors with last_errno, test_dropped_outgoing). Never blocks, allocates or throws.
void SendCounted(UdpSocket& socket, LossSimulator& loss, UdpCounters& counters,
                 std::span<const std::uint8_t> datagram, const UdpEndpoint& destination) noexcept;

}  // namespace rigidtouch::device
