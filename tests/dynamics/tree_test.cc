// Kinematic trees in joint space (src/dynamics/tree.h): closed forms for a door, a slide, a
// pendulum and a double pendulum; static torques against J^T f; and the mass matrix, bias forces
// and point Jacobians against MuJoCo 2.2.2 on trees written here (src/io/mjcf_tree.h reads them).
#include "dynamics/tree.h"

#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "io/mjcf_tree.h"
#include "limit_malloc.h"

namespace rigidtouch::dynamics {
namespace {

constexpr double kPi = 3.14159265358979323846;

Mat3 BoxInertia(double m, const Vec3& size_m) {
  const Vec3 s2 = size_m.cwiseProduct(size_m);
  return (m / 12.0 * Vec3(s2.y() + s2.z(), s2.x() + s2.z(), s2.x() + s2.y())).asDiagonal();
}

// max |a - b| over max |b|: the error relative to the reference's scale
double RelErr(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return (a - b).cwiseAbs().maxCoeff() / std::max(b.cwiseAbs().maxCoeff(), 1e-300);
}

// A door: a plate of width w (x), height (z) and thickness t hinged about its edge on the z axis.
struct Door {
  double m_kg = 20.0, w_m = 0.8, height_m = 2.0, t_m = 0.04, armature = 0.0;
  double HingeInertia() const { return m_kg * w_m * w_m / 3.0 + m_kg * t_m * t_m / 12.0; }
  TreeModel Model() const {
    TreeBody b;
    b.mass_kg = m_kg;
    b.com_m = Vec3(w_m / 2, 0, 0);
    b.inertia_kgm2 = BoxInertia(m_kg, Vec3(w_m, t_m, height_m));
    TreeJoint j;
    j.axis = Vec3::UnitZ();
    j.armature = armature;
    b.joints = {j};
    return MakeTree({b}, Vec3(0, 0, -9.81));
  }
};

TEST(TreeTest, DoorMassMatrixAndPointJacobian) {
  Door door;
  door.armature = 0.25;
  const TreeModel model = door.Model();
  TreeData data = MakeTreeData(model);
  const double theta = 0.7, r = 0.6, z = 0.3;
  data.qpos[0] = theta;
  TreeKinematics(model, data);
  TreeMassMatrix(model, data);
  // I = m w^2/3 + m t^2/12 about the edge, plus the armature; rounding only: 1e-12 relative
  EXPECT_NEAR(data.M(0, 0), door.HingeInertia() + door.armature, 1e-12 * data.M(0, 0));
  const Vec3 p_W(r * std::cos(theta), r * std::sin(theta), z);
  Eigen::MatrixXd Jt(3, 1), Jr(3, 1);
  TreePointJacobian(model, data, 0, p_W, Jt, Jr);
  // the point moves on a circle of radius r: dp/dq = r (-sin, cos, 0); rounding: 1e-14 m
  EXPECT_LT((Jt.col(0) - r * Vec3(-std::sin(theta), std::cos(theta), 0)).norm(), 1e-14);
  EXPECT_LT((Jr.col(0) - Vec3::UnitZ()).norm(), 1e-15);
}

TEST(TreeTest, DoorTapEffectiveInverseMassAndPlasticCommonSpeed) {
  const Door door;
  const TreeModel model = door.Model();
  TreeData data = MakeTreeData(model);
  const double theta = -0.4, r_m = 0.55, m_tap_kg = 0.3, v_mps = 0.2;
  data.qpos[0] = theta;
  TreeKinematics(model, data);
  TreeMassMatrix(model, data);
  ASSERT_TRUE(TreeFactor(model, data, 0.0));
  const Vec3 n(-std::sin(theta), std::cos(theta), 0);  // the door's normal at the tap
  Eigen::MatrixXd Jt(3, 1), Jr(3, 1), W(1, 1);
  TreePointJacobian(model, data, 0, r_m * Vec3(std::cos(theta), std::sin(theta), 1.0), Jt, Jr);
  const Eigen::MatrixXd Jn = n.transpose() * Jt;
  TreeEffectiveInverseMass(data, Jn, W);
  const double I = door.HingeInertia();
  // 1 / m_eff = r^2 / I; the tests' bound 1e-9 relative (measured ~1e-16)
  EXPECT_NEAR(W(0, 0), r_m * r_m / I, 1e-9 * r_m * r_m / I);
  // plastic tap (Eq. 5, e = 0): p = v / (1/m_t + J M^-1 J^T); common speed = p J M^-1 J^T
  const double p = v_mps / (1.0 / m_tap_kg + W(0, 0));
  const double common = p * W(0, 0);
  const double closed = m_tap_kg * v_mps / (m_tap_kg + I / (r_m * r_m));
  EXPECT_NEAR(common, closed, 1e-9 * closed);
  EXPECT_NEAR(v_mps - p / m_tap_kg, closed, 1e-9 * closed);
}

TEST(TreeTest, SlideEffectiveInverseMassIsOneOverMass) {
  TreeBody b;
  b.mass_kg = 2.5;
  b.com_m = Vec3(0.1, -0.2, 0.05);
  b.inertia_kgm2 = BoxInertia(b.mass_kg, Vec3(0.1, 0.2, 0.3));
  b.quat = Quat(Eigen::AngleAxisd(0.4, Vec3(1, 2, 3).normalized()));
  TreeJoint j;
  j.type = JointType::kSlide;
  j.axis = Vec3(0.3, -0.5, 0.8).normalized();
  b.joints = {j};
  const TreeModel model = MakeTree({b}, Vec3(0, 0, -9.81));
  TreeData data = MakeTreeData(model);
  data.qpos[0] = 0.37;
  TreeKinematics(model, data);
  TreeMassMatrix(model, data);
  ASSERT_TRUE(TreeFactor(model, data, 0.0));
  Eigen::MatrixXd Jt(3, 1), Jr(3, 1), W(3, 3);
  TreePointJacobian(model, data, 0, Vec3(0.3, 0.2, 0.1), Jt, Jr);
  TreeEffectiveInverseMass(data, Jt, W);
  const Vec3 a_W = data.R_WB[0] * j.axis;
  // J M^-1 J^T = a a^T / m: 1/m along the axis, nothing across; rounding: 1e-14 relative
  EXPECT_LT(RelErr(W, a_W * a_W.transpose() / b.mass_kg), 1e-14);
  EXPECT_NEAR(a_W.dot(W * a_W), 1.0 / b.mass_kg, 1e-14 / b.mass_kg);
  EXPECT_LT(Jr.norm(), 1e-300);
}

// A pendulum: a small sphere of mass m (radius 1 cm) on a massless rod of length L about x.
TreeModel Pendulum(double L_m, double m_kg) {
  TreeBody b;
  b.mass_kg = m_kg;
  b.com_m = Vec3(0, 0, -L_m);
  b.inertia_kgm2 = (0.4 * m_kg * 1e-4) * Mat3::Identity();
  TreeJoint j;
  j.axis = Vec3::UnitX();
  b.joints = {j};
  return MakeTree({b}, Vec3(0, 0, -9.81));
}

TEST(TreeTest, PendulumSmallAnglePeriodFromTheStep) {
  const double L_m = 0.5, m_kg = 1.3, h_s = 1e-4;
  const TreeModel model = Pendulum(L_m, m_kg);
  TreeData data = MakeTreeData(model);
  data.qpos[0] = 0.01;
  const double I = m_kg * L_m * L_m + 0.4 * m_kg * 1e-4;
  const double period_s = 2 * kPi * std::sqrt(I / (m_kg * 9.81 * L_m));
  const Eigen::VectorXd tau = Eigen::VectorXd::Zero(1);
  std::vector<double> crossings_s;  // upward zero crossings, linearly interpolated
  for (int k = 0; k < static_cast<int>(5 * period_s / h_s); ++k) {
    const double q0 = data.qpos[0];
    ASSERT_TRUE(TreeStep(model, data, h_s, tau));
    if (q0 < 0.0 && data.qpos[0] >= 0.0) {
      crossings_s.push_back((k + q0 / (q0 - data.qpos[0])) * h_s);
    }
  }
  ASSERT_GE(crossings_s.size(), 3u);
  const double measured_s = (crossings_s.back() - crossings_s.front()) / (crossings_s.size() - 1.0);
  // 0.5 % bound of the brief; the amplitude's own correction is theta0^2/16 = 6e-6
  EXPECT_NEAR(measured_s, period_s, 0.005 * period_s) << "measured " << measured_s;
  std::printf("pendulum period error %.3g (bound 5e-3)\n", measured_s / period_s - 1.0);
}

// Two uniform rods hinged about y, hanging along -z, the second at the end of the first.
TreeModel DoublePendulum() {
  std::vector<TreeBody> bodies(2);
  for (int i = 0; i < 2; ++i) {
    TreeBody& b = bodies[i];
    b.parent = i - 1;
    b.pos_m = i == 0 ? Vec3::Zero() : Vec3(0, 0, -0.4);
    b.mass_kg = i == 0 ? 1.0 : 0.7;
    b.com_m = Vec3(0, 0, -0.2);
    b.inertia_kgm2 = BoxInertia(b.mass_kg, Vec3(0.02, 0.02, 0.4));
    TreeJoint j;
    j.axis = Vec3::UnitY();
    b.joints = {j};
  }
  return MakeTree(bodies, Vec3(0, 0, -9.81));
}

TEST(TreeTest, DoublePendulumFromRestConservesEnergy) {
  const TreeModel model = DoublePendulum();
  TreeData data = MakeTreeData(model);
  TreeKinematics(model, data);
  const double U_rest_J = TreePotentialEnergy(model, data);  // hanging at rest
  data.qpos << 1.2, -0.8;
  TreeKinematics(model, data);
  TreeMassMatrix(model, data);
  const double E0_J = TreePotentialEnergy(model, data) + TreeKineticEnergy(data);
  // semi-implicit Euler's energy error is first order in h: 2.5e-3 of it at h = 1e-4 s (the
  // haptic rate), 6e-4 at 2.5e-5 s
  const double h_s = 2.5e-5;
  const Eigen::VectorXd tau = Eigen::VectorXd::Zero(2);
  double worst = 0.0;
  for (int k = 0; k < static_cast<int>(5.0 / h_s); ++k) {
    ASSERT_TRUE(TreeStep(model, data, h_s, tau));
    TreeKinematics(model, data);
    TreeMassMatrix(model, data);
    const double E_J = TreePotentialEnergy(model, data) + TreeKineticEnergy(data);
    worst = std::max(worst, std::abs(E_J - E0_J));
  }
  // 0.1 % of the energy the motion has (above the hanging rest), the brief's bound
  EXPECT_LT(worst / (E0_J - U_rest_J), 1e-3);
  std::printf("double pendulum energy error %.3g (bound 1e-3)\n", worst / (E0_J - U_rest_J));
}

// A chain of three hinges with tilted axes and offsets.
TreeModel TiltedChain() {
  std::vector<TreeBody> bodies(3);
  const Vec3 axes[3] = {Vec3(0.2, 0.3, 1), Vec3(1, -0.4, 0.1), Vec3(0.1, 1, 0.5)};
  for (int i = 0; i < 3; ++i) {
    TreeBody& b = bodies[i];
    b.parent = i - 1;
    b.pos_m = i == 0 ? Vec3(0.1, 0, 0.5) : Vec3(0.3, 0.05, -0.1);
    b.quat = Quat(Eigen::AngleAxisd(0.3 * (i + 1), Vec3(1, 1, 0).normalized()));
    b.mass_kg = 1.0 + 0.5 * i;
    b.com_m = Vec3(0.15, 0.02 * i, -0.03);
    b.inertia_kgm2 = BoxInertia(b.mass_kg, Vec3(0.3, 0.05, 0.04 + 0.01 * i));
    TreeJoint j;
    j.axis = axes[i].normalized();
    j.pos_m = Vec3(0.01, -0.02, 0.03);
    b.joints = {j};
  }
  return MakeTree(bodies, Vec3(0.5, -0.3, -9.81));
}

TEST(TreeTest, StaticTorquesAreJacobianTransposeOfTheLinksWeights) {
  const TreeModel model = TiltedChain();
  TreeData data = MakeTreeData(model);
  data.qpos << 0.4, -1.1, 2.0;  // at rest: qvel = 0
  TreeKinematics(model, data);
  TreeBiasForces(model, data);
  // the torques holding the chain against its weights m_i g applied at the centres of mass:
  // bias = -sum_i J_i(com_i)^T m_i g
  Eigen::VectorXd expected = Eigen::VectorXd::Zero(3);
  Eigen::MatrixXd Jt(3, 3), Jr(3, 3);
  for (int i = 0; i < 3; ++i) {
    TreePointJacobian(model, data, i, data.com_W[i], Jt, Jr);
    expected -= Jt.transpose() * (model.bodies[i].mass_kg * model.gravity_mps2);
  }
  // rounding only: 1e-12 relative
  EXPECT_LT(RelErr(data.bias, expected), 1e-12) << data.bias.transpose();
}

TEST(TreeTest, PerTickFunctionsDoNotAllocate) {
  if (!test::kMallocCounting) GTEST_SKIP() << "allocations are not counted under sanitizers";
  const TreeModel model = TiltedChain();
  TreeData data = MakeTreeData(model);
  data.qvel << 0.3, -0.2, 0.5;
  Eigen::MatrixXd Jt(3, 3), Jr(3, 3), W(3, 3);
  const Eigen::VectorXd tau = Eigen::VectorXd::Constant(3, 0.1);
  double sink = 0.0;
  test::LimitMalloc guard;
  TreeKinematics(model, data);
  TreeMassMatrix(model, data);
  TreeBiasForces(model, data);
  TreePassiveForces(model, data);
  TreePointJacobian(model, data, 2, data.com_W[2], Jt, Jr);
  ASSERT_TRUE(TreeFactor(model, data, 1e-3));
  TreeEffectiveInverseMass(data, Jt, W);
  ASSERT_TRUE(TreeStep(model, data, 1e-3, tau));
  sink += TreeKineticEnergy(data) + TreePotentialEnergy(model, data);
  EXPECT_EQ(guard.allocations(), 0);
  EXPECT_TRUE(std::isfinite(sink));
}

// ---- against MuJoCo 2.2.2 ----

mjModel* CompileXml(const std::string& xml) {
  auto vfs = std::make_unique<mjVFS>();
  mj_defaultVFS(vfs.get());
  mj_makeEmptyFileVFS(vfs.get(), "tree.xml", static_cast<int>(xml.size()));
  std::memcpy(vfs->filedata[mj_findFileVFS(vfs.get(), "tree.xml")], xml.data(), xml.size());
  char error[1000] = "";
  mjModel* m = mj_loadXML("tree.xml", vfs.get(), error, sizeof(error));
  mj_deleteVFS(vfs.get());
  if (m == nullptr) throw std::runtime_error(error);
  return m;
}

// Random coordinates: hinges in [-pi, pi], slides in [-0.3, 0.3] m, unit quaternions, free
// positions in [-1, 1] m; velocities normal with sigma 2.
void RandomState(const mjModel* m, std::mt19937_64& rng, double* qpos, double* qvel) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int j = 0; j < m->njnt; ++j) {
    double* q = qpos + m->jnt_qposadr[j];
    int quat = 0;
    if (m->jnt_type[j] == mjJNT_FREE) {
      for (int k = 0; k < 3; ++k) q[k] = u(rng);
      quat = 3;
    } else if (m->jnt_type[j] == mjJNT_HINGE) {
      q[0] = kPi * u(rng);
      continue;
    } else if (m->jnt_type[j] == mjJNT_SLIDE) {
      q[0] = 0.3 * u(rng);
      continue;
    }
    Eigen::Vector4d v(n(rng), n(rng), n(rng), n(rng));
    v.normalize();
    for (int k = 0; k < 4; ++k) q[quat + k] = v[k];
  }
  for (int i = 0; i < m->nv; ++i) qvel[i] = 2.0 * n(rng);
}

