// Dry joint friction (frictionloss, dynamics::TreeFrictionImpulse) and the ball joint's spring:
// closed forms for a slide held or sliding under gravity, a hinge braking to a stop, a double
// pendulum held in a tilted pose, a ball joint's oscillation period, and the ball spring's torque
// against MuJoCo 2.2.2's qfrc_passive.
#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include "dynamics/tree.h"
#include "io/mjcf_tree.h"
#include "limit_malloc.h"

namespace rigidtouch::dynamics::friction_test {
namespace {

constexpr double kG = 9.81;

// a block of mass m on a vertical slide (axis z) under gravity -g z, with dry friction f
TreeModel VerticalSlide(double m_kg, double f_N) {
  TreeBody b;
  b.mass_kg = m_kg;
  b.inertia_kgm2 = Mat3::Identity() * 0.01;
  TreeJoint j;
  j.type = JointType::kSlide;
  j.axis = Vec3::UnitZ();
  j.frictionloss = f_N;
  b.joints = {j};
  return MakeTree({b}, Vec3(0, 0, -kG));
}

// weight m g = 19.62 N against f = 25 N: the block never moves
TEST(TreeFrictionTest, SlideHeldWhenFrictionExceedsTheWeight) {
  const double m_kg = 2.0, f_N = 25.0, h_s = 1e-3;
  const TreeModel model = VerticalSlide(m_kg, f_N);
  TreeData data = MakeTreeData(model);
  const Eigen::VectorXd tau = Eigen::VectorXd::Zero(1);
  for (int k = 0; k < 2000; ++k) {
    ASSERT_TRUE(TreeStep(model, data, h_s, tau));
    // the friction impulse holds the weight's impulse exactly: lambda = m g h < f h
    ASSERT_NEAR(data.friction_lambda[0], m_kg * kG * h_s, 1e-15);
    ASSERT_EQ(data.qvel[0], 0.0) << "step " << k;  // sticking: exactly zero
  }
  EXPECT_EQ(data.qpos[0], 0.0);
}

// weight 19.62 N against f = 10 N: the block slides down at (m g - f) / m from rest
TEST(TreeFrictionTest, SlideAcceleratesAtWeightMinusFrictionOverMass) {
  const double m_kg = 2.0, f_N = 10.0, h_s = 1e-3;
  const TreeModel model = VerticalSlide(m_kg, f_N);
  TreeData data = MakeTreeData(model);
  const Eigen::VectorXd tau = Eigen::VectorXd::Zero(1);
  const double a = (m_kg * kG - f_N) / m_kg;
  const int n = 1000;
  double z_m = 0.0;  // semi-implicit Euler: z_n = h sum_k v_k = -a h^2 n (n + 1) / 2
  for (int k = 1; k <= n; ++k) {
    ASSERT_TRUE(TreeStep(model, data, h_s, tau));
    ASSERT_NEAR(data.qvel[0], -a * h_s * k, 1e-9 * a * h_s * k) << "step " << k;
    ASSERT_DOUBLE_EQ(data.friction_lambda[0], f_N * h_s);  // sliding: the full bound, upwards
  }
  z_m = -a * h_s * h_s * n * (n + 1) / 2.0;
  EXPECT_NEAR(data.qpos[0], z_m, 1e-9 * std::abs(z_m));
}

// a disc spinning on a vertical hinge (gravity along the axis: no torque) with dry friction f
// brakes at f / I, stops, and stays stopped
TEST(TreeFrictionTest, HingeBrakesAtFrictionOverInertiaAndStaysStopped) {
  const double m_kg = 1.5, r_m = 0.2, f_Nm = 0.3, armature = 0.01, h_s = 1e-3, w0 = 2.0;
  TreeBody b;
  b.mass_kg = m_kg;
  b.inertia_kgm2 =
      Vec3(m_kg * r_m * r_m / 4, m_kg * r_m * r_m / 4, m_kg * r_m * r_m / 2).asDiagonal();
  TreeJoint j;
  j.axis = Vec3::UnitZ();
  j.frictionloss = f_Nm;
  j.armature = armature;
  b.joints = {j};
  const TreeModel model = MakeTree({b}, Vec3(0, 0, -kG));
  TreeData data = MakeTreeData(model);
  data.qvel[0] = w0;
  const double I = m_kg * r_m * r_m / 2 + armature;
  const double alpha = f_Nm / I;  // the deceleration
  const Eigen::VectorXd tau = Eigen::VectorXd::Zero(1);
  const int stop = static_cast<int>(std::floor(w0 / (alpha * h_s)));  // last step still sliding
  for (int k = 1; k <= stop; ++k) {
    ASSERT_TRUE(TreeStep(model, data, h_s, tau));
    ASSERT_NEAR(data.qvel[0], w0 - alpha * h_s * k, 1e-9 * w0) << "step " << k;
  }
  const double theta_stop = data.qpos[0];
  // the continuous stopping angle w0^2 / (2 alpha), to one step's travel
  EXPECT_NEAR(theta_stop, w0 * w0 / (2 * alpha), w0 * h_s);
  for (int k = 0; k < 1000; ++k) {
    ASSERT_TRUE(TreeStep(model, data, h_s, tau));
    // the first step brakes the remainder w < alpha h inside the bound: stuck from there on
    ASSERT_EQ(data.qvel[0], 0.0) << "step " << k;
  }
  EXPECT_NEAR(data.qpos[0], theta_stop, w0 * h_s);
}

// Two rods hinged about y, tilted by 0.3 and -0.2 rad from hanging: gravity's static torques are
// the bias forces at rest; friction above both holds the pose exactly, friction below the
// outer joint's lets it fall while the inner one holds.
TreeModel FrictionDoublePendulum(double f0, double f1) {
  std::vector<TreeBody> bodies(2);
  for (int i = 0; i < 2; ++i) {
    TreeBody& b = bodies[i];
    b.parent = i - 1;
    b.pos_m = i == 0 ? Vec3::Zero() : Vec3(0, 0, -0.4);
    b.mass_kg = i == 0 ? 1.0 : 0.7;
    b.com_m = Vec3(0, 0, -0.2);
    b.inertia_kgm2 = Vec3(0.01, 0.01, 1e-4).asDiagonal();
    TreeJoint j;
    j.axis = Vec3::UnitY();
    j.frictionloss = i == 0 ? f0 : f1;
    b.joints = {j};
  }
  return MakeTree(bodies, Vec3(0, 0, -kG));
}

Eigen::VectorXd StaticTorques(const TreeModel& model, const Eigen::Vector2d& q) {
  TreeData data = MakeTreeData(model);
  data.qpos = q;
  TreeKinematics(model, data);
  TreeBiasForces(model, data);
  return data.bias;  // at zero velocity: gravity's generalized force, negated
}

TEST(TreeFrictionTest, CoupledJointsHeldWhenFrictionExceedsTheirStaticTorques) {
  const Eigen::Vector2d q0(0.3, -0.2);
  const Eigen::VectorXd g = StaticTorques(FrictionDoublePendulum(1, 1), q0);
  const double h_s = 1e-3;
  const TreeModel model =
      FrictionDoublePendulum(1.05 * std::abs(g[0]) + 0.05, 1.05 * std::abs(g[1]) + 0.05);
  TreeData data = MakeTreeData(model);
  data.qpos = q0;
  const Eigen::VectorXd tau = Eigen::VectorXd::Zero(2);
  for (int k = 0; k < 2000; ++k) {
    ASSERT_TRUE(TreeStep(model, data, h_s, tau));
    ASSERT_LT(data.friction_sweeps, kFrictionMaxSweeps);  // converged
    ASSERT_EQ(data.qvel[0], 0.0);
    ASSERT_EQ(data.qvel[1], 0.0);
  }
  EXPECT_EQ(data.qpos[0], q0[0]);
  EXPECT_EQ(data.qpos[1], q0[1]);
  // the impulses balance gravity's over each step: lambda = h g (the static torques)
  EXPECT_NEAR(data.friction_lambda[0], h_s * g[0], 1e-12);
  EXPECT_NEAR(data.friction_lambda[1], h_s * g[1], 1e-12);
  std::printf("held double pendulum: static torques %.4g, %.4g N m, %d sweeps\n", g[0], g[1],
              data.friction_sweeps);
}

TEST(TreeFrictionTest, OuterJointSlipsWhenItsFrictionIsBelowItsStaticTorque) {
  const Eigen::Vector2d q0(0.3, -0.2);
  const Eigen::VectorXd g = StaticTorques(FrictionDoublePendulum(1, 1), q0);
  const TreeModel model = FrictionDoublePendulum(10.0, 0.5 * std::abs(g[1]));
  TreeData data = MakeTreeData(model);
  data.qpos = q0;
  const Eigen::VectorXd tau = Eigen::VectorXd::Zero(2);
  for (int k = 0; k < 100; ++k) {
    ASSERT_TRUE(TreeStep(model, data, 1e-3, tau));
    ASSERT_EQ(data.qvel[0], 0.0);  // 10 N m holds the inner joint against the swinging rod
  }
  // the outer rod (at 0.3 - 0.2 = 0.1 rad from hanging) swings back towards hanging
  EXPECT_LT(data.qpos[1], q0[1] - 1e-3);
  EXPECT_EQ(data.qpos[0], q0[0]);
}

TEST(TreeFrictionTest, FrictionStepDoesNotAllocate) {
  if (!test::kMallocCounting) GTEST_SKIP() << "allocations are not counted under sanitizers";
  const TreeModel model = FrictionDoublePendulum(0.5, 0.2);
  TreeData data = MakeTreeData(model);
  data.qvel << 0.3, -0.2;
  const Eigen::VectorXd tau = Eigen::VectorXd::Zero(2);
  test::LimitMalloc guard;
  for (int k = 0; k < 10; ++k) ASSERT_TRUE(TreeStep(model, data, 1e-3, tau));
  EXPECT_EQ(guard.allocations(), 0);
}

TEST(TreeFrictionTest, NegativeFrictionlossIsRefused) {
  EXPECT_THROW(VerticalSlide(1.0, -1.0), Error);
}

// ---- the ball joint's spring ----

// a sphere (inertia I about every axis through its centre) on a ball joint at its centre, no
// gravity: the spring torque -k r about the rotation's fixed axis gives theta'' = -(k / I) theta
// exactly (not only for small angles), period 2 pi sqrt(I / k)
TEST(TreeFrictionTest, BallSpringOscillatesWithPeriodTwoPiSqrtInertiaOverStiffness) {
  const double m_kg = 2.0, r_m = 0.1, k = 3.0, h_s = 1e-4, theta0 = 0.05;
  const double I = 0.4 * m_kg * r_m * r_m;
  TreeBody b;
  b.mass_kg = m_kg;
  b.inertia_kgm2 = Mat3::Identity() * I;
  TreeJoint j;
  j.type = JointType::kBall;
  j.stiffness = k;
  b.joints = {j};
  const TreeModel model = MakeTree({b}, Vec3::Zero());
  TreeData data = MakeTreeData(model);
  const Vec3 axis = Vec3(1, 2, -0.5).normalized();
  const Quat q0(Eigen::AngleAxisd(theta0, axis));
  data.qpos << q0.w(), q0.x(), q0.y(), q0.z();
  TreeKinematics(model, data);
  const double E0 = TreePotentialEnergy(model, data);
  EXPECT_NEAR(E0, 0.5 * k * theta0 * theta0, 1e-15);
  const double period_s = 2 * std::numbers::pi * std::sqrt(I / k);
  const Eigen::VectorXd tau = Eigen::VectorXd::Zero(3);
  std::vector<double> crossings_s;  // upward zero crossings of the angle along the axis
  double prev = theta0;
  for (int n = 0; n < static_cast<int>(4.5 * period_s / h_s); ++n) {
    ASSERT_TRUE(TreeStep(model, data, h_s, tau));
    const Quat q(data.qpos[0], data.qpos[1], data.qpos[2], data.qpos[3]);
    const double angle = 2.0 * std::atan2(q.vec().dot(axis), q.w());
    if (prev < 0.0 && angle >= 0.0) crossings_s.push_back((n + prev / (prev - angle)) * h_s);
    prev = angle;
    // the rotation stays about the axis: the spring's torque is along it
    ASSERT_LT((q.vec() - q.vec().dot(axis) * axis).norm(), 1e-12);
  }
  ASSERT_GE(crossings_s.size(), 3u);
  const double measured_s = (crossings_s.back() - crossings_s.front()) / (crossings_s.size() - 1.0);
  EXPECT_NEAR(measured_s, period_s, 1e-3 * period_s) << "measured " << measured_s;
  std::printf("ball spring period error %.3g (bound 1e-3)\n", measured_s / period_s - 1.0);
}

mjModel* CompileBallXml(const std::string& xml) {
  auto vfs = std::make_unique<mjVFS>();
  mj_defaultVFS(vfs.get());
  mj_makeEmptyFileVFS(vfs.get(), "ball.xml", static_cast<int>(xml.size()));
  std::memcpy(vfs->filedata[mj_findFileVFS(vfs.get(), "ball.xml")], xml.data(), xml.size());
  char error[1000] = "";
  mjModel* m = mj_loadXML("ball.xml", vfs.get(), error, sizeof(error));
  mj_deleteVFS(vfs.get());
  if (m == nullptr) throw std::runtime_error(error);
  return m;
}

// the spring torque at rotations up to and past pi (where the rotation vector flips to the
// shorter way round), with a springref pose given by the body's own offset (MuJoCo's qpos_spring
// of a ball is identity: the spring is relaxed at the body's pose in the file)
TEST(TreeFrictionTest, BallSpringTorqueEqualsMujocosPassiveForce) {
  mjModel* m = CompileBallXml(
      "<mujoco><worldbody><body name=\"a\" quat=\"0.9 0.1 0.3 0.2\"><joint type=\"ball\" "
      "stiffness=\"2.5\" damping=\"0.4\"/><geom type=\"box\" size=\"0.1 0.2 0.3\" pos=\"0.1 0 "
      "0\"/><body pos=\"0 0 -0.5\"><joint type=\"ball\" stiffness=\"1.5\"/><geom type=\"sphere\" "
      "size=\"0.1\"/></body></body></worldbody></mujoco>");
  const TreeModel model = io::TreeFromMjModel(m);
  TreeData data = MakeTreeData(model);
  mjData* d = mj_makeData(m);
  double worst = 0.0;
  for (const double angle : {0.01, 0.7, 2.5, 3.1, 3.2, 4.0, 6.0}) {
    const Quat q1(Eigen::AngleAxisd(angle, Vec3(0.3, -1, 0.4).normalized()));
    const Quat q2(Eigen::AngleAxisd(0.5 * angle, Vec3(1, 0.2, 0).normalized()));
    const double qpos[8] = {q1.w(), q1.x(), q1.y(), q1.z(), q2.w(), q2.x(), q2.y(), q2.z()};
    for (int i = 0; i < 8; ++i) d->qpos[i] = data.qpos[i] = qpos[i];
    for (int i = 0; i < 6; ++i) d->qvel[i] = data.qvel[i] = 0.1 * (i + 1) - 0.25;
    mj_forward(m, d);
    TreePassiveForces(model, data);
    for (int i = 0; i < 6; ++i) {
      worst = std::max(worst, std::abs(data.passive[i] - d->qfrc_passive[i]) /
                                  std::max(1.0, std::abs(d->qfrc_passive[i])));
    }
  }
  EXPECT_LT(worst, 1e-12);
  mj_deleteData(d);
  mj_deleteModel(m);
}

}  // namespace
}  // namespace rigidtouch::dynamics::friction_test
