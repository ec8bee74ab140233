// The device side of the UDP device link (docs/device-protocol.md, version 3): streams a local
// Device's state to one authenticated renderer and applies that renderer's newest command to it,
// clamped to the device's own force limit. Used by `rigidtouch device-sim` and by vendor bridges
// (examples/vendor_bridge/), which link the installed rigidtouch::rigidtouch and implement
// rigidtouch/device.h. Also the pre-shared key both ends authenticate every datagram with.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "rigidtouch/device.h"

namespace rigidtouch::device {

/// An IPv4 address and port, both in host byte order.
struct UdpEndpoint {
  /// The address, e.g. 0x7f000001 for 127.0.0.1.
  std::uint32_t address = 0;
  /// The port; 0 when binding means "any free port".
  std::uint16_t port = 0;

  /// Returns true for an address in 127.0.0.0/8.
  bool IsLoopback() const { return (address >> 24) == 127; }
  /// Returns the endpoint as "udp://A.B.C.D:PORT".
  std::string ToString() const;
  /// Returns true when address and port are equal.
  bool operator==(const UdpEndpoint&) const = default;
};

/// Bytes of the pre-shared key (HMAC-SHA-256 key).
inline constexpr std::size_t kDeviceKeyBytes = 32;

/// The pre-shared key both ends of the link authenticate every datagram with.
struct DeviceKey {
  /// The key bytes; keep them secret.
  std::array<std::uint8_t, kDeviceKeyBytes> bytes{};
  /// Returns true when the bytes are equal.
  bool operator==(const DeviceKey&) const = default;
};

/// Returns a fresh random key (libsodium's randombytes). Throws Error if libsodium cannot start.
DeviceKey GenerateDeviceKey();

/// Returns the per-user default key file: $XDG_CONFIG_HOME/rigidtouch/device.key when
/// XDG_CONFIG_HOME is an absolute path, else $HOME/.config/rigidtouch/device.key. Throws Error
/// when neither variable is usable.
std::string DefaultDeviceKeyPath();

/// Reads a key file: 64 hexadecimal digits, optionally followed by white space. Throws Error
/// naming the file when it is missing, not a regular file, not owned by this user, readable or
/// writable by group or others (as ssh refuses private keys; the message says to chmod 600), or
/// malformed.
DeviceKey LoadDeviceKey(const std::string& path);

/// Writes `key` to `path` with mode 0600, creating its directory (mode 0700) if needed. Throws
/// Error when the file exists and `overwrite` is false, or when it cannot be written.
void WriteDeviceKey(const std::string& path, const DeviceKey& key, bool overwrite);

/// Returns `key` if set; else the key in `key_file` if that is not empty (the file must exist);
/// else the per-user default key file's, created with a fresh key on first use.
DeviceKey ResolveDeviceKey(const std::optional<DeviceKey>& key, const std::string& key_file);

/// Outcome of decoding one datagram's framing or payload. Every value except kOk means the
/// datagram was dropped. A datagram whose MAC does not verify is counted apart
/// (UdpCounters::unauthenticated), not here.
enum class DecodeResult : std::uint8_t {
  kOk = 0,         ///< A valid packet of an expected type.
  kTooShort,       ///< Fewer bytes than the header or than the payload the header announces.
  kBadMagic,       ///< The first four bytes are not the protocol magic.
  kWrongVersion,   ///< A protocol version this build does not speak (version 1 included).
  kWrongType,      ///< A known header, but not a packet type the receiver expects.
  kOversized,      ///< More bytes than the header announces or than the type allows.
  kNonFinite,      ///< A NaN or infinite value in the payload.
  kBadQuaternion,  ///< An orientation quaternion whose norm differs from 1 by more than 1e-3.
  kBadLimits,      ///< A hello-reply announcing a negative device limit.
};

/// Number of DecodeResult values, the size of per-reason counter arrays.
inline constexpr std::size_t kDecodeResultCount = 9;

/// Test-only loss simulation: each datagram is dropped with the given probability, drawn from a
/// seeded generator so runs are reproducible. Both fractions default to 0 (no loss).
struct PacketLoss {
  /// Probability in [0, 1] of discarding a received datagram.
  double incoming_fraction = 0.0;
  /// Probability in [0, 1] of not sending a datagram.
  double outgoing_fraction = 0.0;
  /// Seed of the generator that draws the drops.
  std::uint64_t seed = 1;
};

/// What one end of the link has seen since construction, in datagrams unless stated. Plain
/// counters: read them from the thread that drives the device (or after it has stopped).
struct UdpCounters {
  /// Datagrams read from the socket, valid or not.
  std::uint64_t received = 0;
  /// Decoded packets that became the newest state or command (client: at most one per Read).
  std::uint64_t accepted = 0;
  /// Valid packets older than the newest sequence, dropped; client side also the valid states
  /// one Read took before the newest it took (only the newest is rendered).
  std::uint64_t stale = 0;
  /// Valid states with the same sequence as the newest one, dropped (client side).
  std::uint64_t duplicate = 0;
  /// Datagrams from an address other than the peer, dropped.
  std::uint64_t wrong_source = 0;
  /// Well-framed datagrams whose MAC does not verify under our key (forged, corrupted, or
  /// another key), dropped.
  std::uint64_t unauthenticated = 0;
  /// Authenticated datagrams of the session whose counter is not above the newest one accepted
  /// (a replay, a duplicate, or one overtaken in flight), dropped.
  std::uint64_t replayed = 0;
  /// Authenticated states or commands outside the established session (no session yet, an old
  /// session's, or a hello-reply to a hello we no longer wait for), dropped.
  std::uint64_t no_session = 0;
  /// Sessions established (client: hello-replies accepted; server: confirming hellos that
  /// answered its challenge).
  std::uint64_t handshakes = 0;
  /// Server side: authenticated hellos refused because another address holds a live session.
  std::uint64_t hellos_refused = 0;
  /// Authenticated handshake packets refused as replays: server side, a hello whose client
  /// nonce it challenged before, or a confirming hello that answers no challenge in flight;
  /// client side, a hello-reply to a hello it no longer waits for, or the same reply again. A
  /// replay never opens, extends or ends a session.
  std::uint64_t replayed_handshakes = 0;
  /// Client side: states that waited in the socket while the renderer did not read (a stall
  /// longer than max_state_age_s), dropped before the MAC check and never rendered.
  std::uint64_t expired = 0;
  /// Server side: sessions ended because the peer sent nothing authenticated for
  /// session_timeout_s.
  std::uint64_t session_timeouts = 0;
  /// Server side: commands whose force was clamped to the device's max_force_N before Write.
  std::uint64_t clamped_commands = 0;
  /// Malformed datagrams, dropped, indexed by DecodeResult.
  std::array<std::uint64_t, kDecodeResultCount> malformed{};
  /// Transitions from fresh to stale (the watchdog tripped).
  std::uint64_t watchdog_trips = 0;
  /// Transitions from stale back to fresh.
  std::uint64_t recoveries = 0;
  /// Datagrams handed to the socket.
  std::uint64_t sent = 0;
  /// Send failures (see last_errno).
  std::uint64_t send_errors = 0;
  /// Receive failures other than "nothing pending" (see last_errno).
  std::uint64_t receive_errors = 0;
  /// Received datagrams discarded by the test-only loss simulation.
  std::uint64_t test_dropped_incoming = 0;
  /// Datagrams not sent because of the test-only loss simulation.
  std::uint64_t test_dropped_outgoing = 0;
  /// Server side: zero-force writes because there was no command yet, the watchdog tripped or
  /// the server was released (Release).
  std::uint64_t fallback_writes = 0;
  /// Server side: Device::Read calls that returned valid = false.
  std::uint64_t invalid_device_states = 0;
  /// Server side: times a session started with a different client address.
  std::uint64_t peer_changes = 0;
  /// The errno value of the last send or receive failure, 0 if none.
  int last_errno = 0;

