#include "render/output.h"

#include "render/workspace.h"

namespace rigidtouch::render {
namespace {

bool StateFinite(const Data& data) {
  for (const BodyState& s : data.bodies) {
    if (!s.x_W.allFinite() || !s.v_W.allFinite() || !s.w_W.allFinite() ||
        !s.q_WB.coeffs().allFinite()) {
      return false;
    }
  }
  return true;
}

}  // namespace

DeviceCommand DeviceWrench(const Model& model, Data& data, std::uint64_t sequence) {
  const int tool = model.tool;
  DeviceCommand out;
  out.sequence = sequence;
  data.tool_penalty_force_W.setZero();
  data.tool_penetration_m = 0.0;
  data.tool_contacts = 0;
  Vec3 tool_torque = Vec3::Zero();
  for (int ci = 0; ci < data.ncontact; ++ci) {
    const Contact& c = data.contacts[ci];
    if (c.body_a != tool && c.body_b != tool) continue;
    const double sign = c.body_a == tool ? 1.0 : -1.0;
    const Vec3 f = sign * (c.normal_force_N * c.n_W + c.friction_force_W);
    data.tool_penalty_force_W += f;
    tool_torque += (c.p_W - data.bodies[tool].x_W).cross(f);
    ++data.tool_contacts;
    if (c.depth_m > data.tool_penetration_m) {
      data.tool_penetration_m = c.depth_m;
      data.tool_normal_W = sign * c.n_W;
    }
  }
  if (model.device.coupling == Coupling::kVirtual) {
    out.penalty_force_N = -data.tool_coupling_force_W;  // the coupling spring pulls the device
  } else {
    out.penalty_force_N = data.tool_penalty_force_W;
    out.torque_Nm = tool_torque;
  }
  out.impulsive_force_N = data.tool_impulse_W / model.timestep_s;  // Eq. 9
  out.force_N = out.penalty_force_N + out.impulsive_force_N;
  if (model.device.max_force_N > 0.0 && out.force_N.norm() > model.device.max_force_N) {
    out.force_N *= model.device.max_force_N / out.force_N.norm();
    out.clipped = true;
    data.Warn(Warning::kForceClipped);
    if (out.impulsive_force_N.squaredNorm() > 0.0) data.Warn(Warning::kImpulseClipped);
  }
  return out;
}

void Safeguard(const Model& model, Data& data, bool device_ok, DeviceCommand& out) {
  if (!StateFinite(data)) {
    data.Warn(Warning::kNonFiniteState);
    ResetState(model, data);
    device_ok = false;
  }
  if (!device_ok || !out.force_N.allFinite() || !out.torque_Nm.allFinite()) {
    out.force_N.setZero();
    out.torque_Nm.setZero();
    out.safe_fallback = true;
  }
}

}  // namespace rigidtouch::render