// Worst relative errors of the mass matrix, bias and Jacobians over several random states.
struct Errors {
  double M = 0, bias = 0, jac = 0;
};

Errors CompareWithMujoco(const std::string& xml, int states) {
  mjModel* m = CompileXml(xml);
  mjData* d = mj_makeData(m);
  const TreeModel model = io::TreeFromMjModel(m);
  TreeData data = MakeTreeData(model);
  EXPECT_EQ(model.nq, m->nq);
  EXPECT_EQ(model.nv, m->nv);
  EXPECT_LT((model.qpos0 - Eigen::Map<Eigen::VectorXd>(m->qpos0, m->nq)).norm(), 1e-12);
  std::mt19937_64 rng(45);
  Errors e;
  const int nv = m->nv;
  using RowMat = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  RowMat M_mj(nv, nv), jacp(3, nv), jacr(3, nv);
  Eigen::MatrixXd Jt(3, nv), Jr(3, nv);
  std::uniform_real_distribution<double> u(-0.2, 0.2);
  for (int s = 0; s < states; ++s) {
    RandomState(m, rng, d->qpos, d->qvel);
    mj_forward(m, d);  // normalises the quaternions of d->qpos
    data.qpos = Eigen::Map<Eigen::VectorXd>(d->qpos, m->nq);
    data.qvel = Eigen::Map<Eigen::VectorXd>(d->qvel, nv);
    TreeKinematics(model, data);
    TreeMassMatrix(model, data);
    TreeBiasForces(model, data);
    mj_fullM(m, M_mj.data(), d->qM);
    e.M = std::max(e.M, RelErr(data.M, M_mj));
    e.bias = std::max(e.bias, RelErr(data.bias, Eigen::Map<Eigen::VectorXd>(d->qfrc_bias, nv)));
    for (int b = 1; b < m->nbody; ++b) {
      const Vec3 p_W = Eigen::Map<Vec3>(d->xpos + 3 * b) + Vec3(u(rng), u(rng), u(rng));
      mj_jac(m, d, jacp.data(), jacr.data(), p_W.data(), b);
      TreePointJacobian(model, data, b - 1, p_W, Jt, Jr);
      e.jac = std::max(e.jac, std::max(RelErr(Jt, jacp), RelErr(Jr, jacr)));
      EXPECT_LT((data.x_W[b - 1] - Eigen::Map<Vec3>(d->xpos + 3 * b)).norm(), 1e-12);
    }
  }
  mj_deleteData(d);
  mj_deleteModel(m);
  return e;
}

