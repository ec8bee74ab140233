// Render (tick stage 8): the device command. The wrench the tool's contacts exert (or the virtual
// coupling's pull) plus the impulsive force of Eq. 9, limited to the device's force, and the
// safety guards that replace it with zero when the state or the input went bad.
#pragma once

#include "contact/phases.h"
#include "render/coupling.h"
#include "rigidtouch/rigidtouch.h"

namespace rigidtouch::render {

/// Scales a finite force, and the torque with it, so that |force_N| <= max_force_N (0: no limit)
/// exactly, keeping its direction; overflow-safe for components up to the largest double.
/// Returns whether it scaled. Used by the render stage and by the haptic loop's last guard.
bool LimitForce(double max_force_N, Vec3& force_N, Vec3& torque_Nm);

/// Clips a torque's magnitude to max_torque_Nm, keeping its direction, rounded down and
/// overflow-safe; a non-finite torque becomes zero. max_torque_Nm <= 0 (a device that displays
/// no torque) makes the torque zero without counting it as clipped. Returns whether it clipped.
bool LimitTorque(double max_torque_Nm, Vec3& torque_Nm);

/// Sums the tool's contact forces into data (tool_penalty_force_N_W, penetration, normal, count;
/// the contacts of the tool's group, as this tick's stage 3 built the groups) and returns the
/// command: penalty (or coupling) + Eq. 9 impulsive force, clipped to
/// DeviceParams::max_force_N (Warning::kForceClipped, and kImpulseClipped when it held an
/// impulsive part). Where the impulse over h or the sum overflows, the parts are added in units
/// of the larger one, so a finite clipped answer is still found. `contact` is stage 3's scratch:
/// the groups and the approach speeds (for the event renderer's transient).
DeviceCommand DeviceWrench(const Model& model, Data& data, const contact::ContactScratch& contact,
                           std::uint64_t sequence);

/// The safety guards: a non-finite body state counts Warning::kNonFiniteState; then a bad input or
/// state, or a non-finite command, makes the command the safe zero wrench
/// (DeviceCommand::safe_fallback). Returns false when the state was non-finite: the caller (the
/// tick) puts it back to initial (ResetState, which the engine owns).
bool Safeguard(Data& data, bool device_ok, DeviceCommand& out);

/// Stage 7, render, in one call: the held tool put back (HoldTool), the command (DeviceWrench,
/// with the event transient), the passivity controller (PassivityControl) and the safety guards
/// (Safeguard). `state_ok` becomes false when the state went non-finite: the tick then puts it
/// back to initial (ResetState, which the engine owns).
DeviceCommand DeviceOutput(const Model& model, Data& data, const contact::ContactScratch& contact,
                           const DeviceState& device, const CouplingResult& coupling,
                           bool& state_ok);

}  // namespace rigidtouch::render
