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

}  // namespace rigidtouch::device
