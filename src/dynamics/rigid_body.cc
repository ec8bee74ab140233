#include "dynamics/rigid_body.h"

#include <cmath>

#include <Eigen/LU>

namespace rigidtouch::dynamics {
namespace {

constexpr int kGyroscopicNewtonIterations = 8;

Mat3 Skew(const Vec3& v) {
  Mat3 S;
  S << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
  return S;
}

}  // namespace

double KineticEnergy(const BodyModel& b, const BodyState& s) {
  return 0.5 * b.mass_kg * s.v_W.squaredNorm() + 0.5 * s.w_W.dot(WorldInertia(b, s) * s.w_W);
}

Vec3 ImplicitGyroscopicTorque(const BodyModel& b, const Mat3& R_WB, const Vec3& w, double h) {
  const Vec3& I = b.inertia_kgm2;
  const Vec3 L = (R_WB.transpose() * w).cwiseProduct(I);  // body-frame angular momentum
  const double scale = L.norm();
  if (!(scale > 0.0)) return Vec3::Zero();
  // unknown: the midpoint momentum x = (L + L') / 2; residual F(x) = 2 x - 2 L + h (I^-1 x) x x
  Vec3 x = L;
  bool converged = false;
  for (int it = 0; it < kGyroscopicNewtonIterations; ++it) {
    const Vec3 wm = x.cwiseQuotient(I);
    const Vec3 F = 2.0 * (x - L) + h * wm.cross(x);
    if (F.norm() <= 1e-14 * scale) {
      converged = true;
      break;
    }
    // dF/dx = 2 1 + h ([w_m]x - [x]x diag(I)^-1)
    Mat3 J = h * (Skew(wm) - Skew(x) * I.cwiseInverse().asDiagonal());
    J.diagonal().array() += 2.0;
    x -= J.partialPivLu().solve(F);
  }
  if (!converged || !x.allFinite()) return GyroscopicTorque(b, R_WB, w);
  const Vec3 L_next = 2.0 * x - L;
  // I_W (w' - w) / h = R (L' - L) / h
  return R_WB * (L_next - L) / h;
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
