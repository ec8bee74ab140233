#include "render/output.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "render/event.h"
#include "render/passivity.h"

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

// Scales the wrench (m u, torque) so that |m u| <= max_force_N, measuring the force in units of
// m so that no step overflows when |m u| is beyond the double range. u and m are finite, m > 0.
// Returns whether it scaled; force_N is then the clipped force.
bool ClampScaled(const Vec3& u, double m, double max_force_N, Vec3& force_N, Vec3& torque_Nm) {
  const double n_u = u.norm();
  if (n_u <= max_force_N / m) {
    force_N = u * m;  // fits: |m u| <= max_force_N, finite
    return false;
  }
  const double s = max_force_N / n_u;  // n_u > 0 here
  force_N = u * s;
  torque_Nm = (torque_Nm / m) * s;
  return true;
}

// The limit is a hard bound: rounding may leave |f| a few ulps above it.
void RoundDownToLimit(double max_force_N, Vec3& force_N, Vec3& torque_Nm) {
  constexpr double kShrink = 1.0 - 4.0 * std::numeric_limits<double>::epsilon();
  for (int k = 0; k < 4 && force_N.norm() > max_force_N; ++k) {
    force_N *= kShrink;
    torque_Nm *= kShrink;
  }
}

}  // namespace

bool LimitForce(double max_force_N, Vec3& force_N, Vec3& torque_Nm) {
  if (!(max_force_N > 0.0) || !force_N.allFinite()) return false;
  const double n = force_N.norm();
  bool clipped = false;
  if (std::isfinite(n)) {
    if (n <= max_force_N) return false;
    const double s = max_force_N / n;
    force_N *= s;
    torque_Nm *= s;
    clipped = true;
  } else {
    // components above ~1e154: the squared norm overflows, the direction does not
    const double m = force_N.cwiseAbs().maxCoeff();
    clipped = ClampScaled(force_N / m, m, max_force_N, force_N, torque_Nm);
  }
  if (clipped) RoundDownToLimit(max_force_N, force_N, torque_Nm);
  return clipped;
}

bool LimitTorque(double max_torque_Nm, Vec3& torque_Nm) {
  if (!(max_torque_Nm > 0.0)) {
    torque_Nm.setZero();
    return false;
  }
  if (!torque_Nm.allFinite()) {
    torque_Nm.setZero();
    return true;
  }
  // the force clip's arithmetic (overflow-safe, rounded down), with nothing scaled alongside
  Vec3 none = Vec3::Zero();
  return LimitForce(max_torque_Nm, torque_Nm, none);
}

DeviceCommand DeviceWrench(const Model& model, Data& data, const contact::ContactScratch& contact,
                           std::uint64_t sequence) {
  const int tool = model.tool;
  DeviceCommand out;
  out.sequence = sequence;
  data.tool_penalty_force_N_W.setZero();
  data.tool_penetration_m = 0.0;
  data.tool_contacts = 0;
  Vec3 tool_torque = Vec3::Zero();
  // the tool's contacts are among its group's (this tick's groups, stage 3), in contact order
  const contact::Groups& G = contact.groups;
  const int group = data.ncontact > 0 ? data.body_group[tool] : -1;
  const int begin = group >= 0 ? G.contact_start[group] : 0;
  const int end = group >= 0 ? G.contact_start[group + 1] : 0;
  for (int k = begin; k < end; ++k) {
    const Contact& c = data.contacts[G.contacts[k]];
    if (c.body_a != tool && c.body_b != tool) continue;
    const double sign = c.body_a == tool ? 1.0 : -1.0;
    const Vec3 f = sign * (c.normal_force_N * c.n_W + c.friction_force_N_W);
    data.tool_penalty_force_N_W += f;
    tool_torque += (c.p_W - data.bodies[tool].x_W).cross(f);
    ++data.tool_contacts;
    if (c.depth_m > data.tool_penetration_m) {
      data.tool_penetration_m = c.depth_m;
      data.tool_normal_W = sign * c.n_W;
    }
  }
  if (model.device.coupling == Coupling::kVirtual) {
    out.penalty_force_N = -data.tool_coupling_force_N_W;  // the coupling spring pulls the device
  } else {
    out.penalty_force_N = data.tool_penalty_force_N_W;
    out.torque_Nm = tool_torque;
  }
  // Eq. 9, or the event renderer's open-loop transient (no impulses there)
  out.impulsive_force_N = data.tool_impulse_Ns_W / model.timestep_s +
                          EventTransient(model, data, contact.normal_velocity);
  out.force_N = out.penalty_force_N + out.impulsive_force_N;
  const double max_force_N = model.device.limits.max_force_N;
  if (out.force_N.allFinite()) {
    out.clipped = LimitForce(max_force_N, out.force_N, out.torque_Nm);
  } else if (max_force_N > 0.0 && out.penalty_force_N.allFinite() &&
             data.tool_impulse_Ns_W.allFinite()) {
    // the impulse over h or the sum overflowed: add the parts in units of the larger, so the
    // clipped force keeps the direction of the finite answer instead of becoming zero
    const double m = std::max(out.penalty_force_N.cwiseAbs().maxCoeff(),
                              data.tool_impulse_Ns_W.cwiseAbs().maxCoeff());
    const Vec3 u = out.penalty_force_N / m + (data.tool_impulse_Ns_W / m) / model.timestep_s;
    out.clipped = ClampScaled(u, m, max_force_N, out.force_N, out.torque_Nm);
    if (out.clipped) RoundDownToLimit(max_force_N, out.force_N, out.torque_Nm);
  }
  // anything still non-finite (no limit to clip to) becomes the safe zero wrench in Safeguard
  if (out.clipped) {
    data.Warn(Warning::kForceClipped);
    if (data.tool_impulse_Ns_W.squaredNorm() > 0.0) data.Warn(Warning::kImpulseClipped);
  }
  return out;
}

bool Safeguard(Data& data, bool device_ok, DeviceCommand& out) {
  const bool state_ok = StateFinite(data);
  if (!state_ok) {
    data.Warn(Warning::kNonFiniteState);
    device_ok = false;
  }
  if (!device_ok || !out.force_N.allFinite() || !out.torque_Nm.allFinite()) {
    out.force_N.setZero();
    out.torque_Nm.setZero();
    out.safe_fallback = true;
  }
  return state_ok;
}

DeviceCommand DeviceOutput(const Model& model, Data& data, const contact::ContactScratch& contact,
                           const DeviceState& device, const CouplingResult& coupling,
                           bool& state_ok) {
  HoldTool(model, data, coupling);
  DeviceCommand out = DeviceWrench(model, data, contact, device.sequence);
  // the passivity observer and controller at the port, over whatever the renderer asked for
  PassivityControl(model, data, device, coupling.device_ok, out);
  state_ok = Safeguard(data, coupling.device_ok, out);
  return out;
}

}  // namespace rigidtouch::render
