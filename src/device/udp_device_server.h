// The device side of the UDP device link: streams a local Device's state to a renderer and
// applies the renderer's newest command to it. Used by `rigidtouch device-sim` and by vendor
// bridges (examples/vendor_bridge/).
#pragma once

#include <array>
#include <cstdint>
#include <string>

#include "device/device.h"
#include "device/udp_link.h"
#include "device/udp_protocol.h"
#include "device/udp_socket.h"

namespace rigidtouch::device {

/// Configuration of a UdpDeviceServer (immutable once the server is built).
struct UdpDeviceServerOptions {
  std::string listen = "udp://127.0.0.1:47000";  // address to bind; port 0 picks a free port
  std::string peer;  // fixed renderer address; empty: the last client that sent a valid command
  double watchdog_s = 0.05;         // no fresh command for this long: zero force to the device
  bool allow_non_loopback = false;  // required for any address outside 127.0.0.0/8
  PacketLoss test_loss;             // test-only simulated loss; keep zero in real use
};

/// Serves one Device over UDP. Call Step once per device period (e.g. from loop::RateLoop):
/// Read the device, send its state to the peer, drain commands (newest sequence wins), Write the
/// newest command to the device, or zero force flagged safe-fallback when there is none yet or
/// the watchdog has tripped. Step never blocks, allocates or throws.
class UdpDeviceServer {
 public:
  /// Validates the options and binds. Throws Error naming the option when an address is
  /// malformed, not loopback without allow_non_loopback, or cannot be bound (e.g. in use).
  /// `device` must outlive the server.
  UdpDeviceServer(Device& device, const UdpDeviceServerOptions& options);

  /// One device period (see the class comment).
  void Step();

  /// Counters since construction.
  const UdpCounters& counters() const { return counters_; }
  /// True while no fresh command has arrived for watchdog_s (after a first one did).
  bool watchdog_tripped() const { return tripped_; }
  /// The bound address (with the chosen port when bound to port 0).
  const UdpEndpoint& local_endpoint() const { return socket_.local(); }
  /// True once states have somewhere to go (a fixed peer, or a client has sent a command).
  bool has_peer() const { return has_peer_; }
  /// Where states are sent; meaningful when has_peer().
  const UdpEndpoint& peer() const { return peer_; }
  /// Sequence number of the last state sent (0 before the first).
  std::uint64_t last_sequence() const { return sequence_; }

 private:
  void SendState();
  void DrainCommands(std::int64_t now_ns);

  Device& device_;
  std::int64_t watchdog_ns_ = 0;
  bool fixed_peer_ = false;
  bool has_peer_ = false;
  UdpEndpoint peer_;
  UdpSocket socket_;
  LossSimulator loss_;
  UdpCounters counters_;
  std::uint64_t sequence_ = 0;  // the server numbers states itself: strictly increasing on the wire
  DeviceCommand command_;       // newest accepted command
  bool has_command_ = false;
  bool tripped_ = false;
  std::int64_t last_fresh_ns_ = 0;
  std::array<std::uint8_t, kMaxDatagramBytes> buffer_{};
};

}  // namespace rigidtouch::device
