// Torque-free rotation of a free body through the whole tick against closed forms: the kinetic
// energy and |L| of a box tumbling about its intermediate axis (Dzhanibekov) or a skew axis stay
// constant, and a symmetric top's body-frame angular velocity precesses at (I3 - I1) / I1 w3.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "rigidtouch/rigidtouch.h"
#include "test_util.h"

namespace rigidtouch {
namespace {

constexpr double kH = 1e-3;         // h [s]
constexpr int kSteps = 5000;        // 5 s
constexpr double kDriftTol = 5e-4;  // relative drift of KE and |L| over 5 s

// One free body with principal inertias I (diaginertia, inertial frame = body frame), no
// gravity, far from the floor; it is the tool, with no device (coupling none, zero user wrench).
Model FreeBody(const Vec3& I, const Vec3& w_W) {
  const std::string xml =
      "<mujoco><option timestep=\"0.001\" gravity=\"0 0 0\"/><worldbody>"
      "<geom name=\"floor\" type=\"plane\" size=\"1 1 0.1\"/>"
      "<body name=\"tool\" pos=\"0 0 1\"><freejoint/>"
      "<inertial pos=\"0 0 0\" mass=\"1\" diaginertia=\"" +
      std::to_string(I.x()) + " " + std::to_string(I.y()) + " " + std::to_string(I.z()) +
      "\"/><geom type=\"box\" size=\"0.05 0.05 0.05\" contype=\"0\" conaffinity=\"0\"/>"
      "</body></worldbody></mujoco>";
  LoadOptions options;
  options.timestep_s = kH;
  Model model = LoadModel(test::WriteTempFile("free_body.xml", xml), options);
  model.initial[0].w_W = w_W;
  return model;
}

Vec3 WorldMomentum(const Model& model, const Data& data) {
  const BodyState& s = data.bodies[0];
  const Mat3 R = s.q_WB.toRotationMatrix();
  return R * (R.transpose() * s.w_W).cwiseProduct(model.bodies[0].inertia_kgm2);
}

struct Drift {
  double energy = 0.0, momentum = 0.0, direction = 0.0;  // max relative |dKE|, |d|L||, |dL|/|L|
};

Drift Fly(const Model& model) {
  Data data = MakeData(model);
  const double ke0 = KineticEnergy(model, data);
  const Vec3 L0 = WorldMomentum(model, data);
  Drift d;
  for (int k = 0; k < kSteps; ++k) {
    Tick(model, data, TickInput{});
    const Vec3 L = WorldMomentum(model, data);
    d.energy = std::max(d.energy, std::abs(KineticEnergy(model, data) - ke0) / ke0);
    d.momentum = std::max(d.momentum, std::abs(L.norm() - L0.norm()) / L0.norm());
    d.direction = std::max(d.direction, (L - L0).norm() / L0.norm());
  }
  return d;
}

TEST(FreeRotationTest, IntermediateAxisKeepsEnergyAndMomentum) {
  // I1 < I2 < I3, spin about axis 2 with a small perturbation: it flips (Dzhanibekov) within 5 s
  const Model model = FreeBody(Vec3(1e-3, 2e-3, 3e-3), Vec3(0.01, 5.0, 0.01));
  const Drift d = Fly(model);
  RecordProperty("energy_drift", std::to_string(d.energy));
  RecordProperty("momentum_drift", std::to_string(d.momentum));
  std::printf("intermediate axis: |dKE|/KE = %.3e, |d|L||/|L| = %.3e, |dL|/|L| = %.3e\n", d.energy,
              d.momentum, d.direction);
  EXPECT_LT(d.energy, kDriftTol);
  EXPECT_LT(d.momentum, kDriftTol);
}

TEST(FreeRotationTest, SkewAxisKeepsEnergyAndMomentum) {
  const Model model = FreeBody(Vec3(1e-3, 2e-3, 3e-3), Vec3(3.0, -2.0, 4.0));
  const Drift d = Fly(model);
  std::printf("skew axis: |dKE|/KE = %.3e, |d|L||/|L| = %.3e, |dL|/|L| = %.3e\n", d.energy,
              d.momentum, d.direction);
  EXPECT_LT(d.energy, kDriftTol);
  EXPECT_LT(d.momentum, kDriftTol);
}

TEST(FreeRotationTest, SymmetricTopPrecessesAtTheClosedFormRate) {
  // I1 = I2 = 1e-3, I3 = 2e-3, w3 = 3 rad/s: Omega = (I3 - I1) / I1 w3 = 3 rad/s about body z
  const double I1 = 1e-3, I3 = 2e-3, w3 = 3.0;
  const Model model = FreeBody(Vec3(I1, I1, I3), Vec3(1.0, 0.0, w3));
  Data data = MakeData(model);
  double angle = 0.0, last = 0.0;
  for (int k = 0; k < kSteps; ++k) {
    Tick(model, data, TickInput{});
    const Vec3 w_B = data.bodies[0].q_WB.toRotationMatrix().transpose() * data.bodies[0].w_W;
    const double a = std::atan2(w_B.y(), w_B.x());
    double da = a - last;
    if (da > M_PI) da -= 2.0 * M_PI;
    if (da < -M_PI) da += 2.0 * M_PI;
    angle += da;
    last = a;
  }
  const double omega = (I3 - I1) / I1 * w3;
  const double measured = angle / (kSteps * kH);
  std::printf("symmetric top: precession %.6f rad/s, closed form %.6f rad/s\n", measured, omega);
  EXPECT_NEAR(measured, omega, 0.01 * omega);
}

}  // namespace
}  // namespace rigidtouch
