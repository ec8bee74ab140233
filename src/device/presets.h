// Display limits of common haptic devices, as CHAI3D specifies them for each device model.
#pragma once

#include <span>
#include <string_view>

#include "rigidtouch/device.h"
#include "rigidtouch/model.h"

namespace rigidtouch::device {

/// All presets, in a fixed order: touch, omni, falcon, omega3, generic, ideal. Values (max force,
/// max closed-loop stiffness, max closed-loop damping) are those of CHAI3D 3.x's device classes;
/// `generic` is an assumption (see presets.cc); `ideal` has no limits (0), for studying the
/// method without a device's (device_spec.h).
std::span<const DeviceLimits> Presets();

/// The preset called `name` (exact, lowercase). Throws rigidtouch::Error naming the unknown
/// preset and listing the valid ones.
const DeviceLimits& FindPreset(std::string_view name);

/// Tightens a model's device parameters to `limits`: each of max force, stiffness and damping
/// becomes the stricter (smaller positive) of the two, 0 meaning unknown. Call Configure after
/// it to check the rendered stiffness and damping against the result.
void TightenDeviceParams(DeviceParams& params, const DeviceLimits& limits);

/// A contact's stiffness [N/m] and damping [N s/m].
struct Wall {
  double stiffness_N_per_m = 0.0;
  double damping_Ns_per_m = 0.0;
};

/// The wall a device displays when the user sets neither stiffness nor damping, at time step `h`:
/// its stiffness limit, else `law_stiffness` (the contact law's default) when it has none; the
/// damping from DefaultDamping.
Wall DefaultWall(const DeviceLimits& limits, double h, double law_stiffness);

/// The default damping for stiffness `k` at time step `h`: `k h` capped at the device's damping
/// limit (`k h` when only that limit is unknown); on a device with neither a stiffness nor a
/// damping limit (ideal, or a spec's 0 and 0) `k` times kUnlimitedDampingTime, a wall damped
/// enough to hold the tool through the 100 ms collision window (docs/devices.md).
double DefaultDamping(const DeviceLimits& limits, double h, double k);

/// b / k of the default wall of a device without limits [s] (docs/decisions.md).
inline constexpr double kUnlimitedDampingTime = 0.02;

}  // namespace rigidtouch::device
