// Basic types shared by every stage: vectors, wrenches, the device port, load-time errors.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <stdexcept>
#include <string>

namespace rigidtouch {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;
using Quat = Eigen::Quaterniond;

/// Error thrown at load or configuration time for bad user input. The message names the file,
/// field or parameter and, where one exists, its valid range. Never thrown inside `Tick`.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A force and torque pair, both in the world frame, torque about the point stated by the user.
struct Wrench {
  Vec3 force_N = Vec3::Zero();
  Vec3 torque_Nm = Vec3::Zero();
};

/// What a haptic device can display: one type for a preset (values follow CHAI3D's device
/// specifications), a device's own limits (device::Device::limits), the limits a network bridge
/// announces (its name is not sent), and the limits the tick renders within (DeviceParams::limits).
struct DeviceLimits {
  /// Preset name, e.g. "touch".
  std::string name;
  /// Maximum continuous force [N]; 0 means unlimited.
  double max_force_N = 0.0;
  /// Maximum closed-loop linear stiffness [N/m]; 0 means unknown.
  double max_stiffness_N_per_m = 0.0;
  /// Maximum closed-loop linear damping [N s/m]; 0 means unknown.
  double max_damping_Ns_per_m = 0.0;
  /// Maximum continuous torque [N m]; 0 means the device displays no torque, and none is sent
  /// (every preset is a 3-DoF force device). The loop's last guard and the bridge's device side
  /// clip the torque's magnitude to it.
  double max_torque_Nm = 0.0;
};

/// What a haptic device reports each tick (world frame, SI units). `valid` is false when the
/// reading is stale or missing (e.g. a network watchdog fired); the tick then outputs zero force.
/// `fresh` is false when the reading repeats the previous tick's (same sequence): the tick then
/// starts no collision window and applies no impulse (docs/device-protocol.md, Watchdogs).
struct DeviceState {
  std::uint64_t sequence = 0;      // monotonically increasing per reading
  double time_s = 0.0;             // device clock
  Vec3 position_m = Vec3::Zero();  // end-effector position
  Quat orientation = Quat::Identity();
  Vec3 velocity_mps = Vec3::Zero();  // as the device estimates it
  Vec3 angular_velocity_radps = Vec3::Zero();
  std::uint32_t buttons = 0;
  bool valid = true;
  bool fresh = true;  // a new reading since the previous tick (the haptic loop sets it)
};

/// What the renderer commands the device to display for the next tick.
struct DeviceCommand {
  std::uint64_t sequence = 0;   // the DeviceState sequence this answers
  Vec3 force_N = Vec3::Zero();  // total force sent to the device (after limits)
  Vec3 torque_Nm = Vec3::Zero();
  Vec3 penalty_force_N = Vec3::Zero();    // penalty (or coupling) part, before limits
  Vec3 impulsive_force_N = Vec3::Zero();  // Eq. 9 part, before limits
  bool clipped = false;                   // the device force limit clipped this command
  bool safe_fallback = false;             // an error was detected; the output is zero
};

}  // namespace rigidtouch
