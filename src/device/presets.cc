#include "device/presets.h"

#include <algorithm>
#include <array>
#include <string>

#include "base/limits.h"
#include "rigidtouch/types.h"

namespace rigidtouch::device {

namespace {

// values as CHAI3D 3.x sets m_maxLinearForce [N], m_maxLinearStiffness [N/m] and
// m_maxLinearDamping [N/(m/s)] in its device classes; torque 0: each displays force only (3-DoF)
const std::array<DeviceLimits, 6>& PresetTable() {
  static const std::array<DeviceLimits, 6> table = {{
      // CHAI3D CPhantomDevices.cpp, model name "Touch" (3D Systems / Geomagic Touch)
      {"touch", 3.3, 400.0, 4.0, 0.0},
      // CHAI3D CPhantomDevices.cpp, model name "PHANTOM Omni"
      {"omni", 3.3, 700.0, 5.0, 0.0},
      // CHAI3D CFalconDevice.cpp (Novint Falcon)
      {"falcon", 8.0, 3000.0, 20.0, 0.0},
      // CHAI3D CDeltaDevices.cpp, Force Dimension omega.3 defaults
      {"omega3", 12.0, 5000.0, 30.0, 0.0},
      // assumption: a mid-range desktop device. force and stiffness match CHAI3D's virtual
      // device (CVirtualDevice.cpp: 10 N, 1000 N/m); damping 10 N s/m is our choice, between
      // the PHANToM family (4-8) and the Falcon (20), since CHAI3D's virtual 100 is not physical
      {"generic", 10.0, 1000.0, 10.0, 0.0},
      // not a device: the method itself, no force, stiffness or damping limit, and no torque (the
      // simulated hand takes force only); its 1 um encoder and zero delay are in device_spec.cc's
      // PresetSpec
      {"ideal", 0.0, 0.0, 0.0, 0.0},
  }};
  return table;
}

}  // namespace

std::span<const DeviceLimits> Presets() {
  return PresetTable();
}

const DeviceLimits& FindPreset(std::string_view name) {
  for (const DeviceLimits& preset : PresetTable()) {
    if (preset.name == name) return preset;
  }
  std::string valid;
  for (const DeviceLimits& preset : PresetTable()) {
    if (!valid.empty()) valid += ", ";
    valid += preset.name;
  }
  throw Error("unknown device preset '" + std::string(name) + "'; valid presets: " + valid);
}

void TightenDeviceParams(DeviceParams& params, const DeviceLimits& limits) {
  params.limits.max_force_N = limits::StricterLimit(params.limits.max_force_N, limits.max_force_N);
  params.limits.max_stiffness_N_per_m =
      limits::StricterLimit(params.limits.max_stiffness_N_per_m, limits.max_stiffness_N_per_m);
  params.limits.max_damping_Ns_per_m =
      limits::StricterLimit(params.limits.max_damping_Ns_per_m, limits.max_damping_Ns_per_m);
}

Wall DefaultWall(const DeviceLimits& limits, double h, double law_stiffness) {
  const double k =
      limits.max_stiffness_N_per_m > 0.0 ? limits.max_stiffness_N_per_m : law_stiffness;
  return {k, DefaultDamping(limits, h, k)};
}

double DefaultDamping(const DeviceLimits& limits, double h, double k) {
  // k h is what a sampled device can add without eating its own physical damping (Colgate and
  // Brown's b > K T / 2 + |B|); an ideal device has no such bound, and k h alone lets the spring
  // throw a 0.6 kg tool back out inside the window
  if (limits.max_damping_Ns_per_m > 0.0) return std::min(k * h, limits.max_damping_Ns_per_m);
  // a device that states a stiffness limit but no damping limit keeps the sampled bound
  if (limits.max_stiffness_N_per_m > 0.0) return k * h;
  return k * kUnlimitedDampingTime;
}

}  // namespace rigidtouch::device
