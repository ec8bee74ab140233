#include "render/coupling.h"

#include <cmath>

namespace rigidtouch::render {
namespace {

bool FiniteState(const DeviceState& s) {
  return std::isfinite(s.time_s) && s.position_m.allFinite() && s.velocity_mps.allFinite() &&
         s.angular_velocity_radps.allFinite() && s.orientation.coeffs().allFinite();
}

// Within the reach and speeds a hand on a desktop device can produce (DeviceParams): a finite
// but absurd state (a corrupted or misconfigured bridge) would otherwise become an absurd force.
bool Plausible(const DeviceParams& d, const DeviceState& s) {
  return s.position_m.norm() <= d.plausible_radius_m &&
         s.velocity_mps.norm() <= d.plausible_speed_mps &&
         s.angular_velocity_radps.norm() <= d.plausible_angular_speed_radps;
}

// Without a usable device state a directly coupled tool has no pose to follow: it stays where
// the last good state put it, at rest, until a good state arrives. Left to the dynamics it would
// keep its last velocity, bounce off the wall and drift away, and the trace would show contacts
// and impulses of a hand that is not there while the device displays zero.
CouplingResult StartHold(const Model& model, Data& data, CouplingResult r) {
  r.user = Wrench{};
  if (model.device.coupling != Coupling::kDirect) return r;
  BodyState& t = data.bodies[model.tool];
  t.v_W.setZero();
  t.w_W.setZero();
  r.hold_tool = true;
  r.held_tool = t;
  return r;
}

CouplingResult Couple(const Model& model, Data& data, const TickInput& input) {
  CouplingResult r;
  const DeviceState& dev = input.device;
  if (model.device.coupling == Coupling::kNone) {
    if (input.tool_wrench.force_N.allFinite() && input.tool_wrench.torque_Nm.allFinite()) {
      r.user = input.tool_wrench;
    } else {
      r.device_ok = false;
    }
  } else if (!dev.valid || !FiniteState(dev)) {
    r.device_ok = false;
  } else if (!Plausible(model.device, dev)) {
    data.Warn(Warning::kImplausibleDeviceState);
    r.device_ok = false;
    return StartHold(model, data, r);
  } else {
    const int tool = model.tool;
    BodyState& t = data.bodies[tool];
    // the tool turns with the handle under both couplings, so contact torques cannot spin a tool
    // the user holds (a free sphere dragged over a rough floor would roll and stick-slip, and
    // the user would feel that chatter as friction)
    t.q_WB = (dev.orientation * model.bodies[tool].iquat_B).normalized();
    t.w_W = dev.angular_velocity_radps;
    const Vec3 x_dev = dev.position_m + model.device.workspace_offset_m;
    if (model.device.coupling == Coupling::kDirect) {
      t.x_W = x_dev;
      t.v_W = dev.velocity_mps;
    } else {
      // the spring-damper couples the position
      r.user.force_N = model.device.coupling_stiffness_N_per_m * (x_dev - t.x_W) +
                       model.device.coupling_damping_Ns_per_m * (dev.velocity_mps - t.v_W);
      data.tool_coupling_force_N_W = r.user.force_N;
    }
  }
  if (!r.device_ok) {
    data.Warn(Warning::kBadDeviceState);
    return StartHold(model, data, r);
  }
  return r;
}

}  // namespace

CouplingResult CoupleDevice(const Model& model, Data& data, const TickInput& input) {
  CouplingResult r = Couple(model, data, input);
  const bool repeated = model.device.coupling != Coupling::kNone && !input.device.fresh;
  r.new_motion = !repeated && !r.hold_tool;
  return r;
}

void HoldTool(const Model& model, Data& data, const CouplingResult& coupling) {
  if (coupling.hold_tool) data.bodies[model.tool] = coupling.held_tool;
}

}  // namespace rigidtouch::render
