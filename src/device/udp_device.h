// The renderer side of the UDP device link: a Device whose state arrives from a device server
// (UdpDeviceServer, or any program speaking docs/device-protocol.md) and whose commands go back
// to it, within one authenticated session. Newest wins; a watchdog marks the state invalid when
// it goes stale and asks the server for a new session.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>

#include "device/udp_link.h"
#include "device/udp_protocol.h"
#include "device/udp_socket.h"
#include "rigidtouch/device.h"

namespace rigidtouch::device {

/// Configuration of a UdpDevice (immutable once the device is built).
struct UdpDeviceOptions {
  std::string server = "udp://127.0.0.1:47000";  // the device server to talk to
  std::string local = "udp://127.0.0.1:0";       // address to bind; port 0 picks a free port
  double watchdog_s = 0.05;         // no fresh state for this long: state invalid, zero force
  bool allow_non_loopback = false;  // required for any address outside 127.0.0.0/8
  DeviceLimits limits;  // own limits; limits() combines them with the server's announced ones
  std::optional<DeviceKey> key;    // the pre-shared key; when unset, key_file is read
  std::string key_file;            // empty: the per-user default, created on first use
  double hello_interval_s = 0.02;  // hello resend period while there is no session
  PacketLoss test_loss;            // test-only simulated loss; keep zero in real use
};

/// Device client over UDP. Read and Write never block, allocate or throw; problems are counted
/// in counters(). Read drains every pending datagram and keeps the newest valid state of the
/// session; without a session it (re)sends a hello every hello_interval_s.
class UdpDevice final : public Device {
 public:
  /// Validates the options, resolves the key, binds the local socket and sends a hello with a
  /// fresh nonce. Throws Error naming the option when an address is malformed, not loopback
  /// without allow_non_loopback, or cannot be bound, or naming the key file when it is unusable.
  explicit UdpDevice(const UdpDeviceOptions& options);

  /// Newest state received. `valid` is false before the first state and while the watchdog is
  /// tripped (no fresh state for watchdog_s); the pose is then the last one received.
  DeviceState Read() override;

  /// Sends the command to the server (one datagram); nothing without a session.
  void Write(const DeviceCommand& command) override;

  /// The options' limits, each made the stricter of it and the one the server announced in
  /// the newest session's hello-reply (0 counts as no limit).
  const DeviceLimits& limits() const override { return limits_; }

  /// True while a session is established (a hello-reply was accepted and the watchdog has not
  /// ended it since).
  bool has_session() const { return session_; }
  /// The limits the server announced in the newest session; zero before the first.
  const DeviceLimits& announced_limits() const { return announced_; }

  /// Counters since construction.
  const UdpCounters& counters() const { return counters_; }
  /// True while no fresh state has arrived for watchdog_s (after a first one did).
  bool watchdog_tripped() const { return tripped_; }
  /// The bound local address (with the chosen port when bound to port 0).
  const UdpEndpoint& local_endpoint() const { return socket_.local(); }
  /// The server address states are accepted from and commands are sent to.
  const UdpEndpoint& server_endpoint() const { return server_; }

 private:
  void SendHello(std::int64_t now_ns, bool new_handshake);
  void HandleReply(const PacketHeader& header, std::span<const std::uint8_t> datagram,
                   std::int64_t now_ns);
  void HandleState(const PacketHeader& header, std::span<const std::uint8_t> datagram,
                   std::int64_t now_ns);

  DeviceLimits own_limits_;
  DeviceLimits limits_;
  DeviceLimits announced_;
  UdpEndpoint server_;
  std::int64_t watchdog_ns_ = 0;
  std::int64_t hello_interval_ns_ = 0;
  DeviceKey key_;
  UdpSocket socket_;
  LossSimulator loss_;
  UdpCounters counters_;
  // session: our nonce (fresh per handshake), the server's, and the per-direction counters
  bool session_ = false;
  std::uint64_t client_nonce_ = 0;
  std::uint64_t server_nonce_ = 0;
  std::uint64_t sent_counter_ = 0;
  std::uint64_t received_counter_ = 0;
  std::int64_t last_hello_ns_ = 0;
  DeviceState state_;  // newest accepted state
  bool has_state_ = false;
  bool has_session_state_ = false;  // a state of the current session was accepted
  bool tripped_ = false;
  std::int64_t last_fresh_ns_ = 0;  // newest accepted state, or the session's start
  std::array<std::uint8_t, kMaxDatagramBytes> buffer_{};
};

}  // namespace rigidtouch::device
