#include "dynamics/rigid_body.h"

#include <cmath>

namespace rigidtouch::dynamics {

double KineticEnergy(const BodyModel& b, const BodyState& s) {
  return 0.5 * b.mass_kg * s.v_W.squaredNorm() + 0.5 * s.w_W.dot(WorldInertia(b, s) * s.w_W);
}

void IntegratePosition(BodyState& s, double h) {
  s.x_W += h * s.v_W;
  const double angle = s.w_W.norm() * h;
  if (angle > 0.0) {
    const Quat dq(Eigen::AngleAxisd(angle, s.w_W / s.w_W.norm()));
    s.q_WB = dq * s.q_WB;
  }
  s.q_WB.normalize();
}

}  // namespace rigidtouch::dynamics
