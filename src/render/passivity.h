// Render (tick stage 8): the time-domain passivity observer and controller at the device port
// (Hannaford and Ryu, IEEE T-RO 18(1), 2002), over any renderer. The observer integrates the
// energy the renderer absorbs at the port over a contact; when the energy it predicts for this
// tick turns negative (the renderer would have given the user more than it took), the controller
// adds the damping that brings it back to zero, within the device's limits.
#pragma once

#include "rigidtouch/rigidtouch.h"

namespace rigidtouch::render {

/// Speed below which the controller stays idle [m/s]: its damping alpha = -E / (h |v|^2) grows
/// without bound as v -> 0 while the force alpha |v| it can apply vanishes; 0.1 mm/s is below a
/// 1 um encoder's finite-difference resolution at 10 kHz.
inline constexpr double kPassivityMinSpeed_mps = 1e-4;

/// The largest damping the controller may add [N s/m]: the device's max_damping_Ns_per_m when
/// known, and never more than m_tool / h, the damping that stops the tool's motion in one tick
/// (a sampled damper beyond it reverses the motion instead of dissipating it).
double MaxControlDamping(const Model& model);

/// Observer and controller for one tick, on the command after DeviceWrench (nothing when
/// RenderParams::passivity_control is off or there is no device). With x, v the device's position
/// and velocity read this tick and F the force it held over the last tick:
///   E <- E - F_last . (x - x_last)                  (observer: the last tick, exact for a hold)
///   E_pred = E - F . v h - R                        (this tick's force, predicted; R the
///                                                    reserve for the observer's quantization
///                                                    error, |e| (sum |dF| + |F|), |e| <= sqrt(3) q
///                                                    / 2 with q
///                                                    DeviceParams::position_resolution_m)
///   E_pred < 0, |v| > kPassivityMinSpeed_mps:  alpha = min(-E_pred / (h |v|^2), MaxControlDamping)
///                                              F <- F - alpha v, then the device's force limit.
/// E restarts at 0 when the last tick held no force (a contact's integral, not the run's, so
/// energy absorbed in one tap cannot pay for activity in the next). An invalid device state
/// restarts it too. Never allocates or throws.
void PassivityControl(const Model& model, Data& data, const DeviceState& device, bool device_ok,
                      DeviceCommand& out);

}  // namespace rigidtouch::render
