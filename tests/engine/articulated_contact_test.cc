// Contact groups with articulated trees through Tick (issue 45; contact/tree_groups.h) against
// closed forms: the plastic tap of a tool on a hinged door and on a slide, a door swung onto its
// stop (single impulse and train), a tool pressing a link of a chain at rest (joint forces
// J^T f), the determinism of a scene with a tree on one and two threads, no allocation.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <numbers>
#include <string>

#include "dynamics/tree.h"
#include "engine/workspace.h"
#include "limit_malloc.h"
#include "rigidtouch/rigidtouch.h"
#include "test_util.h"

namespace rigidtouch {
namespace {

// the tool's law without spring, damper or friction: only the impulse acts at the tap
LoadOptions TapOptions(RendererKind renderer) {
  LoadOptions o;
  o.contact.stiffness_N_per_m = 0.0;
  o.contact.damping_Ns_per_m = 0.0;
  o.contact.friction_static = 0.0;
  o.contact.friction_kinetic = 0.0;
  o.render.renderer = renderer;
  o.render.restitution = 0.0;
  return o;
}

// A 10 kg door panel (box of half-extents 0.4 x 0.02 x 0.5 m centred 0.4 m from its hinge on z),
// no gravity, and a 0.5 kg tool sphere (radius 1 cm) 0.6 m from the hinge, touching the panel's
// face (0.5 mm deep). The tool moves at 0.2 m/s along the normal (+y); the door is at rest.
// A plastic tap (e = 0): the common speed of the contact point after the onset impulse is
// m_t v / (m_t + I / r^2), I the door's inertia about its hinge, r = 0.6 m. Tolerance 1e-9
// relative (the solve's relative regularisation is 1e-13).
TEST(ArticulatedContactTest, PlasticTapOnAHingedDoorGivesTheCommonSpeed) {
  const std::string xml =
      "<mujoco><option timestep=\"0.001\" gravity=\"0 0 0\"/><worldbody>"
      "<body name=\"door\"><joint name=\"hinge\" type=\"hinge\" axis=\"0 0 1\"/>"
      "<geom name=\"panel\" type=\"box\" size=\"0.4 0.02 0.5\" pos=\"0.4 0 0\" mass=\"10\"/>"
      "</body>"
      "<body name=\"tool\" pos=\"0.6 -0.0295 0\"><freejoint/>"
      "<geom type=\"sphere\" size=\"0.01\" mass=\"0.5\"/></body>"
      "</worldbody></mujoco>";
  const Model m =
      LoadModel(test::WriteTempFile("door_tap.xml", xml), TapOptions(RendererKind::kImpulse));
  ASSERT_EQ(m.trees.size(), 1u);
  Data d = MakeData(m);
  const double v = 0.2, m_t = 0.5, r = 0.6;
  d.bodies[m.tool].v_W = Vec3(0.0, v, 0.0);
  Tick(m, d, TickInput{});
  ASSERT_EQ(d.nimpulse, 1);
  const double mass = 10.0, a = 0.8, b = 0.04, c = 0.4;
  const double I = mass * (a * a + b * b) / 12.0 + mass * c * c;
  const double expected = m_t * v / (m_t + I / (r * r));
  const double tool_speed = d.bodies[m.tool].v_W.y();
  const double door_speed = d.trees[0]->qvel[0] * r;
  EXPECT_NEAR(tool_speed / expected, 1.0, 1e-9) << tool_speed << " m/s, closed form " << expected;
  EXPECT_NEAR(door_speed / expected, 1.0, 1e-9) << door_speed << " m/s, closed form " << expected;
  // the tool's impulse is reported as against a free body: m_t (v - v_c) against its motion
  EXPECT_NEAR(d.tool_impulse_Ns_W.y() / (-m_t * (v - expected)), 1.0, 1e-9);
  EXPECT_TRUE(d.impulses[0].tool);
}

// A 2 kg box on a slide along y and the 0.5 kg tool at 0.3 m/s along it, touching: 1-D masses,
// the common speed m1 v / (m1 + m2) to 1e-9 relative.
TEST(ArticulatedContactTest, PlasticTapOnASlideGivesTheOneDimensionalCommonSpeed) {
  const std::string xml =
      "<mujoco><option timestep=\"0.001\" gravity=\"0 0 0\"/><worldbody>"
      "<body name=\"slider\"><joint name=\"rail\" type=\"slide\" axis=\"0 1 0\"/>"
      "<geom type=\"box\" size=\"0.05 0.05 0.05\" mass=\"2\"/></body>"
      "<body name=\"tool\" pos=\"0 -0.0595 0\"><freejoint/>"
      "<geom type=\"sphere\" size=\"0.01\" mass=\"0.5\"/></body>"
      "</worldbody></mujoco>";
  const Model m =
      LoadModel(test::WriteTempFile("slide_tap.xml", xml), TapOptions(RendererKind::kImpulse));
  Data d = MakeData(m);
  const double v = 0.3, m1 = 0.5, m2 = 2.0;
  d.bodies[m.tool].v_W = Vec3(0.0, v, 0.0);
  Tick(m, d, TickInput{});
  ASSERT_EQ(d.nimpulse, 1);
  const double expected = m1 * v / (m1 + m2);
  EXPECT_NEAR(d.bodies[m.tool].v_W.y() / expected, 1.0, 1e-9);
  EXPECT_NEAR(d.trees[0]->qvel[0] / expected, 1.0, 1e-9);
}

// a door (the panel above) with a stop at q = 0 (range -1 .. 0 rad), no tool, swung at 2 rad/s
// from -0.0503 rad: it reaches its stop in the 26th step. `pressed`: a joint spring towards
// q = 0.5 rad (5 N m/rad) keeps it on its stop afterwards
std::string DoorOnItsStopXml(bool pressed = false) {
  return "<mujoco><compiler angle=\"radian\"/><option timestep=\"0.001\" gravity=\"0 0 0\"/>"
         "<worldbody>"
         "<body name=\"door\"><joint name=\"hinge\" type=\"hinge\" axis=\"0 0 1\" limited=\"true\""
         " range=\"-1 0\"" +
         std::string(pressed ? " stiffness=\"5\" springref=\"0.5\"" : "") +
         "/>"
         "<geom name=\"panel\" type=\"box\" size=\"0.4 0.02 0.5\" pos=\"0.4 0 0\" mass=\"10\"/>"
         "</body></worldbody>"
         "<keyframe><key name=\"initial\" qpos=\"-0.0503\" qvel=\"2\"/></keyframe></mujoco>";
}

Model DoorOnItsStop(RendererKind limit_renderer, bool pressed = false) {
  LoadOptions o;
  o.tool_name = "none";
  o.render.renderer = RendererKind::kPenalty;  // the wall's renderer: limits have their own
  o.render.joint_limit_renderer = limit_renderer;
  return LoadModel(test::WriteTempFile("door_stop.xml", DoorOnItsStopXml(pressed)), o);
}

// e = 0, single impulse: the onset tick ends with the door at rest (plastic, to 1e-9 of the
// approach speed); after it the only push away from the stop is the penalty's release of the
// depth x0 reached at onset, which for the critically damped limit spring (natural frequency w)
// never exceeds x0 w / e^1 (backward Euler damps more)
TEST(ArticulatedContactTest, DoorOnItsStopWithAPlasticImpulseDoesNotRebound) {
  const Model m = DoorOnItsStop(RendererKind::kImpulse);
  Data d = MakeData(m);
  const TickInput in;
  int onset_step = -1;
  for (int s = 0; s < 40 && onset_step < 0; ++s) {
    Tick(m, d, in);
    if (d.nimpulse > 0) onset_step = s;
  }
  ASSERT_GE(onset_step, 0) << "no impulse at the stop";
  EXPECT_EQ(d.impulses[0].total, 1);
  EXPECT_NEAR(d.trees[0]->qvel[0], 0.0, 1e-9 * 2.0);
  const double x0 = d.trees[0]->qpos[0];  // the depth beyond the stop
  EXPECT_GT(x0, 0.0);
  const double w = 2.0 * std::numbers::pi / (contact::kLimitPeriodSteps * m.timestep_s);
  double worst_away = 0.0;
  for (int s = 0; s < 100; ++s) {
    Tick(m, d, in);
    EXPECT_EQ(d.nimpulse, 0);
    worst_away = std::min(worst_away, d.trees[0]->qvel[0]);
  }
  EXPECT_GE(worst_away, -x0 * w / std::exp(1.0)) << "depth " << x0 << " rad";
  // penalty only: the door would leave at about the speed the spring gives back
  const Model pm = DoorOnItsStop(RendererKind::kPenalty);
  Data pd = MakeData(pm);
  double penalty_away = 0.0;
  for (int s = 0; s < 140; ++s) {
    Tick(pm, pd, in);
    EXPECT_EQ(pd.nimpulse, 0);
    penalty_away = std::min(penalty_away, pd.trees[0]->qvel[0]);
  }
  EXPECT_LT(penalty_away, worst_away);
}

// a train on the stop, the door held on it by its spring: every impulse of the window is
// non-negative on its row, and no impulse raises the tree's kinetic energy (1e-12 relative). An
// impulse lands while the limit row is there: the penalty's release of the onset depth lifts the
// door off its stop for a while (the impulses due then find no row), so 2 of the N at least
TEST(ArticulatedContactTest, DoorOnItsStopWithATrainNeverPullsNorAddsEnergy) {
  const Model m = DoorOnItsStop(RendererKind::kTrain, true);
  ASSERT_GT(m.joint_limit_schedule.impulses, 1);
  Data d = MakeData(m);
  const TickInput in;
  int impulses = 0;
  double deepest = 0.0;
  for (int s = 0; s < 200; ++s) {
    Tick(m, d, in);
    deepest = std::max(deepest, d.trees[0]->qpos[0]);
    for (int k = 0; k < d.nimpulse; ++k) {
      const ImpulseEvent& e = d.impulses[k];
      // the onset's impulse takes 1/N of the approach's energy-removing impulse: it acts
      if (impulses == 0) {
        EXPECT_LT(e.kinetic_energy_after_J, e.kinetic_energy_before_J);
      }
      ++impulses;
      EXPECT_LE(e.kinetic_energy_after_J, e.kinetic_energy_before_J * (1.0 + 1e-12)) << s;
      const contact::TreeGroupScratch& tg = d.workspace->contact.trees;
      for (int r = tg.row_start[0]; r < tg.row_start[1]; ++r) {
        EXPECT_GE(tg.rows[r].impulse_Ns, 0.0) << "step " << s;
      }
    }
  }
  EXPECT_GE(impulses, 2);
  // the stop holds: the train's 1/N shares and the limit's penalty let the door 4.3 mrad past its
  // stop (measured); a limit row of the wrong sign let it through by hundreds of radians
  EXPECT_LT(deepest, 1e-2);
  EXPECT_LE(impulses, m.joint_limit_schedule.impulses);
}

// A two-link chain at rest (no gravity) in the x-y plane, hinged about z; the tool (explicit
// law, 2000 N/m) pressed 1 mm into the outer link's capsule. One tick from rest: the chain's
// joint forces are J^T f with J the contact point's Jacobian (dynamics::TreePointJacobian at the
// tick's start) and f the tool's normal force on the link, so qvel = h M^-1 J^T f. Tolerance
// 1e-9 relative.
TEST(ArticulatedContactTest, ToolPressingAChainAtRestGivesJointForcesJTransposeF) {
  const std::string xml =
      "<mujoco><option timestep=\"0.001\" gravity=\"0 0 0\"/><worldbody>"
      "<body name=\"l1\"><joint name=\"j1\" type=\"hinge\" axis=\"0 0 1\"/>"
      "<geom type=\"capsule\" fromto=\"0 0 0 0.3 0 0\" size=\"0.02\" mass=\"1\"/>"
      "<body name=\"l2\" pos=\"0.3 0 0\"><joint name=\"j2\" type=\"hinge\" axis=\"0 0 1\"/>"
      "<geom type=\"capsule\" fromto=\"0 0 0 0.25 0 0\" size=\"0.02\" mass=\"0.6\"/>"
      "</body></body>"
      "<body name=\"tool\" pos=\"0.45 -0.029 0\"><freejoint/>"
      "<geom type=\"sphere\" size=\"0.01\" mass=\"0.5\"/></body>"
      "</worldbody></mujoco>";
  LoadOptions o;
  o.contact.friction_static = 0.0;
  o.contact.friction_kinetic = 0.0;
  o.render.renderer = RendererKind::kPenalty;
  o.render.joint_limit_renderer = RendererKind::kPenalty;
  const Model m = LoadModel(test::WriteTempFile("chain_press.xml", xml), o);
  Data d = MakeData(m);
  // the Jacobian at the start of the tick
  const dynamics::TreeModel& tm = *m.trees[0].dynamics;
  dynamics::TreeData start = dynamics::MakeTreeData(tm);
  start.qpos = d.trees[0]->qpos;
  dynamics::TreeKinematics(tm, start);
  dynamics::TreeMassMatrix(tm, start);
  Tick(m, d, TickInput{});
  ASSERT_EQ(d.ncontact, 1);
  const Contact& c = d.contacts[0];
  ASSERT_GT(c.normal_force_N, 0.0);
  EXPECT_NEAR(c.normal_force_N / (2000.0 * 0.001), 1.0, 1e-6);  // k d at the 1 mm depth
  // the force on the link: -n f if the tool is side a, +n f if it is side b
  const Vec3 f_link = (c.body_a == m.tool ? -1.0 : 1.0) * c.normal_force_N * c.n_W;
  Eigen::MatrixXd jt(3, tm.nv), jr(3, tm.nv);
  dynamics::TreePointJacobian(tm, start, 1, c.p_W, jt, jr);
  const Eigen::VectorXd tau_expected = jt.transpose() * f_link;
  const Eigen::VectorXd tau = start.M * d.trees[0]->qvel / m.timestep_s;
  ASSERT_GT(tau_expected.norm(), 0.0);
  for (int i = 0; i < tm.nv; ++i) {
    EXPECT_NEAR(tau[i], tau_expected[i], 1e-9 * tau_expected.norm()) << "dof " << i;
  }
  // the tool feels the same force, as against a free body
  EXPECT_NEAR((d.tool_penalty_force_N_W + f_link).norm(), 0.0, 1e-12);
}

// FNV-1a over the bodies' and trees' state
std::uint64_t StateHash(const Data& d) {
  std::uint64_t h = 1469598103934665603ull;
  const auto mix = [&h](double x) {
    std::uint64_t bits = 0;
    std::memcpy(&bits, &x, sizeof bits);
    for (int i = 0; i < 8; ++i) {
      h ^= (bits >> (8 * i)) & 0xffu;
      h *= 1099511628211ull;
    }
  };
  for (const BodyState& b : d.bodies) {
    for (int i = 0; i < 3; ++i) mix(b.x_W[i]), mix(b.v_W[i]), mix(b.w_W[i]);
  }
  for (const auto& t : d.trees) {
    for (int i = 0; i < t->qpos.size(); ++i) mix(t->qpos[i]);
    for (int i = 0; i < t->qvel.size(); ++i) mix(t->qvel[i]);
  }
  return h;
}

// a door with a stop and gravity, a tool falling on its top edge and three boxes dropped on it
std::string DoorAndBoxesXml() {
  std::string xml =
      "<mujoco><option timestep=\"0.001\"/><worldbody>"
      "<geom name=\"floor\" type=\"plane\" size=\"2 2 0.1\"/>"
      "<body name=\"door\" pos=\"0 0 0.3\"><joint name=\"hinge\" type=\"hinge\" axis=\"1 0 0\""
      " limited=\"true\" range=\"-0.5 0.5\" damping=\"0.05\"/>"
      "<geom name=\"panel\" type=\"box\" size=\"0.3 0.2 0.02\" pos=\"0 0.1 0\" mass=\"2\"/>"
      "</body>"
      "<body name=\"tool\" pos=\"0.1 0.2 0.36\"><freejoint/>"
      "<geom type=\"sphere\" size=\"0.02\" mass=\"0.2\"/></body>";
  for (int i = 0; i < 3; ++i) {
    xml += "<body name=\"box" + std::to_string(i) + "\" pos=\"" + std::to_string(-0.15 + 0.1 * i) +
           " 0.05 " + std::to_string(0.4 + 0.06 * i) +
           "\"><freejoint/><geom type=\"box\" size=\"0.02 0.02 0.02\" mass=\"0.1\"/></body>";
  }
  return xml + "</worldbody></mujoco>";
}

std::uint64_t DoorAndBoxesHash(int threads, int steps, RendererKind renderer) {
  LoadOptions o;
  o.threads = threads;
  o.render.renderer = renderer;
  const Model m = LoadModel(test::WriteTempFile("door_boxes.xml", DoorAndBoxesXml()), o);
  Data d = MakeData(m);
  const TickInput in;
  int tree_groups = 0;
  for (int s = 0; s < steps; ++s) {
    Tick(m, d, in);
    tree_groups += d.workspace->contact.groups.ntree_group > 0 &&
                   d.workspace->contact.groups.body_start[d.ngroup + 1] >
                       d.workspace->contact.groups.body_start[d.ngroup];
  }
  EXPECT_GT(tree_groups, steps / 4);  // bodies shared a group with the door most of the time
  return StateHash(d);
}

// the golden hash of the door-and-boxes scene over 1.5 s with the train and the single impulse,
// on one thread and on two (the same bits): a change of behaviour shows here. It changed when the
// boxes' contacts on the door got the stick anchor (it was 0x6f3aeb39c0354b04 with the train and
// 0x9ac42535cf240b69 with the single impulse while link rows had tangential damping only; the
// link-static and link-link pairs alone left it unchanged)
TEST(ArticulatedContactTest, GoldenHashOfADoorWithBoxesOnOneAndTwoThreads) {
  for (RendererKind renderer : {RendererKind::kTrain, RendererKind::kImpulse}) {
    const std::uint64_t one = DoorAndBoxesHash(1, 1500, renderer);
    EXPECT_EQ(one, DoorAndBoxesHash(1, 1500, renderer));
    EXPECT_EQ(one, DoorAndBoxesHash(2, 1500, renderer));
    EXPECT_EQ(one, renderer == RendererKind::kTrain ? 0x0e26e9f49d07bf5full : 0xa161cde85c645803ull)
        << std::hex << one;
  }
}

// ticks with a tree in a group, contacts on its links, a limit row and impulses allocate nothing
TEST(ArticulatedContactTest, NoHeapAllocationInTicksWithTreeGroups) {
  if (!test::kMallocCounting) GTEST_SKIP() << "malloc is owned by the sanitizer";
  LoadOptions o;
  o.render.renderer = RendererKind::kTrain;
  const Model m = LoadModel(test::WriteTempFile("door_boxes_alloc.xml", DoorAndBoxesXml()), o);
  Data d = MakeData(m);
  const TickInput in;
  int impulses = 0;
  test::LimitMalloc guard;
  for (int s = 0; s < 1500; ++s) {
    Tick(m, d, in);
    impulses += d.nimpulse;
  }
  EXPECT_EQ(guard.allocations(), 0);
  EXPECT_GT(impulses, 0);
}

// the configuration refuses a joint-limit renderer that is not penalty, impulse or train,
// naming the field and the value
TEST(ArticulatedContactTest, EventIsRefusedAsAJointLimitRenderer) {
  LoadOptions o;
  o.tool_name = "none";
  o.render.joint_limit_renderer = RendererKind::kEvent;
  try {
    LoadModel(test::WriteTempFile("door_stop_event.xml", DoorOnItsStopXml()), o);
    FAIL() << "accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("joint_limit_renderer = event"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace rigidtouch
