// Coupling (tick stage 1): the device's state moves the tool. Direct coupling puts the tool where
// the handle is; virtual coupling pulls a simulated tool towards it with a spring-damper.
#pragma once

#include "rigidtouch/rigidtouch.h"

namespace rigidtouch::render {

/// What stage 1 hands to the later stages.
struct CouplingResult {
  Wrench user;            // wrench on the tool's centre of mass from the user or the coupling
  bool device_ok = true;  // false: the input was invalid or non-finite (zero force is output)
  // direct coupling without a usable state: the tool stays at rest where it was (HoldTool)
  bool hold_tool = false;
  BodyState held_tool;
  // the stale-reading policy, decided here only: false when the reading carries no new motion,
  // because it repeats the last one (DeviceState::fresh false: the device stopped updating, or
  // has not yet) or is unusable (invalid, non-finite or implausible: hold_tool). An impulse
  // computed from such a reading would push against a hand that may have moved or gone, and a
  // train's later impulses grow (Eq. 8), so the tick then starts no window (stage 4 sees no
  // contact onset) and applies no impulse (stage 5 is skipped). The haptic loop holds the last
  // fresh tick's force meanwhile (docs/decisions.md, "Device limits").
  bool new_motion = true;
};

/// Stage 1: applies input to the tool (its pose and velocity under direct coupling, its rotation
/// under both) and returns the user wrench. An invalid or non-finite input counts
/// Warning::kBadDeviceState, a finite one beyond DeviceParams' plausible reach or speeds
/// Warning::kImplausibleDeviceState; both make the output zero and, under direct coupling, stop
/// the tool where it is (hold_tool: no velocity now, the same pose after integration).
/// Also decides whether the reading carries new motion (CouplingResult::new_motion).
CouplingResult CoupleDevice(const Model& model, Data& data, const TickInput& input);

/// After stage 6 (render::DeviceOutput's first step): puts a held tool back at its pose, at rest
/// (nothing when !hold_tool).
void HoldTool(const Model& model, Data& data, const CouplingResult& coupling);

}  // namespace rigidtouch::render
