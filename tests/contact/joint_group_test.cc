// Joint-space contact groups (src/contact/joint_group.h): the onset impulse of Eq. 5 on a door
// and on a slide against their closed forms, a door swung onto its stop (single impulse and the
// train of Eq. 8), a tool pressing a link of a chain (joint forces = J^T f, the friction cone),
// a group mixing the tool, a free body and a tree (non-negative impulses, momentum), and no
// allocation in the per-tick calls.
#include "contact/joint_group.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include "limit_malloc.h"

namespace rigidtouch::contact {
namespace {

using dynamics::JointType;
using dynamics::TreeBody;
using dynamics::TreeData;
using dynamics::TreeJoint;
using dynamics::TreeModel;

constexpr double kJgStep_s = 1e-3;

Mat3 JgBoxInertia(double m, const Vec3& size_m) {
  const Vec3 s2 = size_m.cwiseProduct(size_m);
  return (m / 12.0 * Vec3(s2.y() + s2.z(), s2.x() + s2.z(), s2.x() + s2.y())).asDiagonal();
}

// a door: a plate of width w (x), height 2 m (z) and thickness t hinged about the z axis at its
// edge; about the hinge I = m w^2 / 3 + m t^2 / 12
struct JgDoor {
  double m_kg = 20.0, w_m = 0.8, t_m = 0.04;
  double HingeInertia() const { return m_kg * w_m * w_m / 3.0 + m_kg * t_m * t_m / 12.0; }
  TreeModel Model() const {
    TreeBody b;
    b.mass_kg = m_kg;
    b.com_m = Vec3(w_m / 2, 0, 0);
    b.inertia_kgm2 = JgBoxInertia(m_kg, Vec3(w_m, t_m, 2.0));
    b.joints = {TreeJoint{}};
    return dynamics::MakeTree({b}, Vec3(0, 0, -9.81));
  }
};

TreeModel JgSlide(double m_kg) {
  TreeBody b;
  b.mass_kg = m_kg;
  b.inertia_kgm2 = JgBoxInertia(m_kg, Vec3(0.2, 0.2, 0.2));
  TreeJoint j;
  j.type = JointType::kSlide;
  j.axis = Vec3::UnitX();
  b.joints = {j};
  return dynamics::MakeTree({b}, Vec3(0, 0, -9.81));
}

// a planar chain of three hinges about y, links 0.4 m along x
TreeModel JgChain() {
  std::vector<TreeBody> bodies(3);
  for (int i = 0; i < 3; ++i) {
    TreeBody& b = bodies[i];
    b.parent = i - 1;
    b.pos_m = i == 0 ? Vec3::Zero() : Vec3(0.4, 0, 0);
    b.quat = Quat(Eigen::AngleAxisd(0.3 * (i + 1), Vec3::UnitY()));
    b.mass_kg = 1.0 + 0.5 * i;
    b.com_m = Vec3(0.2, 0, 0);
    b.inertia_kgm2 = JgBoxInertia(b.mass_kg, Vec3(0.4, 0.05, 0.05));
    TreeJoint j;
    j.axis = Vec3::UnitY();
    b.joints = {j};
  }
  return dynamics::MakeTree(bodies, Vec3::Zero());
}

void JgPrepare(const TreeModel& model, TreeData& data) {
  dynamics::TreeKinematics(model, data);
  dynamics::TreeMassMatrix(model, data);
  ASSERT_TRUE(dynamics::TreeFactor(model, data, kJgStep_s));
}

SolverBody JgTool(double m_kg, const Vec3& v_W) {
  SolverBody tool;
  tool.inv_mass = 1.0 / m_kg;
  tool.inv_inertia_W = Mat3::Identity() / (0.4 * m_kg * 0.01 * 0.01);  // a 1 cm sphere
  tool.v_W = v_W;
  return tool;
}

// the common speed after a tap of a tool of mass m_t at v on the door (theta = 0) at distance r,
// Eq. 5 with scale 1 + e; returns (tool speed, door point speed) along +y
std::pair<double, double> JgDoorTap(double m_t, double v, double r, double scale) {
  const JgDoor door;
  const TreeModel model = door.Model();
  TreeData data = MakeTreeData(model);
  JgPrepare(model, data);
  SolverBody tool = JgTool(m_t, Vec3(0, v, 0));
  const Vec3 p_W(r, 0, 0.3);
  const Vec3 tool_com_W = p_W - Vec3(0, 0.01, 0);
  GroupTree tree{&model, &data};
  JointRow row;
  row.a = {RowSideKind::kBody, 0, -1};
  row.b = {RowSideKind::kLink, 0, 0};
  row.n_W = -Vec3::UnitY();  // from the door towards the tool
  row.p_W = p_W;
  row.impulse_scale = scale;
  JointGroup group{{&tool, 1}, {&tool_com_W, 1}, {&tree, 1}, {&row, 1}};
  JointGroupSolver solver(4, 16);
  const JointImpulseStats stats = solver.ApplyJointImpulses(group);
  EXPECT_EQ(stats.error, JointGroupError::kNone);
  EXPECT_GE(row.impulse_Ns, 0.0);
  return {tool.v_W.y(), data.qvel[0] * r};
}

TEST(JointGroupTest, PlasticTapOnAHingedDoorLeavesTheClosedFormCommonSpeed) {
  const double m_t = 0.3, v = 0.25, r = 0.55;
  const double closed = m_t * v / (m_t + JgDoor{}.HingeInertia() / (r * r));
  const auto [tool_mps, door_mps] = JgDoorTap(m_t, v, r, 1.0);
  // the bound: 1e-9 relative (rounding and the 1e-13 regularisation only)
  EXPECT_NEAR(tool_mps, closed, 1e-9 * closed);
  EXPECT_NEAR(door_mps, closed, 1e-9 * closed);
}

TEST(JointGroupTest, ElasticTapOnAHingedDoorIsTheOneDimensionalCollision) {
  const double m_t = 0.3, v = 0.25, r = 0.55;
  const double m_eff = JgDoor{}.HingeInertia() / (r * r);
  const auto [tool_mps, door_mps] = JgDoorTap(m_t, v, r, 2.0);  // e = 1
  const double tool_closed = (m_t - m_eff) / (m_t + m_eff) * v;
  const double door_closed = 2.0 * m_t / (m_t + m_eff) * v;
  EXPECT_NEAR(tool_mps, tool_closed, 1e-9 * v);
  EXPECT_NEAR(door_mps, door_closed, 1e-9 * v);
  // kinetic energy kept: 1/2 m_t v^2 = 1/2 m_t v_t'^2 + 1/2 m_eff v_d'^2, to 1e-9 relative
  const double ke0 = 0.5 * m_t * v * v;
  const double ke1 = 0.5 * m_t * tool_mps * tool_mps + 0.5 * m_eff * door_mps * door_mps;
  EXPECT_NEAR(ke1, ke0, 1e-9 * ke0);
}

TEST(JointGroupTest, PlasticTapOnASlideIsTheCollisionOfTwoMasses) {
  const double m_t = 0.4, m = 2.5, v = 0.3;
  const TreeModel model = JgSlide(m);
  TreeData data = MakeTreeData(model);
  JgPrepare(model, data);
  SolverBody tool = JgTool(m_t, Vec3(v, 0, 0));
  const Vec3 p_W(-0.1, 0.02, 0.05);
  const Vec3 tool_com_W = p_W - Vec3(0.01, 0, 0);
  GroupTree tree{&model, &data};
  JointRow row;
  row.a = {RowSideKind::kBody, 0, -1};
  row.b = {RowSideKind::kLink, 0, 0};
  row.n_W = -Vec3::UnitX();
  row.p_W = p_W;
  row.impulse_scale = 1.0;
  JointGroup group{{&tool, 1}, {&tool_com_W, 1}, {&tree, 1}, {&row, 1}};
  JointGroupSolver solver(2, 8);
  ASSERT_EQ(solver.ApplyJointImpulses(group).error, JointGroupError::kNone);
  const double closed = m_t * v / (m_t + m);
  EXPECT_NEAR(tool.v_W.x(), closed, 1e-9 * closed);
  EXPECT_NEAR(data.qvel[0], closed, 1e-9 * closed);
  EXPECT_NEAR(row.impulse_Ns, m * closed, 1e-9 * m * closed);
}

// the door at its lower limit q = 0, turning into it at -w
struct JgStop {
  JgDoor door;
  TreeModel model = door.Model();
  TreeData data = MakeTreeData(model);
  GroupTree tree{&model, &data};
  JointRow row;
  JointGroup group{{}, {}, {&tree, 1}, {&row, 1}};
  JointGroupSolver solver{2, 4};
  explicit JgStop(double w_radps) {
    data.qvel[0] = -w_radps;
    row.a = {RowSideKind::kJoint, 0, 0};
    row.limit_sign = 1.0;
  }
};

TEST(JointGroupTest, DoorSwungOntoItsStopDoesNotReboundWithAPlasticImpulse) {
  JgStop stop(1.5);
  JgPrepare(stop.model, stop.data);
  stop.row.impulse_scale = 1.0;  // Eq. 5, e = 0
  ASSERT_EQ(stop.solver.ApplyJointImpulses(stop.group).error, JointGroupError::kNone);
  // stopped exactly (rounding: 1e-12 of the approach); no rebound
  EXPECT_NEAR(stop.data.qvel[0], 0.0, 1e-12 * 1.5);
  // the impulse is the door's angular momentum I w (N m s), to 1e-9 relative
  const double Iw = stop.door.HingeInertia() * 1.5;
  EXPECT_NEAR(stop.row.impulse_Ns, Iw, 1e-9 * Iw);
}

TEST(JointGroupTest, DoorStopTrainNeverPullsNorRaisesEnergyAndStopsTheDoor) {
  JgStop stop(1.5);
  const int impulses = 5, interval = 4;              // N = 5 impulses, n_i = 4 steps
  const double k = 2000.0, b = 5.0, push_Nm = -3.0;  // the stop's law; a hand pushing into it
  int pushing_impulses = 0;
  for (int step = 0; step < impulses * interval; ++step) {
    JgPrepare(stop.model, stop.data);
    dynamics::TreeBiasForces(stop.model, stop.data);
    // free motion with the push; the stop's penalty implicitly
    Eigen::VectorXd accel = Eigen::VectorXd::Constant(1, push_Nm) - stop.data.bias;
    dynamics::TreeSolve(stop.data, accel);
    stop.data.qvel += kJgStep_s * accel;
    stop.row.phi_n_N = k * std::max(-stop.data.qpos[0], 0.0);
    stop.row.c_n_Ns_per_m = kJgStep_s * k + b;
    stop.row.impulse_scale = 0.0;
    ASSERT_EQ(stop.solver.SolveJointPenalty(stop.group, kJgStep_s).error, JointGroupError::kNone);
    EXPECT_GE(stop.row.normal_force_N, 0.0);
    if (step % interval == 0) {
      const int i = step / interval + 1;
      stop.row.impulse_scale = 1.0 / (impulses - i + 1);  // Eq. 8
      const double ke0 = JointGroupKineticEnergy(stop.group);
      ASSERT_EQ(stop.solver.ApplyJointImpulses(stop.group).error, JointGroupError::kNone);
      const double ke1 = JointGroupKineticEnergy(stop.group);
      EXPECT_GE(stop.row.impulse_Ns, 0.0) << "impulse " << i;
      pushing_impulses += stop.row.impulse_Ns > 0.0 ? 1 : 0;
      EXPECT_LE(ke1, ke0 * (1.0 + 1e-12)) << "impulse " << i;
      if (i == impulses) {
        EXPECT_NEAR(stop.data.qvel[0], 0.0, 1e-12);  // the last one stops it
      }
    }
    dynamics::TreeIntegratePositions(stop.model, stop.data, kJgStep_s);
  }
  // the hand drives the door back into the stop between impulses: every impulse of the train acts
  EXPECT_EQ(pushing_impulses, impulses);
}

TEST(JointGroupTest, ToolTrainAndPlasticStopInOneGroup) {
  // the door turning into its stop at q = 0 while a tool, faster, pushes it there: the tool's row
  // takes a train's share 1/3, the stop a plastic single impulse
  JgStop stop(1.5);
  JgPrepare(stop.model, stop.data);
  const double r = 0.6;
  SolverBody tool = JgTool(0.3, Vec3(0, -2.0, 0));
  const Vec3 tool_com_W(r, 0.01, 0.3);
  JointRow rows[2];
  rows[0].a = {RowSideKind::kBody, 0, -1};
  rows[0].b = {RowSideKind::kLink, 0, 0};
  rows[0].n_W = Vec3::UnitY();
  rows[0].p_W = Vec3(r, 0, 0.3);
  rows[0].impulse_scale = 1.0 / 3.0;
  rows[1] = stop.row;
  rows[1].impulse_scale = 1.0;
  JointGroup group{{&tool, 1}, {&tool_com_W, 1}, {&stop.tree, 1}, rows};
  const double ke0 = JointGroupKineticEnergy(group);
  JointGroupSolver solver(2, 8);
  const JointImpulseStats stats = solver.ApplyJointImpulses(group);
  ASSERT_EQ(stats.error, JointGroupError::kNone);
  EXPECT_EQ(stats.solves, 2);
  EXPECT_GT(rows[0].impulse_Ns, 0.0);
  EXPECT_GT(rows[1].impulse_Ns, 0.0);
  EXPECT_LE(JointGroupKineticEnergy(group), ke0);
  // the stop's plastic impulse, solved last, leaves the door at rest against it (rounding: 1e-12
  // of the approach)
  EXPECT_NEAR(stop.data.qvel[0], 0.0, 1e-12 * 1.5);
}

// a tool pressing link 2 of the chain at rest, 1 mm deep, with a stick anchor force
struct JgPress {
  TreeModel model = JgChain();
  TreeData data = MakeTreeData(model);
  GroupTree tree{&model, &data};
  SolverBody tool = JgTool(0.5, Vec3::Zero());
  Vec3 tool_com_W;
  JointRow row;
  JointGroup group{{&tool, 1}, {&tool_com_W, 1}, {&tree, 1}, {&row, 1}};
  JointGroupSolver solver{2, 16};
  explicit JgPress(const Vec3& phi_t_W) {
    JgPrepare(model, data);
    row.a = {RowSideKind::kBody, 0, -1};
    row.b = {RowSideKind::kLink, 0, 2};
    // the link's upper face (its local +z) at its middle
    const Vec3 n_W = data.R_WB[2].col(2);
    row.n_W = n_W;
    row.p_W = data.x_W[2] + data.R_WB[2] * Vec3(0.2, 0, 0.025);
    tool_com_W = row.p_W + 0.01 * n_W;
    tool.v_W = -0.02 * n_W;
    row.phi_n_N = 2000.0 * 1e-3;
    row.c_n_Ns_per_m = kJgStep_s * 2000.0 + 2.0;
    row.stick = true;
    row.phi_t_W = phi_t_W - phi_t_W.dot(n_W) * n_W;
    row.c_t_Ns_per_m = row.c_n_Ns_per_m;
    row.mu_static = 0.5;
    row.mu_kinetic = 0.4;
  }
};

TEST(JointGroupTest, ToolPressingAChainLinkGivesJointTorquesJTransposeF) {
  JgPress press(Vec3(0.3, 0.1, 0));
  const Eigen::VectorXd qvel0 = press.data.qvel;
  ASSERT_EQ(press.solver.SolveJointPenalty(press.group, kJgStep_s).error, JointGroupError::kNone);
  EXPECT_GT(press.row.normal_force_N, 0.0);
  EXPECT_FALSE(press.row.slipped);
  // the force on the link (side b) is -(f_n n + f_t)
  const Vec3 f_link_N = -(press.row.normal_force_N * press.row.n_W + press.row.friction_force_N_W);
  Eigen::MatrixXd jt(3, 3), jr(3, 3);
  dynamics::TreePointJacobian(press.model, press.data, 2, press.row.p_W, jt, jr);
  const Eigen::VectorXd expected = jt.transpose() * f_link_N;
  const Eigen::VectorXd tau = press.solver.TreeContactForce(0);
  // rounding of the row sums: 1e-12 of the largest torque
  EXPECT_LT((tau - expected).cwiseAbs().maxCoeff(), 1e-12 * expected.cwiseAbs().maxCoeff());
  // and the joints accelerate by them: M dv = h J^T f (no damping), 1e-9 relative
  const Eigen::VectorXd m_dv = press.data.M * (press.data.qvel - qvel0);
  EXPECT_LT((m_dv - kJgStep_s * expected).cwiseAbs().maxCoeff(),
            1e-9 * kJgStep_s * expected.cwiseAbs().maxCoeff());
  // the tool gets the opposite: m_t dv = h (f_n n + f_t)
  EXPECT_LT((press.tool.v_W / press.tool.inv_mass - (-0.02 * press.row.n_W / press.tool.inv_mass) +
             kJgStep_s * f_link_N)
                .norm(),
            1e-9 * kJgStep_s * f_link_N.norm());
}

TEST(JointGroupTest, ChainLinkFrictionStaysInsideTheCone) {
  JgPress press(Vec3(40.0, 25.0, 0));  // an anchor force far beyond mu_s f_n
  ASSERT_EQ(press.solver.SolveJointPenalty(press.group, kJgStep_s).error, JointGroupError::kNone);
  EXPECT_TRUE(press.row.slipped);
  const double fn = press.row.normal_force_N;
  EXPECT_GT(fn, 0.0);
  // kinetic friction once slipping: |f_t| <= mu_k f_n up to 1e-12 relative
  EXPECT_LE(press.row.friction_force_N_W.norm(), press.row.mu_kinetic * fn * (1.0 + 1e-12));
  EXPECT_GT(press.row.friction_force_N_W.norm(), 0.0);
}

// tool -> free body -> a block on a slide along x, plus the tool resting on a floor and the free
// body touching a stop behind it
struct JgMixed {
  double m_t = 0.5, m_f = 1.2, m_s = 2.0, v = 0.4;
  TreeModel model = JgSlide(m_s);
  TreeData data = MakeTreeData(model);
  GroupTree tree{&model, &data};
  SolverBody bodies[2];
  Vec3 com_W[2] = {Vec3(-0.3, 0, 0), Vec3(-0.15, 0, 0)};
  JointRow rows[4];
  JointGroup group{bodies, com_W, {&tree, 1}, rows};
  JointGroupSolver solver{8, 32};
  JgMixed() {
    JgPrepare(model, data);
    bodies[0] = JgTool(m_t, Vec3(v, 0, 0));
    bodies[1] = JgTool(m_f, Vec3::Zero());
    rows[0].a = {RowSideKind::kBody, 0, -1};  // tool, left of the free body
    rows[0].b = {RowSideKind::kBody, 1, -1};
    rows[0].n_W = -Vec3::UnitX();
    rows[0].p_W = Vec3(-0.2, 0, 0);
    rows[1].a = {RowSideKind::kBody, 1, -1};  // free body, left of the slide's block
    rows[1].b = {RowSideKind::kLink, 0, 0};
    rows[1].n_W = -Vec3::UnitX();
    rows[1].p_W = Vec3(-0.1, 0, 0);
    rows[2].a = {RowSideKind::kBody, 0, -1};  // the tool on a floor, at rest on it
    rows[2].n_W = Vec3::UnitZ();
    rows[2].p_W = com_W[0] - Vec3(0, 0, 0.01);
    rows[3].a = {RowSideKind::kBody, 1, -1};  // a stop left of the free body, on its x line:
    rows[3].n_W = Vec3::UnitX();              // only a pull there could keep it still
    rows[3].p_W = Vec3(-0.16, 0, 0);
    for (JointRow& row : rows) row.impulse_scale = 1.0;
  }
  double MomentumX() const {
    return bodies[0].v_W.x() / bodies[0].inv_mass + bodies[1].v_W.x() / bodies[1].inv_mass +
           m_s * data.qvel[0];
  }
};

TEST(JointGroupTest, MixedGroupImpulsesAreNonNegativeAndKeepMomentum) {
  JgMixed mixed;
  const double p0 = mixed.MomentumX();
  const double ke0 = JointGroupKineticEnergy(mixed.group);
  const JointImpulseStats stats = mixed.solver.ApplyJointImpulses(mixed.group);
  ASSERT_EQ(stats.error, JointGroupError::kNone);
  for (const JointRow& row : mixed.rows) EXPECT_GE(row.impulse_Ns, 0.0);
  // the stop would have to pull to keep the free body still: it gets no impulse, so no outside
  // impulse acts along x and the momentum is kept (1e-12 relative)
  EXPECT_EQ(mixed.rows[3].impulse_Ns, 0.0);
  EXPECT_NEAR(mixed.MomentumX(), p0, 1e-12 * std::abs(p0));
  // plastic: all three move together at m_t v / (m_t + m_f + m_s), 1e-9 relative
  const double common = mixed.m_t * mixed.v / (mixed.m_t + mixed.m_f + mixed.m_s);
  EXPECT_NEAR(mixed.bodies[0].v_W.x(), common, 1e-9 * common);
  EXPECT_NEAR(mixed.bodies[1].v_W.x(), common, 1e-9 * common);
  EXPECT_NEAR(mixed.data.qvel[0], common, 1e-9 * common);
  EXPECT_LT(JointGroupKineticEnergy(mixed.group), ke0);
}

TEST(JointGroupTest, RefusesBadRowsWithoutChangingVelocities) {
  JgMixed mixed;
  mixed.rows[1].b.index = 3;  // no such link
  EXPECT_EQ(mixed.solver.ApplyJointImpulses(mixed.group).error, JointGroupError::kBadRow);
  mixed.rows[1].b.index = 0;
  mixed.rows[2].impulse_scale = 2.5;
  EXPECT_EQ(mixed.solver.ApplyJointImpulses(mixed.group).error, JointGroupError::kBadScale);
  EXPECT_EQ(mixed.bodies[0].v_W.x(), mixed.v);
  EXPECT_EQ(mixed.data.qvel[0], 0.0);
}

TEST(JointGroupTest, PerTickCallsDoNotAllocate) {
  if (!test::kMallocCounting) GTEST_SKIP() << "allocations are not counted under sanitizers";
  JgMixed mixed;
  for (JointRow& row : mixed.rows) {
    row.phi_n_N = 1.0;
    row.c_n_Ns_per_m = 2.0;
    row.stick = true;
    row.c_t_Ns_per_m = 2.0;
    row.mu_static = row.mu_kinetic = 0.5;
  }
  mixed.rows[0].phi_t_W = Vec3(0, 3.0, 0);  // slips
  test::LimitMalloc guard;
  const JointPenaltyStats penalty = mixed.solver.SolveJointPenalty(mixed.group, kJgStep_s);
  const JointImpulseStats impulse = mixed.solver.ApplyJointImpulses(mixed.group);
  EXPECT_EQ(guard.allocations(), 0);
  EXPECT_EQ(penalty.error, JointGroupError::kNone);
  EXPECT_EQ(impulse.error, JointGroupError::kNone);
}

}  // namespace
}  // namespace rigidtouch::contact
