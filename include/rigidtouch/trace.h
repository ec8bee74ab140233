// One sample of a haptic run, written per tick (the trace CSV has one row per sample).
#pragma once

#include <cstdint>
#include <string_view>

#include "rigidtouch/types.h"

namespace rigidtouch {

/// A fixed-size, trivially copyable per-tick record: safe to push through a lock-free queue.
/// Forces are those acting on the user/device along the world axes.
struct TraceSample {
  std::int64_t step = 0;
  int tap = -1;  // index of the scripted tap in progress, -1 between taps
  double time_s = 0.0;
  Vec3 tool_position_m = Vec3::Zero();
  Vec3 tool_velocity_mps = Vec3::Zero();
  Vec3 penalty_force_N = Vec3::Zero();    // penalty (or virtual coupling) force sent to the device
  Vec3 impulsive_force_N = Vec3::Zero();  // Eq. 9 force sent to the device
  Vec3 device_force_N = Vec3::Zero();     // what the device displayed (after its limits)
  Vec3 hand_force_N = Vec3::Zero();       // force the hand applies to the device handle
  Vec3 wall_normal = Vec3::UnitZ();       // normal of the deepest tool contact (or last seen)
  double penetration_m = 0.0;             // deepest tool penetration, 0 when not in contact
  int tool_contacts = 0;                  // number of tool contacts this tick
  int impulses = 0;                       // impulses applied to the tool's group this tick
  double kinetic_energy_before_J = 0.0;   // group kinetic energy before this tick's impulse
  double kinetic_energy_after_J = 0.0;    // and after it (equal when no impulse)
  bool clipped = false;                   // the device force limit clipped this tick
  double passivity_dissipated_J = 0.0;    // the passivity controller's dissipation, measured now
};

}  // namespace rigidtouch