  /// Returns the number of malformed datagrams over all reasons.
  std::uint64_t MalformedTotal() const;
  /// Returns the number of malformed datagrams for one reason.
  std::uint64_t Malformed(DecodeResult reason) const {
    return malformed[static_cast<std::size_t>(reason)];
  }
};

/// Configuration of a UdpDeviceServer (immutable once the server is built).
struct UdpDeviceServerOptions {
  /// Address to bind as "udp://HOST:PORT"; port 0 picks a free port.
  std::string listen = "udp://127.0.0.1:47000";
  /// Fixed renderer address; empty means any client holding the key (one session at a time).
  std::string peer;
  /// Time without a fresh command after which the device gets zero force [s], in (0, 10].
  double watchdog_s = 0.05;
  /// Time without an authenticated datagram from the peer after which its session ends and
  /// another client may start one [s], in [watchdog_s, 60].
  double session_timeout_s = 0.5;
  /// The pre-shared key; when unset, `key_file` is read (see ResolveDeviceKey).
  std::optional<DeviceKey> key;
  /// Key file; empty means the per-user default, created on first use (DefaultDeviceKeyPath).
  std::string key_file;
  /// Must be true for any address outside 127.0.0.0/8.
  bool allow_non_loopback = false;
  /// Test-only simulated packet loss; keep it zero in real use.
  PacketLoss test_loss;
};

/// Serves one Device over UDP. Call Step once per device period (from the vendor's servo
/// callback or a rate loop): it reads the device, sends its state to the session's peer, drains
/// hellos and commands (only authenticated ones of the session; newest wins) and writes the
/// newest command to the device with its force clamped to device.limits().max_force_N (and the
/// torque scaled with it), or zero
/// force flagged safe-fallback when there is none yet or the watchdog has tripped. A session
/// starts with an authenticated hello that the server challenges with a fresh nonce and a
/// confirming hello that answers the challenge; a hello seen before is refused as a replay, and
/// while a session is live, hellos from other addresses are refused. Step never blocks, allocates
/// or throws. Not thread-safe: call every member from the thread that drives it.
class UdpDeviceServer {
 public:
  /// Validates the options, resolves the key and binds. Throws Error naming the option when an
  /// address is malformed, not loopback without allow_non_loopback, or cannot be bound (e.g. in
  /// use), or naming the key file when it cannot be used. `device` must outlive the server.
  UdpDeviceServer(Device& device, const UdpDeviceServerOptions& options);
  /// Closes the socket.
  ~UdpDeviceServer();
  /// Moves the server; the moved-from object may only be destroyed or assigned to.
  UdpDeviceServer(UdpDeviceServer&&) noexcept;
  /// Moves the server; the moved-from object may only be destroyed or assigned to.
  UdpDeviceServer& operator=(UdpDeviceServer&&) noexcept;
  UdpDeviceServer(const UdpDeviceServer&) = delete;
  UdpDeviceServer& operator=(const UdpDeviceServer&) = delete;

  /// Runs one device period (see the class comment).
  void Step();
  /// Writes the zero wrench, flagged safe-fallback, to the device and drops the newest command,
  /// so that later Steps write zero until the renderer sends a new one. Call it from the thread
  /// that drives Step when the bridge stops (after the last Step): a device holds its last
  /// command, and the renderer's may still be a push into a wall.
  void Release();

  /// Returns the counters since construction.
  const UdpCounters& counters() const;
  /// Returns true while no fresh command has arrived for watchdog_s (after a first one did).
  bool watchdog_tripped() const;
  /// Returns the bound address (with the chosen port when bound to port 0).
  const UdpEndpoint& local_endpoint() const;
  /// Returns true while a session is established (states have somewhere to go).
  bool has_peer() const;
  /// Returns the session's client address; meaningful when has_peer().
  const UdpEndpoint& peer() const;
  /// Returns the sequence number of the last state sent (0 before the first).
  std::uint64_t last_sequence() const;

 private:
  // the socket and the loss generator stay out of the installed header
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace rigidtouch::device
