// Render (tick stage 8): the device command. The wrench the tool's contacts exert (or the virtual
// coupling's pull) plus the impulsive force of Eq. 9, limited to the device's force, and the
// safety guards that replace it with zero when the state or the input went bad.
#pragma once

#include "rigidtouch/rigidtouch.h"

namespace rigidtouch::render {

/// Sums the tool's contact forces into data (tool_penalty_force_W, penetration, normal, count)
/// and returns the command: penalty (or coupling) + Eq. 9 impulsive force, clipped to
/// DeviceParams::max_force_N (Warning::kForceClipped, and kImpulseClipped when it held an
/// impulsive part).
DeviceCommand DeviceWrench(const Model& model, Data& data, std::uint64_t sequence);

/// The safety guards: a non-finite body state counts Warning::kNonFiniteState and puts the state
/// back to initial (ResetState); then a bad input or state, or a non-finite command, makes the
/// command the safe zero wrench (DeviceCommand::safe_fallback).
void Safeguard(const Model& model, Data& data, bool device_ok, DeviceCommand& out);

}  // namespace rigidtouch::render
