// The device port: every device, real, simulated, replayed or bridged, implements this interface
// and is driven in a fixed order each period: Read, compute, Write, EndPeriod (CHAI3D
// cGenericHapticDevice, HAPI's device/renderer split). Installed, so a vendor bridge outside the
// tree can implement it.
#pragma once

#include <cstdint>
#include <string>

#include "rigidtouch/trace.h"
#include "rigidtouch/types.h"

namespace rigidtouch::device {

/// The device's limits: rigidtouch::DeviceLimits (rigidtouch/types.h), the one limits type of
/// presets, devices, the bridge and the model, also named here for code written against this
/// header before it moved.
using DeviceLimits = rigidtouch::DeviceLimits;

/// A haptic device. Implementations never throw from Read, Write or EndPeriod: errors are
/// reported through DeviceState::valid and counters of the implementation. The driver calls
/// them from one thread, once each per period, in the order Read, Write, EndPeriod; when it stops
/// it calls Write once more, after the last EndPeriod, with the zero wrench (flagged
/// safe-fallback), so that a device that holds its last command stops pushing.
class Device {
 public:
  virtual ~Device() = default;

  /// Returns the latest state of the end effector (world frame, SI units).
  virtual DeviceState Read() = 0;

  /// Commands the wrench to display until the next Write.
  virtual void Write(const DeviceCommand& command) = 0;

  /// Returns the display limits of this device.
  virtual const DeviceLimits& limits() const = 0;

  /// Called once per period after Write, with the period in seconds. A device that lives in
  /// loop time (a simulated plant) advances itself here, so the same loop drives simulated and
  /// real devices; a real device keeps its own clock and ignores it (the default).
  virtual void EndPeriod(double period_s) { static_cast<void>(period_s); }

  /// Adds to a tick's trace sample what only the device knows, such as the scripted tap in
  /// progress or the force a simulated hand applies. Called after Write and before EndPeriod,
  /// so the values describe the start of the period. The default leaves the sample unchanged.
  virtual void AnnotateTrace(TraceSample& sample) const { static_cast<void>(sample); }

  /// True once a device that has an end (a replayed record) has delivered its last state; the
  /// loop then stops after that period. Checked after EndPeriod. The default never ends.
  virtual bool Ended() const { return false; }
};

/// Returns a monotonic clock reading in nanoseconds (CLOCK_MONOTONIC), the clock both ends of
/// the UDP link use for their watchdogs; a bridge may use it to stamp DeviceState::time_s.
std::int64_t MonotonicNowNs() noexcept;

}  // namespace rigidtouch::device
