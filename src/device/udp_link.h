// Pieces shared by both ends of the UDP device link: the counters they report and the test-only
// packet-loss simulation.
#pragma once

#include <array>
#include <cstdint>
#include <random>
#include <span>
#include <string_view>

#include "device/udp_protocol.h"
#include "device/udp_socket.h"

namespace rigidtouch::device {

/// What one end of the link has seen since construction. Plain counters: read them from the
/// thread that drives the device (or after the loop has stopped).
struct UdpCounters {
  std::uint64_t received = 0;      // datagrams read from the socket, valid or not
  std::uint64_t accepted = 0;      // decoded packets that became the newest state/command
  std::uint64_t stale = 0;         // valid, but older than the newest sequence: dropped
  std::uint64_t duplicate = 0;     // valid, same sequence as the newest state: dropped (client)
  std::uint64_t wrong_source = 0;  // from an address other than the peer: dropped
  std::array<std::uint64_t, kDecodeResultCount> malformed{};  // dropped, indexed by DecodeResult
  std::uint64_t watchdog_trips = 0;                           // fresh -> stale transitions
  std::uint64_t recoveries = 0;                               // stale -> fresh transitions
  std::uint64_t sent = 0;                                     // datagrams handed to the socket
  std::uint64_t send_errors = 0;                              // sendto failures (see last_errno)
  std::uint64_t receive_errors = 0;         // recvfrom failures other than "nothing pending"
  std::uint64_t test_dropped_incoming = 0;  // discarded by the test-only loss simulation
  std::uint64_t test_dropped_outgoing = 0;  // not sent because of the test-only loss simulation
  std::uint64_t fallback_writes = 0;  // server: zero-force writes (no command yet or watchdog)
  std::uint64_t invalid_device_states = 0;  // server: Device::Read returned valid = false
  std::uint64_t peer_changes = 0;           // server: the client address changed
  int last_errno = 0;                       // errno of the last send or receive failure

  /// Number of malformed datagrams over all reasons.
  std::uint64_t MalformedTotal() const;
  /// Malformed datagrams for one reason.
  std::uint64_t Malformed(DecodeResult reason) const {
    return malformed[static_cast<std::size_t>(reason)];
  }
};

/// Test-only loss simulation: each datagram is dropped with the given probability, drawn from a
/// seeded generator so runs are reproducible. Both fractions default to 0 (no loss).
struct PacketLoss {
  double incoming_fraction = 0.0;  // in [0, 1]
  double outgoing_fraction = 0.0;  // in [0, 1]
  std::uint64_t seed = 1;
};

/// Throws Error naming `what` and the field when a fraction is outside [0, 1].
void ValidatePacketLoss(const PacketLoss& loss, std::string_view what);

/// Throws Error naming `what` unless watchdog_s is finite and in (0, 10] s.
void ValidateWatchdog(double watchdog_s, std::string_view what);

/// Validates watchdog_s as ValidateWatchdog does and returns it in nanoseconds.
std::int64_t WatchdogNs(double watchdog_s, std::string_view what);

/// Monotonic clock in nanoseconds (CLOCK_MONOTONIC), used by both ends' watchdogs.
std::int64_t MonotonicNowNs() noexcept;

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

/// Sends one datagram unless the test-only loss drops it, and counts the outcome in `counters`
/// (sent, send_errors with last_errno, test_dropped_outgoing). Never blocks, allocates or throws.
void SendCounted(UdpSocket& socket, LossSimulator& loss, UdpCounters& counters,
                 std::span<const std::uint8_t> datagram, const UdpEndpoint& destination) noexcept;

}  // namespace rigidtouch::device
