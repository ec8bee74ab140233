// One session of the UDP device link as either end sees it (docs/device-protocol.md,
// "Sessions"): both nonces, the counter of the packets this end sends, the newest counter and
// sequence accepted from the other end; and the device side's memory of the hellos it has
// challenged, so that a hello seen before never opens or extends a session. UdpDevice (renderer
// side) and UdpDeviceServer (device side) both keep their session here.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "device/udp_protocol.h"
#include "rigidtouch/bridge.h"

namespace rigidtouch::device {

/// How a received sequence compares with the newest one accepted in the session.
enum class SequenceOrder : std::uint8_t {
  kFirst,  ///< No payload accepted yet in this session.
  kNewer,
  kEqual,
  kOlder,
};

/// The session state both ends keep. Never allocates or throws.
class UdpSession {
 public:
  /// True between Open and Close.
  bool live() const { return live_; }
  std::uint64_t client_nonce() const { return client_nonce_; }
  std::uint64_t server_nonce() const { return server_nonce_; }

  /// Starts the session of these nonces: both counters and the newest sequence from scratch.
  void Open(std::uint64_t client_nonce, std::uint64_t server_nonce);
  /// Ends it: nothing more is accepted or sent under its nonces.
  void Close() { live_ = false; }
  /// True when the session is live with exactly these nonces.
  bool Is(std::uint64_t client_nonce, std::uint64_t server_nonce) const {
    return live_ && client_nonce == client_nonce_ && server_nonce == server_nonce_;
  }

  /// The header of the next state or command this end sends: both nonces, the next counter.
  PacketHeader NextHeader(PacketType type);

  /// Takes an authenticated state or command: of this session (else `no_session`), with a
  /// counter above the newest accepted (else `replayed`), whose payload `decode` accepts (else
  /// counted in `malformed` by its reason). On success advances the received counter, writes
  /// `*payload` and returns true.
  template <typename Payload>
  bool Receive(const PacketHeader& header, std::span<const std::uint8_t> datagram,
               DecodeResult (*decode)(std::span<const std::uint8_t>, Payload*), Payload* payload,
               UdpCounters& counters) {
    if (!Is(header.client_nonce, header.server_nonce)) {
      ++counters.no_session;
      return false;
    }
    if (header.counter <= received_counter_) {
      ++counters.replayed;
      return false;
    }
    const DecodeResult result = decode(datagram, payload);
    if (result != DecodeResult::kOk) {
      ++counters.malformed[static_cast<std::size_t>(result)];
      return false;
    }
    received_counter_ = header.counter;
    return true;
  }

  /// Where `sequence` stands against the newest one accepted in the session.
  SequenceOrder Order(std::uint64_t sequence) const;
  /// Makes `sequence` the newest accepted one.
  void Accept(std::uint64_t sequence);
  /// Forgets the newest sequence, so the next one is taken whatever it is (the device side after
  /// its watchdog tripped).
  void ForgetSequence() { has_sequence_ = false; }
  /// True once a payload of this session has been accepted.
  bool has_sequence() const { return has_sequence_; }

 private:
  bool live_ = false;
  std::uint64_t client_nonce_ = 0;
  std::uint64_t server_nonce_ = 0;
  std::uint64_t sent_counter_ = 0;
  std::uint64_t received_counter_ = 0;
  bool has_sequence_ = false;
  std::uint64_t newest_sequence_ = 0;
};

/// The device side's handshake memory: the challenges it sent that await their confirming hello,
/// and the client nonces of the last kRememberedHellos hellos it challenged. Never allocates.
class HandshakeMemory {
 public:
  /// Challenges in flight at once; a new one replaces the oldest.
  static constexpr std::size_t kPending = 4;
  /// Client nonces remembered; a hello carrying one of them is a replay and is refused.
  static constexpr std::size_t kRememberedHellos = 256;

  /// A challenge sent: the hello's address and nonce, the device's nonce and when.
  struct Challenge {
    UdpEndpoint source;
    std::uint64_t client_nonce = 0;
    std::uint64_t server_nonce = 0;
    std::int64_t sent_ns = 0;
  };

  /// The challenge in flight for this address and client nonce, or null.
  const Challenge* Pending(const UdpEndpoint& source, std::uint64_t client_nonce) const;
  /// True when a hello with this client nonce was challenged before (a replay).
  bool Seen(std::uint64_t client_nonce) const;
  /// Remembers the hello and its challenge (replacing the oldest challenge in flight).
  const Challenge& Remember(const UdpEndpoint& source, std::uint64_t client_nonce,
                            std::uint64_t server_nonce, std::int64_t now_ns);
  /// Takes the challenge that the confirming hello (source, client and server nonce) answers,
  /// sent at most `max_age_ns` ago: true and forgotten (each challenge confirms once), or false.
  bool Confirm(const UdpEndpoint& source, std::uint64_t client_nonce, std::uint64_t server_nonce,
               std::int64_t now_ns, std::int64_t max_age_ns);

 private:
  std::array<Challenge, kPending> pending_{};
  std::size_t next_pending_ = 0;
  std::array<std::uint64_t, kRememberedHellos> seen_{};
  std::size_t next_seen_ = 0;
};

}  // namespace rigidtouch::device
