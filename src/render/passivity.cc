#include "render/passivity.h"

#include <algorithm>
#include <cmath>

#include "render/output.h"

namespace rigidtouch::render {

double MaxControlDamping(const Model& model) {
  const double by_mass = model.bodies[model.tool].mass_kg / model.timestep_s;
  const double device = model.device.limits.max_damping_Ns_per_m;
  return device > 0.0 ? std::min(device, by_mass) : by_mass;
}

void PassivityControl(const Model& model, Data& data, const DeviceState& device, bool device_ok,
                      DeviceCommand& out) {
  if (!model.render.passivity_control || model.device.coupling == Coupling::kNone) return;
  PassivityState& p = data.passivity;
  p.step_dissipated_J = 0.0;
  p.damping_Ns_per_m = 0.0;
  if (!device_ok || !out.force_N.allFinite() || !device.position_m.allFinite() ||
      !device.velocity_mps.allFinite()) {
    p.observed_J = 0.0;
    p.has_last = false;
    return;
  }
  const Vec3& x = device.position_m;
  const Vec3& v = device.velocity_mps;
  if (p.has_last) {
    const Vec3 dx = x - p.last_position_m;
    if (p.last_force_N.squaredNorm() == 0.0) {  // a new contact
      p.observed_J = 0.0;
      p.force_variation_N = 0.0;
    }
    p.observed_J -= p.last_force_N.dot(dx);
    p.step_dissipated_J = -p.last_control_force_N.dot(dx);
    p.dissipated_J += p.step_dissipated_J;
  }
  const double h = model.timestep_s;
  const double v2 = v.squaredNorm();
  // the observer's error: positions quantized to q per axis (|e| <= sqrt(3) q / 2) make the
  // observed sum -F_k . (x_(k+1) - x_k) differ from the true one by at most
  // |e| (sum_k |F_k - F_(k-1)| + |F_n|) (summation by parts, F = 0 before the contact): keep that
  // much in reserve
  const double e_max = 0.5 * std::sqrt(3.0) * model.device.position_resolution_m;
  const double reserve_J =
      e_max * (p.force_variation_N + (out.force_N - p.last_force_N).norm() + out.force_N.norm());
  const double predicted_J = p.observed_J - out.force_N.dot(v) * h - reserve_J;
  p.last_control_force_N.setZero();
  if (predicted_J < 0.0 && v2 > kPassivityMinSpeed_mps * kPassivityMinSpeed_mps) {
    // alpha |v|^2 h = -E_pred: the damping that dissipates this tick what the port is short of
    p.damping_Ns_per_m = std::min(-predicted_J / (h * v2), MaxControlDamping(model));
    const Vec3 before = out.force_N;
    out.force_N -= p.damping_Ns_per_m * v;
    if (LimitForce(model.device.limits.max_force_N, out.force_N, out.torque_Nm)) {
      out.clipped = true;
      data.Warn(Warning::kForceClipped);
    }
    p.last_control_force_N = out.force_N - before;
  }
  p.force_variation_N += (out.force_N - p.last_force_N).norm();
  p.last_force_N = out.force_N;
  p.last_position_m = x;
  p.has_last = true;
}

}  // namespace rigidtouch::render
