// The renderer side of the UDP device link: a Device whose state arrives from a device server
// (UdpDeviceServer, or any program speaking docs/device-protocol.md) and whose commands go back
// to it. Newest sequence wins; a watchdog marks the state invalid when it goes stale.
#pragma once

#include <array>
#include <cstdint>
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
  DeviceLimits limits;              // reported by limits(); the link itself does not clip
  PacketLoss test_loss;             // test-only simulated loss; keep zero in real use
};

/// Device client over UDP. Read and Write never block, allocate or throw; problems are counted
/// in counters(). Read drains every pending datagram and keeps the newest valid state.
class UdpDevice final : public Device {
 public:
  /// Validates the options, binds the local socket and sends one zero-force command flagged
  /// safe-fallback so the server learns where to stream states. Throws Error naming the option
  /// when an address is malformed, not loopback without allow_non_loopback, or cannot be bound.
  explicit UdpDevice(const UdpDeviceOptions& options);

  /// Newest state received. `valid` is false before the first state and while the watchdog is
  /// tripped (no fresh state for watchdog_s); the pose is then the last one received.
  DeviceState Read() override;

  /// Sends the command to the server (one datagram).
  void Write(const DeviceCommand& command) override;

  /// Limits from the options.
  const DeviceLimits& limits() const override { return limits_; }

  /// Counters since construction.
  const UdpCounters& counters() const { return counters_; }
  /// True while no fresh state has arrived for watchdog_s (after a first one did).
  bool watchdog_tripped() const { return tripped_; }
  /// The bound local address (with the chosen port when bound to port 0).
  const UdpEndpoint& local_endpoint() const { return socket_.local(); }
  /// The server address states are accepted from and commands are sent to.
  const UdpEndpoint& server_endpoint() const { return server_; }

 private:
  DeviceLimits limits_;
  UdpEndpoint server_;
  std::int64_t watchdog_ns_ = 0;
  UdpSocket socket_;
  LossSimulator loss_;
  UdpCounters counters_;
  DeviceState state_;  // newest accepted state
  bool has_state_ = false;
  bool tripped_ = false;
  std::int64_t last_fresh_ns_ = 0;
  std::array<std::uint8_t, kMaxDatagramBytes> buffer_{};
};

}  // namespace rigidtouch::device
