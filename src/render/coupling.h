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
};

/// Stage 1: applies input to the tool (its pose and velocity under direct coupling, its rotation
/// under both) and returns the user wrench. An invalid or non-finite input counts
/// Warning::kBadDeviceState, a finite one beyond DeviceParams' plausible reach or speeds
/// Warning::kImplausibleDeviceState; both make the output zero and, under direct coupling, stop
/// the tool where it is (hold_tool: no velocity now, the same pose after integration).
CouplingResult CoupleDevice(const Model& model, Data& data, const TickInput& input);

/// After stage 7: puts a held tool back at its pose, at rest (nothing when !hold_tool).
void HoldTool(const Model& model, Data& data, const CouplingResult& coupling);

}  // namespace rigidtouch::render