struct MujocoCase {
  const char* name;
  const char* body;  // the worldbody's content
};

const MujocoCase kCases[] = {
    {"hinge_chain", R"(
<body pos="0.1 0.2 1" quat="0.9 0.1 0.3 0.2">
  <joint type="hinge" axis="0.3 0.4 1" pos="0.05 0 0.1" ref="0.2" armature="0.01" damping="0.1"/>
  <geom type="capsule" fromto="0 0 0 0.3 0.1 -0.2" size="0.03"/>
  <body pos="0.3 0.1 -0.2" euler="0.3 0.2 0.1">
    <joint type="hinge" axis="1 0 0.5" pos="0 0.02 0" armature="0.05"/>
    <geom type="box" size="0.1 0.03 0.02" pos="0.1 0 0" euler="0.2 0.4 0"/>
    <body pos="0.2 0 0">
      <joint type="hinge" axis="0 1 0.2" ref="-0.5"/>
      <inertial pos="0.1 0.02 0" mass="0.7" fullinertia="0.01 0.02 0.015 0.001 -0.002 0.003"/>
      <body pos="0.2 0.05 0">
        <joint type="hinge" axis="0.2 0.1 1" pos="0.01 0.01 0.01"/>
        <geom type="sphere" size="0.05" pos="0.1 0 0"/>
      </body>
    </body>
  </body>
</body>)"},
    {"slide_hinge", R"(
<body pos="0 0 0.5">
  <joint type="slide" axis="1 0.2 0.1" ref="0.1" armature="0.2"/>
  <geom type="box" size="0.1 0.1 0.05"/>
  <body pos="0.1 0 0" euler="0 0.3 0">
    <joint type="hinge" axis="0 1 0" pos="0 0 0.05"/>
    <geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.02"/>
    <body pos="0.3 0 0">
      <joint type="slide" axis="0.3 0 1"/>
      <geom type="sphere" size="0.04" pos="0 0.02 0"/>
    </body>
  </body>
  <body pos="-0.1 0 0">
    <joint type="hinge" axis="0.5 0.5 0"/>
    <geom type="capsule" fromto="0 0 0 -0.2 0.1 0" size="0.02"/>
  </body>
</body>)"},
    {"ball", R"(
<body pos="0 0 1">
  <joint type="ball" pos="0.02 0 0.1" armature="0.03"/>
  <geom type="capsule" fromto="0 0 0 0 0.1 -0.3" size="0.03"/>
  <body pos="0 0.1 -0.3" euler="0.2 0 0.4">
    <joint type="hinge" axis="1 0 0"/>
    <geom type="box" size="0.05 0.1 0.02" pos="0 0.1 0"/>
    <body pos="0 0.2 0">
      <joint type="ball" pos="0 -0.01 0.02"/>
      <geom type="capsule" fromto="0 0 0 0.2 0.1 0" size="0.02"/>
    </body>
  </body>
</body>)"},
    {"free_with_depth", R"(
<body pos="0.3 0 1" euler="0.1 0.2 0.3">
  <freejoint/>
  <geom type="box" size="0.2 0.1 0.05"/>
  <body pos="0.2 0 0">
    <joint type="hinge" axis="0 0.3 1" pos="0.01 0 0"/>
    <geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.02"/>
    <body pos="0.3 0 0">
      <joint type="ball"/>
      <geom type="capsule" fromto="0 0 0 0.1 0.2 0" size="0.02"/>
      <body pos="0.1 0.2 0">
        <joint type="slide" axis="0 1 0"/>
        <geom type="sphere" size="0.03"/>
      </body>
    </body>
  </body>
</body>)"},
    {"several_joints_per_body", R"(
<body pos="0 0 0.8">
  <joint type="slide" axis="0 0 1"/>
  <joint type="hinge" axis="1 0 0" pos="0 0.05 0"/>
  <joint type="hinge" axis="0 1 0.3" pos="0.02 0 0" armature="0.02"/>
  <geom type="box" size="0.1 0.08 0.05" pos="0.05 0 0"/>
  <body pos="0.2 0 0">
    <joint type="hinge" axis="0 0 1" pos="0 0 0.02"/>
    <joint type="ball" pos="0.01 0 0"/>
    <geom type="capsule" fromto="0 0 0 0.2 0 -0.1" size="0.02"/>
    <body pos="0.2 0 -0.1">
      <joint type="slide" axis="1 0 0"/>
      <joint type="ball" pos="0 0.02 0"/>
      <geom type="sphere" size="0.04" pos="0.03 0 0"/>
    </body>
  </body>
</body>)"},
};

