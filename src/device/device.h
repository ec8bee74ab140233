// The device port: every device, real, simulated, replayed or bridged, implements this interface
// and is driven in a fixed order each tick: Read, compute, Write (CHAI3D cGenericHapticDevice,
// HAPI's device/renderer split).
#pragma once

#include <span>
#include <string>
#include <string_view>

#include "rigidtouch/types.h"

namespace rigidtouch::device {

/// Display limits of a device model. Values follow CHAI3D's device specifications.
struct DeviceLimits {
  std::string name;                    // preset name, e.g. "touch"
  double max_force_N = 0.0;            // maximum continuous force; 0 means unlimited
  double max_stiffness_N_per_m = 0.0;  // maximum closed-loop linear stiffness
  double max_damping_Ns_per_m = 0.0;   // maximum closed-loop linear damping
};

/// A haptic device. Implementations never throw from Read or Write: errors are reported through
/// DeviceState::valid and counters of the implementation.
class Device {
 public:
  virtual ~Device() = default;
  /// Latest state of the end effector.
  virtual DeviceState Read() = 0;
  /// Command the wrench to display until the next Write.
  virtual void Write(const DeviceCommand& command) = 0;
  /// Limits of this device.
  virtual const DeviceLimits& limits() const = 0;
};

}  // namespace rigidtouch::device
