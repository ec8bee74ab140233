// Free rigid bodies (Eq. 1): world-frame inertia, kinetic energy, free-motion forces and the
// semi-implicit position update.
#pragma once

#include "rigidtouch/model.h"

namespace rigidtouch::dynamics {

/// Inertia tensor in the world frame, I_W = R diag(I) R^T  [kg m^2].
inline Mat3 WorldInertia(const BodyModel& b, const BodyState& s) {
  const Mat3 R = s.q_WB.toRotationMatrix();
  return R * b.inertia_kgm2.asDiagonal() * R.transpose();
}

/// Inverse inertia tensor in the world frame, for the body's rotation R_WB  [1/(kg m^2)].
inline Mat3 WorldInverseInertia(const BodyModel& b, const Mat3& R_WB) {
  return R_WB * b.inertia_kgm2.cwiseInverse().asDiagonal() * R_WB.transpose();
}

/// Velocity of a body point at offset r_W from the centre of mass.
inline Vec3 PointVelocity(const BodyState& s, const Vec3& r_W) {
  return s.v_W + s.w_W.cross(r_W);
}

/// Kinetic energy 1/2 m v.v + 1/2 w.I w  [J].
double KineticEnergy(const BodyModel& b, const BodyState& s);

/// I_W w = R diag(I) R^T w for the body's rotation R_WB (computed once per tick by the caller).
inline Vec3 WorldInertiaTimes(const BodyModel& b, const Mat3& R_WB, const Vec3& w) {
  return R_WB * (R_WB.transpose() * w).cwiseProduct(b.inertia_kgm2);
}

/// I_W^-1 tau = R diag(1/I) R^T tau for the body's rotation R_WB.
inline Vec3 WorldInverseInertiaTimes(const BodyModel& b, const Mat3& R_WB, const Vec3& tau) {
  return R_WB * (R_WB.transpose() * tau).cwiseQuotient(b.inertia_kgm2);
}

/// Gyroscopic torque -w x (I w) of Eq. 1's B term, for the body's rotation R_WB  [N m].
inline Vec3 GyroscopicTorque(const BodyModel& b, const Mat3& R_WB, const Vec3& w) {
  return -w.cross(WorldInertiaTimes(b, R_WB, w));
}

/// The gyroscopic part of Eq. 1 over one step h as an equivalent torque: the torque that takes the
/// world angular velocity w to w' of the implicit-midpoint step of Euler's torque-free equations
/// in the body frame, L' = L - h w_m x L_m with L = diag(I) w_B, L_m = (L + L') / 2 and
/// w_m = diag(I)^-1 L_m, solved by Newton iterations. The midpoint rule keeps every quadratic
/// invariant of those equations, so with the position update below (which turns the body about w',
/// leaving w' fixed in the body frame) the kinetic energy 1/2 w.I w and |L| carry over from step to
/// step to the solver's tolerance; the explicit term -w x I w gains energy near the intermediate
/// axis. Falls back to GyroscopicTorque if the iteration does not converge (h |w| far above 1).
/// Returns I_W (w' - w) / h  [N m].
Vec3 ImplicitGyroscopicTorque(const BodyModel& b, const Mat3& R_WB, const Vec3& w, double h);

/// Semi-implicit Euler position update with the new velocities: x += h v, q = exp(h w) q, with
/// the quaternion renormalised so it stays unit.
void IntegratePosition(BodyState& s, double h);

}  // namespace rigidtouch::dynamics