std::string Wrap(const std::string& worldbody) {
  return "<mujoco><compiler angle=\"radian\"/><option gravity=\"0.4 -0.3 -9.81\"/>"
         "<worldbody>" +
         worldbody + "</worldbody></mujoco>";
}

TEST(TreeTest, MassMatrixBiasAndJacobiansEqualMujocos) {
  for (const MujocoCase& c : kCases) {
    const Errors e = CompareWithMujoco(Wrap(c.body), 10);
    // 1e-10 relative, the brief's bound (measured errors printed)
    EXPECT_LT(e.M, 1e-10) << c.name;
    EXPECT_LT(e.bias, 1e-10) << c.name;
    EXPECT_LT(e.jac, 1e-10) << c.name;
    std::printf("%s: M %.2g, bias %.2g, jac %.2g (bound 1e-10)\n", c.name, e.M, e.bias, e.jac);
  }
}

// A humanoid like MuJoCo's: free torso, two hinges in the abdomen, ball hips and shoulders,
// hinge knees, elbows and ankles, capsules throughout (31 dofs).
const char* kHumanoid = R"(
<body name="torso" pos="0 0 1.4">
  <freejoint/>
  <geom type="capsule" fromto="0 -.07 0 0 .07 0" size=".07"/>
  <geom name="head" type="sphere" pos="0 0 .19" size=".09"/>
  <body name="lwaist" pos="-.01 0 -.26" quat="1 0 -.002 0">
    <geom type="capsule" fromto="0 -.06 0 0 .06 0" size=".06"/>
    <joint name="abdomen_z" type="hinge" pos="0 0 .065" axis="0 0 1" armature=".02"/>
    <joint name="abdomen_y" type="hinge" pos="0 0 .065" axis="0 1 0" armature=".02"/>
    <body name="pelvis" pos="0 0 -.165" quat="1 0 -.002 0">
      <joint name="abdomen_x" type="hinge" pos="0 0 .1" axis="1 0 0" armature=".02"/>
      <geom type="capsule" fromto="-.02 -.07 0 -.02 .07 0" size=".09"/>
      <body name="right_thigh" pos="0 -.1 -.04">
        <joint name="right_hip" type="ball" armature=".01"/>
        <geom type="capsule" fromto="0 0 0 0 .01 -.34" size=".06"/>
        <body name="right_shin" pos="0 .01 -.403">
          <joint name="right_knee" type="hinge" pos="0 0 .02" axis="0 -1 0"/>
          <geom type="capsule" fromto="0 0 0 0 0 -.3" size=".049"/>
          <body name="right_foot" pos="0 0 -.39">
            <joint type="hinge" axis="0 1 0.1" pos="0 0 .05"/>
            <geom type="capsule" fromto="-.05 -.02 0 .12 -.03 0" size=".027"/>
          </body>
        </body>
      </body>
      <body name="left_thigh" pos="0 .1 -.04">
        <joint name="left_hip" type="ball" armature=".01"/>
        <geom type="capsule" fromto="0 0 0 0 -.01 -.34" size=".06"/>
        <body name="left_shin" pos="0 -.01 -.403">
          <joint name="left_knee" type="hinge" pos="0 0 .02" axis="0 -1 0"/>
          <geom type="capsule" fromto="0 0 0 0 0 -.3" size=".049"/>
          <body name="left_foot" pos="0 0 -.39">
            <joint type="hinge" axis="0 1 -0.1" pos="0 0 .05"/>
            <geom type="capsule" fromto="-.05 .02 0 .12 .03 0" size=".027"/>
          </body>
        </body>
      </body>
    </body>
  </body>
  <body name="right_upper_arm" pos="0 -.17 .06">
    <joint name="right_shoulder" type="ball" armature=".01"/>
    <geom type="capsule" fromto="0 0 0 .16 -.16 -.16" size=".04"/>
    <body name="right_lower_arm" pos=".18 -.18 -.18">
      <joint name="right_elbow" type="hinge" axis="0 -1 1"/>
      <geom type="capsule" fromto=".01 .01 .01 .17 .17 .17" size=".031"/>
      <geom type="sphere" pos=".18 .18 .18" size=".04"/>
    </body>
  </body>
  <body name="left_upper_arm" pos="0 .17 .06">
    <joint name="left_shoulder" type="ball" armature=".01"/>
    <geom type="capsule" fromto="0 0 0 .16 .16 -.16" size=".04"/>
    <body name="left_lower_arm" pos=".18 .18 -.18">
      <joint name="left_elbow" type="hinge" axis="0 -1 -1"/>
      <geom type="capsule" fromto=".01 -.01 .01 .17 -.17 .17" size=".031"/>
      <geom type="sphere" pos=".18 -.18 .18" size=".04"/>
    </body>
  </body>
