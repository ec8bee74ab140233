// Free rigid bodies (Eq. 1) against closed forms: kinetic energy, world-frame inertia, the
// gyroscopic torque and the semi-implicit position update.
#include "dynamics/rigid_body.h"

#include <gtest/gtest.h>

#include <cmath>

namespace rigidtouch::dynamics {
namespace {

BodyModel Brick() {
  BodyModel b;
  b.mass_kg = 2.0;
  b.inertia_kgm2 = Vec3(1.0, 2.0, 3.0);
  return b;
}

TEST(RigidBodyTest, KineticEnergyOfTranslationAndSpinAboutAPrincipalAxis) {
  const BodyModel b = Brick();
  BodyState s;
  s.q_WB = Quat(Eigen::AngleAxisd(M_PI / 2, Vec3::UnitX()));  // body y is world z
  s.v_W = Vec3(1.0, 0.0, 2.0);
  s.w_W = Vec3(0.0, 0.0, 3.0);  // about body y: I = 2
  // 1/2 2 (1 + 4) + 1/2 2 9 = 5 + 9
  EXPECT_NEAR(KineticEnergy(b, s), 14.0, 1e-12);
}

TEST(RigidBodyTest, WorldInertiaRoundTripsThroughItsInverse) {
  const BodyModel b = Brick();
  const Mat3 R = Quat(Eigen::AngleAxisd(0.7, Vec3(1.0, 2.0, -1.0).normalized())).toRotationMatrix();
  const Vec3 w(0.3, -1.2, 2.5);
  const Vec3 Iw = WorldInertiaTimes(b, R, w);
  EXPECT_TRUE(WorldInverseInertiaTimes(b, R, Iw).isApprox(w, 1e-14));
  EXPECT_TRUE((WorldInverseInertia(b, R) * Iw).isApprox(w, 1e-14));
  EXPECT_TRUE(Iw.isApprox(R * b.inertia_kgm2.asDiagonal() * R.transpose() * w, 1e-14));
}

TEST(RigidBodyTest, GyroscopicTorqueIsMinusOmegaCrossIOmega) {
  const BodyModel b = Brick();
  const Mat3 R = Mat3::Identity();
  // spin about a principal axis: no gyroscopic torque
  EXPECT_EQ(GyroscopicTorque(b, R, Vec3(0.0, 4.0, 0.0)), Vec3::Zero());
  // w = (1, 1, 0): I w = (1, 2, 0), w x I w = (0, 0, 1)
  EXPECT_TRUE(GyroscopicTorque(b, R, Vec3(1.0, 1.0, 0.0)).isApprox(Vec3(0.0, 0.0, -1.0), 1e-15));
}

TEST(RigidBodyTest, ImplicitGyroscopicStepKeepsEnergyAndMomentumOverOneStep) {
  const BodyModel b = Brick();
  const Mat3 R = Quat(Eigen::AngleAxisd(0.7, Vec3(1.0, 2.0, -1.0).normalized())).toRotationMatrix();
  const double h = 0.01;
  // spin about a principal axis: no torque
  EXPECT_LT(ImplicitGyroscopicTorque(b, R, R * Vec3(0.0, 4.0, 0.0), h).norm(), 1e-12);
  // a skew spin: w' = w + h I_W^-1 tau keeps 1/2 w.I w and |I w| to rounding (midpoint rule)
  const Vec3 w(0.3, -1.2, 2.5);
  const Vec3 next = w + h * WorldInverseInertiaTimes(b, R, ImplicitGyroscopicTorque(b, R, w, h));
  EXPECT_FALSE(next.isApprox(w, 1e-6));
  EXPECT_NEAR(next.dot(WorldInertiaTimes(b, R, next)), w.dot(WorldInertiaTimes(b, R, w)), 1e-13);
  EXPECT_NEAR(WorldInertiaTimes(b, R, next).norm(), WorldInertiaTimes(b, R, w).norm(), 1e-13);
  // to first order in h it is the explicit torque -w x I w
  const Vec3 small = ImplicitGyroscopicTorque(b, R, w, 1e-7);
  EXPECT_TRUE(small.isApprox(GyroscopicTorque(b, R, w), 1e-5));
}

TEST(RigidBodyTest, PositionUpdateIsExactForConstantVelocities) {
  BodyState s;
  s.x_W = Vec3(0.1, 0.2, 0.3);
  s.v_W = Vec3(1.0, -2.0, 0.5);
  const Vec3 axis = Vec3(1.0, 1.0, 1.0).normalized();
  s.w_W = 2.0 * axis;  // 2 rad/s
  const Quat q0 = Quat(Eigen::AngleAxisd(0.4, Vec3::UnitZ()));
  s.q_WB = q0;
  const double h = 1e-3;
  const int steps = 1000;
  for (int k = 0; k < steps; ++k) IntegratePosition(s, h);
  // x = x0 + t v and q = exp(t w) q0 at t = 1 s; tolerance: rounding over 1000 steps
  EXPECT_TRUE(s.x_W.isApprox(Vec3(1.1, -1.8, 0.8), 1e-12));
  const Quat expected = Quat(Eigen::AngleAxisd(2.0, axis)) * q0;
  EXPECT_NEAR(std::abs(s.q_WB.dot(expected)), 1.0, 1e-12);
  EXPECT_NEAR(s.q_WB.norm(), 1.0, 1e-15);
}

}  // namespace
}  // namespace rigidtouch::dynamics