</body>)";

TEST(TreeTest, HumanoidEqualsMujoco) {
  const Errors e = CompareWithMujoco(Wrap(kHumanoid), 20);
  // 1e-10 relative, the brief's bound
  EXPECT_LT(e.M, 1e-10);
  EXPECT_LT(e.bias, 1e-10);
  EXPECT_LT(e.jac, 1e-10);
  std::printf("humanoid: M %.2g, bias %.2g, jac %.2g (bound 1e-10)\n", e.M, e.bias, e.jac);
}

// TreeSolveRows gives every right-hand side TreeSolve's bits, and TreeUpdateKinematics leaves
// the kinematics (and qpos) bit for bit as TreeKinematics would, skipping or not
TEST(TreeTest, BatchedSolveAndKinematicsUpdateAreBitIdentical) {
  mjModel* m = CompileXml(Wrap(kHumanoid));
  mjData* d = mj_makeData(m);
  const TreeModel model = io::TreeFromMjModel(m);
  TreeData data = MakeTreeData(model);
  TreeData ref = MakeTreeData(model);
  std::mt19937_64 rng(7);
  RandomState(m, rng, d->qpos, d->qvel);
  data.qpos = Eigen::Map<Eigen::VectorXd>(d->qpos, m->nq);
  data.qpos.segment<4>(3) *= 1.0 + 1e-9;  // a quaternion TreeKinematics must normalise
  ref.qpos = data.qpos;
  TreeKinematics(model, ref);
  TreeUpdateKinematics(model, data);  // changed qpos: the full pass
  const auto same = [](const auto& a, const auto& b) {
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), sizeof(double) * a.size()) == 0;
  };
  EXPECT_TRUE(same(data.qpos, ref.qpos));
  EXPECT_TRUE(same(data.S, ref.S));
  TreeKinematics(model, ref);  // normalises once more, as a later tick's pass would
  TreeUpdateKinematics(model, data);
  EXPECT_TRUE(same(data.qpos, ref.qpos));
  EXPECT_TRUE(same(data.S, ref.S));
  for (std::size_t i = 0; i < model.bodies.size(); ++i) {
    EXPECT_TRUE(same(data.R_WB[i], ref.R_WB[i]) && same(data.x_W[i], ref.x_W[i]) &&
                same(data.com_W[i], ref.com_W[i]) && same(data.inertia_O[i], ref.inertia_O[i]));
  }
  TreeMassMatrix(model, data);
  ASSERT_TRUE(TreeFactor(model, data, 0.002));
  const int nv = model.nv, k = 33;
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::MatrixXd rows(k, nv);
  for (int r = 0; r < k; ++r) {
    for (int c = 0; c < nv; ++c) rows(r, c) = u(rng);
  }
  Eigen::MatrixXd batched = rows;
  TreeSolveRows(data, batched);
  for (int r = 0; r < k; ++r) {
    Eigen::VectorXd x = rows.row(r).transpose();
    TreeSolve(data, x);
    const Eigen::VectorXd b = batched.row(r).transpose();
    EXPECT_TRUE(same(x, b)) << r;
  }
  mj_deleteData(d);
  mj_deleteModel(m);
}

TEST(TreeTest, RefusesANestedFreeJoint) {
  TreeBody root;
  root.mass_kg = 1.0;
  root.inertia_kgm2 = Mat3::Identity();
  TreeBody child = root;
  child.parent = 0;
  TreeJoint free;
  free.type = JointType::kFree;
  child.joints = {free};
  EXPECT_THROW(MakeTree({root, child}, Vec3::Zero()), Error);
}

}  // namespace
}  // namespace rigidtouch::dynamics
