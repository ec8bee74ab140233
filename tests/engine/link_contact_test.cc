// Links of kinematic trees colliding with static geometry and with other links (issue 45; the
// collision filter in geometry/broadphase.h, the rows in contact/tree_groups.h) against closed
// forms: a hinged rod resting on a floor (torque balance about the hinge), a rod falling onto a
// plane with a single plastic or elastic impulse and with a train, two slides of different trees
// and two links of one chain colliding plastically (momentum along the slide), friction with the
// stick anchor, the parent-child filter, a small humanoid-like tree dropped on a plane, and no
// allocation in the tick.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "dynamics/tree.h"
#include "engine/workspace.h"
#include "limit_malloc.h"
#include "rigidtouch/rigidtouch.h"
#include "test_util.h"

namespace rigidtouch {
namespace {

constexpr double kLinkGravity_mps2 = 9.81;

// A 0.5 m rod of mass m_rod (a thin box along its body x) hinged about y at (0, 0, 0.3), with a
// massless sphere (radius 2 cm) at its tip, over a floor plane at z = 0. At q = theta the tip
// sphere's centre is at height 0.3 - 0.5 sin(theta); it touches the floor at sin(theta) = 0.56.
// The sphere is the only geom that can reach the floor (the box is 1 cm thick).
std::string RodOverFloorXml(double theta0, double qvel0, double damping, double m_rod) {
  return "<mujoco><compiler angle=\"radian\"/><option timestep=\"0.001\"/><worldbody>"
         "<geom name=\"floor\" type=\"plane\" size=\"2 2 0.1\"/>"
         "<body name=\"rod\" pos=\"0 0 0.3\"><joint name=\"hinge\" type=\"hinge\" axis=\"0 1 0\""
         " damping=\"" +
         std::to_string(damping) +
         "\"/>"
         "<geom name=\"bar\" type=\"box\" size=\"0.25 0.01 0.005\" pos=\"0.25 0 0\" mass=\"" +
         std::to_string(m_rod) +
         "\"/>"
         "<geom name=\"tip\" type=\"sphere\" size=\"0.02\" pos=\"0.5 0 0\" mass=\"0\"/>"
         "</body></worldbody>"
         "<keyframe><key name=\"initial\" qpos=\"" +
         std::to_string(theta0) + "\" qvel=\"" + std::to_string(qvel0) + "\"/></keyframe></mujoco>";
}

LoadOptions Frictionless(RendererKind renderer, double e = 0.0) {
  LoadOptions o;
  o.tool_name = "none";
  o.contact.friction_static = 0.0;
  o.contact.friction_kinetic = 0.0;
  o.render.renderer = renderer;
  o.render.restitution = e;
  o.render.joint_limit_renderer = RendererKind::kPenalty;
  return o;
}

// the contacts' summed normal force and their force-weighted lever arm about the hinge's y axis
// through the origin x = 0 (the normal is the floor's +z)
void FloorForce(const Data& d, double& force_N, double& torque_Nm) {
  force_N = 0.0;
  torque_Nm = 0.0;
  for (int i = 0; i < d.ncontact; ++i) {
    const Contact& c = d.contacts[i];
    force_N += c.normal_force_N;
    torque_Nm += c.normal_force_N * c.p_W.x();
  }
}

// At rest on the floor the rod's weight and the floor's normal force balance about the hinge:
// m g (l / 2) cos(theta) = F_n r, r the contact point's horizontal distance from the hinge
// (frictionless, so the normal force is the floor's only force on the rod). After 3 s with joint
// damping the two sides agree to 1e-6 relative; without link-static pairs the rod falls through
// the floor.
TEST(LinkContactTest, HingedRodOnAFloorBalancesItsWeightAboutTheHinge) {
  const double m_rod = 2.0, l = 0.5;
  const Model m =
      LoadModel(test::WriteTempFile("rod_floor.xml", RodOverFloorXml(0.55, 0.0, 0.5, m_rod)),
                Frictionless(RendererKind::kPenalty));
  Data d = MakeData(m);
  const TickInput in;
  double lowest = 1.0;
  for (int s = 0; s < 3000; ++s) {
    Tick(m, d, in);
    const double theta = d.trees[0]->qpos[0];
    lowest = std::min(lowest, 0.3 - l * std::sin(theta) - 0.02);
  }
  const double theta = d.trees[0]->qpos[0];
  ASSERT_GT(d.ncontact, 0) << "the rod does not touch the floor";
  double force = 0.0, torque = 0.0;
  FloorForce(d, force, torque);
  const double weight_torque = m_rod * kLinkGravity_mps2 * (l / 2.0) * std::cos(theta);
  EXPECT_NEAR(torque / weight_torque, 1.0, 1e-6) << "theta " << theta << " F_n " << force;
  // the lever arm is the tip's: F_n = m g / 2 here
  EXPECT_NEAR(force / (m_rod * kLinkGravity_mps2 / 2.0), 1.0, 1e-3);
  // it rests on the floor: the landing (penalty only) sank the tip 1.07 mm (measured), the rest
  // m g / (2 k) = 0.05 mm
  EXPECT_GT(lowest, -2e-3);
  EXPECT_NEAR(std::abs(d.trees[0]->qvel[0]), 0.0, 1e-6);
}

// the contact point's normal velocity of the rod's tip contact after this tick's update
double TipNormalVelocity(const Data& d) {
  const Contact& c = d.contacts[0];
  // the link's angular velocity is qvel about +y; the hinge is at (0, 0, 0.3)
  const Vec3 w(0.0, d.trees[0]->qvel[0], 0.0);
  const Vec3 v = w.cross(c.p_W - Vec3(0.0, 0.0, 0.3));
  // side a is the link (the floor is static): the normal points from the floor to the rod
  return v.dot(c.n_W);
}

// Runs the falling rod until its first contact tick (the onset) with `renderer`; returns the
// step, or -1.
int RunToOnset(const Model& m, Data& d) {
  const TickInput in;
  for (int s = 0; s < 400; ++s) {
    Tick(m, d, in);
    if (d.ncontact > 0) return s;
  }
  return -1;
}

// A rod swung onto the floor at about 1.5 m/s at the tip: with a single impulse and e = 0 the
// contact point's normal velocity after the onset tick is 0 (1e-9 of the approach); with
// e = 0.5 it is -e times the velocity just before the impulse, which is the velocity the same
// tick leaves with the penalty renderer (stage 4 is the same for both). Tolerance 1e-9 relative.
TEST(LinkContactTest, RodFallingOnAPlaneWithASingleImpulseObeysRestitution) {
  const std::string xml = RodOverFloorXml(0.45, 3.0, 0.0, 2.0);
  for (const double e : {0.0, 0.5}) {
    const Model mp =
        LoadModel(test::WriteTempFile("rod_fall_p.xml", xml), Frictionless(RendererKind::kPenalty));
    const Model mi = LoadModel(test::WriteTempFile("rod_fall_i.xml", xml),
                               Frictionless(RendererKind::kImpulse, e));
    Data dp = MakeData(mp), di = MakeData(mi);
    const int sp = RunToOnset(mp, dp), si = RunToOnset(mi, di);
    ASSERT_GE(si, 0) << "the rod never reached the floor";
    ASSERT_EQ(sp, si);
    ASSERT_EQ(di.nimpulse, 1) << "no onset impulse";
    ASSERT_EQ(dp.ncontact, 1);
    const double before = TipNormalVelocity(dp);
    ASSERT_LT(before, -0.5);  // approaching
    const double after = TipNormalVelocity(di);
    EXPECT_NEAR(after, -e * before, 1e-9 * std::abs(before)) << "e " << e;
    EXPECT_GE(di.contacts[0].impulse_Ns, 0.0);
    EXPECT_LE(di.impulses[0].kinetic_energy_after_J,
              di.impulses[0].kinetic_energy_before_J * (1.0 + 1e-12));
  }
}

// The same rod with a train: every impulse of the window is non-negative on every row and no
// impulse raises the tree's kinetic energy (1e-12 relative); the rod stays above the floor
// (sink under 1 cm).
TEST(LinkContactTest, RodFallingOnAPlaneWithATrainNeverPullsNorAddsEnergy) {
  const Model m =
      LoadModel(test::WriteTempFile("rod_train.xml", RodOverFloorXml(0.45, 3.0, 0.0, 2.0)),
                Frictionless(RendererKind::kTrain));
  ASSERT_GT(m.schedule.impulses, 1);
  Data d = MakeData(m);
  const TickInput in;
  int impulses = 0;
  double lowest = 1.0;
  for (int s = 0; s < 400; ++s) {
    Tick(m, d, in);
    lowest = std::min(lowest, 0.3 - 0.5 * std::sin(d.trees[0]->qpos[0]) - 0.02);
    for (int k = 0; k < d.nimpulse; ++k) {
      const ImpulseEvent& e = d.impulses[k];
      ++impulses;
      EXPECT_LE(e.kinetic_energy_after_J, e.kinetic_energy_before_J * (1.0 + 1e-12)) << s;
      const contact::TreeGroupScratch& tg = d.workspace->contact.trees;
      for (int r = tg.row_start[0]; r < tg.row_start[1]; ++r) {
        EXPECT_GE(tg.rows[r].impulse_Ns, 0.0) << "step " << s;
      }
    }
  }
  EXPECT_GE(impulses, 2);
  EXPECT_GT(lowest, -1e-2);
}

// Two boxes on slides along x (two trees), 2 kg at +0.4 m/s and 0.5 kg at -0.6 m/s, touching
// (0.5 mm deep), no gravity, plastic single impulse: the penalty and the impulse are internal to
// the pair, so after the onset tick both move at (m1 v1 + m2 v2) / (m1 + m2), 1e-9 relative
TEST(LinkContactTest, TwoSlidesOfTwoTreesCollidePlasticallyAndKeepMomentum) {
  const std::string xml =
      "<mujoco><option timestep=\"0.001\" gravity=\"0 0 0\"/><worldbody>"
      "<body name=\"a\"><joint name=\"sa\" type=\"slide\" axis=\"1 0 0\"/>"
      "<geom type=\"box\" size=\"0.05 0.05 0.05\" mass=\"2\"/></body>"
      "<body name=\"b\" pos=\"0.0995 0 0\"><joint name=\"sb\" type=\"slide\" axis=\"1 0 0\"/>"
      "<geom type=\"box\" size=\"0.05 0.04 0.04\" mass=\"0.5\"/></body>"
      "</worldbody><keyframe><key name=\"initial\" qvel=\"0.4 -0.6\"/></keyframe></mujoco>";
  const Model m =
      LoadModel(test::WriteTempFile("two_slides.xml", xml), Frictionless(RendererKind::kImpulse));
  ASSERT_EQ(m.trees.size(), 2u);
  Data d = MakeData(m);
  Tick(m, d, TickInput{});
  ASSERT_GT(d.ncontact, 0);
  ASSERT_EQ(d.nimpulse, 1);
  EXPECT_EQ(d.workspace->contact.groups.ntree_group, 1);  // one group holds both trees
  const double p = 2.0 * 0.4 + 0.5 * -0.6, common = p / 2.5;
  EXPECT_NEAR(d.trees[0]->qvel[0], common, 1e-9 * std::abs(common));
  EXPECT_NEAR(d.trees[1]->qvel[0], common, 1e-9 * std::abs(common));
  EXPECT_NEAR(2.0 * d.trees[0]->qvel[0] + 0.5 * d.trees[1]->qvel[0], p, 1e-12);
}

// One tree: a 2 kg box A on a slide along x, a massless-ish carrier B (slide along y, no geom)
// below it and a 0.5 kg box C on a slide along x below B. A and C are not parent and child, so
// they collide; C approaches A at 1 m/s. The contact is internal to the tree (J = J_A - J_C on
// its dofs): the tree's x momentum (m_A + m_B + m_C) v_A + m_C v_C is kept, and after a plastic
// impulse C is at rest relative to A, so v_A = P / M and v_C = 0 (1e-9).
TEST(LinkContactTest, TwoLinksOfOneChainCollidePlasticallyAndKeepMomentum) {
  const std::string xml =
      "<mujoco><option timestep=\"0.001\" gravity=\"0 0 0\"/><worldbody>"
      "<body name=\"a\"><joint name=\"sa\" type=\"slide\" axis=\"1 0 0\"/>"
      "<geom type=\"box\" size=\"0.05 0.05 0.05\" mass=\"2\"/>"
      "<body name=\"b\"><joint name=\"sb\" type=\"slide\" axis=\"0 1 0\"/>"
      "<inertial pos=\"0 0 0\" mass=\"0.1\" diaginertia=\"1e-4 1e-4 1e-4\"/>"
      "<body name=\"c\" pos=\"-0.0995 0 0\"><joint name=\"sc\" type=\"slide\" axis=\"1 0 0\"/>"
      "<geom type=\"box\" size=\"0.05 0.04 0.04\" mass=\"0.5\"/></body></body></body>"
      "</worldbody><keyframe><key name=\"initial\" qvel=\"0 0 1\"/></keyframe></mujoco>";
  const Model m =
      LoadModel(test::WriteTempFile("chain_links.xml", xml), Frictionless(RendererKind::kImpulse));
  ASSERT_EQ(m.trees.size(), 1u);
  Data d = MakeData(m);
  const double total = 2.6, p = 0.5 * 1.0;
  Tick(m, d, TickInput{});
  ASSERT_GT(d.ncontact, 0);
  ASSERT_EQ(d.nimpulse, 1);
  const Eigen::VectorXd& v = d.trees[0]->qvel;
  EXPECT_NEAR(total * v[0] + 0.5 * v[2], p, 1e-12);
  EXPECT_NEAR(v[2], 0.0, 1e-9);
  EXPECT_NEAR(v[0], p / total, 1e-9);
  EXPECT_NEAR(v[1], 0.0, 1e-12);
}

// A 1 kg box on a floor, its link on a slide along x below a 0.1 kg carrier on a vertical slide
// (so that it rests on the floor under gravity), pushed along x by a motor at a constant force
// (keyframe ctrl, N); MJCF friction 1
std::string PushedBoxXml(double force_N) {
  return "<mujoco><option timestep=\"0.001\"/><worldbody>"
         "<geom name=\"floor\" type=\"plane\" size=\"2 2 0.1\"/>"
         "<body name=\"carrier\" pos=\"0 0 0.0499\"><joint name=\"up\" type=\"slide\" "
         "axis=\"0 0 1\"/><inertial pos=\"0 0 0\" mass=\"0.1\" diaginertia=\"1e-4 1e-4 1e-4\"/>"
         "<body name=\"box\"><joint name=\"along\" type=\"slide\" axis=\"1 0 0\"/>"
         "<geom type=\"box\" size=\"0.05 0.05 0.05\" mass=\"1\"/></body></body></worldbody>"
         "<actuator><motor name=\"push\" joint=\"along\"/></actuator>"
         "<keyframe><key name=\"initial\" qpos=\"0 0\" ctrl=\"" +
         std::to_string(force_N) + "\"/></keyframe></mujoco>";
}

// Friction on link rows has the free bodies' stick anchor: pushed at 3 N, below mu N = 10.8 N,
// the box holds within the anchor spring's static stretch F / k_t (15 um at 2e5 N/m) over 2 s
// and ends at rest (1e-6 m/s); with tangential damping alone it crept at F / (b_t + h k_t),
// 1 cm/s. Pushed at 15 N it slides with (F - mu m g) / m_x: every contact's friction within
// its cone (1e-9 relative), the speed after 1 s within 1 % of the closed form.
TEST(LinkContactTest, FrictionOnALinkHoldsBelowTheConeAndSlidesBeyondIt) {
  LoadOptions o;
  o.tool_name = "none";
  o.render.renderer = RendererKind::kPenalty;
  const Model held = LoadModel(test::WriteTempFile("pushed_box.xml", PushedBoxXml(3.0)), o);
  Data d = MakeData(held);
  const TickInput in;
  for (int s = 0; s < 2000; ++s) Tick(held, d, in);
  ASSERT_GT(d.ncontact, 0);
  EXPECT_LT(std::abs(d.trees[0]->qpos[1]), 1e-4) << "crept " << d.trees[0]->qpos[1] << " m";
  EXPECT_LT(std::abs(d.trees[0]->qvel[1]), 1e-6);
  const Model pushed = LoadModel(test::WriteTempFile("pushed_box2.xml", PushedBoxXml(15.0)), o);
  Data p = MakeData(pushed);
  for (int s = 0; s < 1000; ++s) {
    Tick(pushed, p, in);
    for (int i = 0; i < p.ncontact; ++i) {
      const Contact& c = p.contacts[i];
      EXPECT_LE(c.friction_force_N_W.norm(), c.normal_force_N * (1.0 + 1e-9) + 1e-12) << s;
    }
  }
  const double expected = (15.0 - 1.0 * 1.1 * 9.81) / 1.0 * 1.0;
  EXPECT_NEAR(p.trees[0]->qvel[1] / expected, 1.0, 1e-2) << p.trees[0]->qvel[1];
}

// a chain of three hinged links whose geoms overlap by 0.5 mm pairwise (under the load's 1 mm
// bound on initial overlaps): the root link's box (x 0 .. 0.2 m, y and z +-2 cm), the second
// link's sphere (4 cm) on the box's +y face, the third link's sphere (3 cm) on the box's face and
// against the second sphere. `filter` false adds <flag filterparent="disable"/>.
std::string OverlappingChainXml(bool filter) {
  return std::string("<mujoco><option timestep=\"0.001\" gravity=\"0 0 0\">") +
         (filter ? "" : "<flag filterparent=\"disable\"/>") +
         "</option><worldbody>"
         "<body name=\"l1\"><joint name=\"j1\" type=\"hinge\" axis=\"0 0 1\"/>"
         "<geom name=\"g1\" type=\"box\" size=\"0.1 0.02 0.02\" pos=\"0.1 0 0\" mass=\"1\"/>"
         "<body name=\"l2\" pos=\"0.1 0.0595 0\"><joint name=\"j2\" type=\"hinge\" "
         "axis=\"0 0 1\"/><geom name=\"g2\" type=\"sphere\" size=\"0.04\" mass=\"1\"/>"
         "<body name=\"l3\" pos=\"0.068776 -0.01 0\"><joint name=\"j3\" type=\"hinge\" "
         "axis=\"0 0 1\"/><geom name=\"g3\" type=\"sphere\" size=\"0.03\" mass=\"1\"/>"
         "</body></body></body></worldbody></mujoco>";
}

// MuJoCo's parent filter: a link's geom does not collide with its parent link's (l2 with l1, l3
// with l2), while l3 and l1, which are not parent and child, do. With filterparent disabled,
// every overlapping pair collides.
TEST(LinkContactTest, AChildLinkOverlappingItsParentHasNoContact) {
  for (const bool filter : {true, false}) {
    const Model m = LoadModel(test::WriteTempFile("overlap_chain.xml", OverlappingChainXml(filter)),
                              Frictionless(RendererKind::kPenalty));
    EXPECT_EQ(m.filter_parent, filter);
    Data d = MakeData(m);
    Tick(m, d, TickInput{});
    bool l1_l2 = false, l2_l3 = false, l1_l3 = false;
    for (int i = 0; i < d.ncontact; ++i) {
      const Contact& c = d.contacts[i];
      const int la = m.geoms[c.geom_a].link, lb = m.geoms[c.geom_b].link;
      const int lo = std::min(la, lb), hi = std::max(la, lb);
      l1_l2 = l1_l2 || (lo == 0 && hi == 1);
      l2_l3 = l2_l3 || (lo == 1 && hi == 2);
      l1_l3 = l1_l3 || (lo == 0 && hi == 2);
    }
    EXPECT_EQ(l1_l2, !filter);
    EXPECT_EQ(l2_l3, !filter);
    EXPECT_TRUE(l1_l3);
  }
}

// a humanoid-like tree: a free root (torso capsule and head sphere), two legs of two hinges each
// (hip, knee with a limit), two arms of one hinge; capsules throughout; its feet `drop` m above a
// floor plane
std::string SmallHumanoidXml(double drop) {
  std::string xml =
      "<mujoco><compiler angle=\"radian\"/><option timestep=\"0.001\"/><worldbody>"
      "<geom name=\"floor\" type=\"plane\" size=\"5 5 0.1\"/>"
      "<body name=\"torso\" pos=\"0 0 " +
      std::to_string(0.8 + 0.035 + drop) +
      "\"><freejoint/>"
      "<geom type=\"capsule\" fromto=\"0 0 -0.15 0 0 0.15\" size=\"0.07\" mass=\"10\"/>"
      "<geom type=\"sphere\" pos=\"0 0 0.28\" size=\"0.08\" mass=\"3\"/>";
  for (const int side : {-1, 1}) {
    const std::string y = std::to_string(0.09 * side), ya = std::to_string(0.14 * side);
    const std::string s = side < 0 ? "r" : "l";
    xml += "<body name=\"thigh_" + s + "\" pos=\"0 " + y + " -0.25\"><joint name=\"hip_" + s +
           "\" type=\"hinge\" axis=\"0 1 0\" damping=\"1\"/>"
           "<geom type=\"capsule\" fromto=\"0 0 0 0 0 -0.25\" size=\"0.045\" mass=\"3\"/>"
           "<body name=\"shin_" +
           s + "\" pos=\"0 0 -0.3\"><joint name=\"knee_" + s +
           "\" type=\"hinge\" axis=\"0 1 0\" limited=\"true\" range=\"0 2.5\" damping=\"1\"/>"
           "<geom type=\"capsule\" fromto=\"0 0 0 0 0 -0.25\" size=\"0.035\" mass=\"2\"/>"
           "</body></body>"
           "<body name=\"arm_" +
           s + "\" pos=\"0 " + ya + " 0.12\"><joint name=\"shoulder_" + s +
           "\" type=\"hinge\" axis=\"0 1 0\" damping=\"0.5\"/>"
           "<geom type=\"capsule\" fromto=\"0 0 0 0 0 -0.25\" size=\"0.03\" mass=\"1.5\"/></body>";
  }
  return xml + "</body></worldbody></mujoco>";
}

// the lowest point of every link geom of the model (capsules and spheres) at the collision
// stage's poses
double LowestLinkPoint(const Model& m, const Data& d) {
  double lowest = 1e9;
  const std::vector<geometry::GeomPose>& poses = d.workspace->collision.poses;
  for (std::size_t g = 0; g < m.geoms.size(); ++g) {
    const GeomModel& geom = m.geoms[g];
    if (geom.tree < 0) continue;
    double z = poses[g].p_W.z() - geom.size.x();
    if (geom.type == GeomType::kCapsule) {
      z -= std::abs(poses[g].R_WG(2, 2)) * geom.size.y();
    }
    lowest = std::min(lowest, z);
  }
  return lowest;
}

// The humanoid-like tree (35 kg) dropped from 5 cm onto the plane with the default (train)
// renderer stays above it for 2 s: its lowest point never sinks more than 1 cm below the floor
// (measured: ...), and the torso ends up resting on or above the floor. Without link-static
// pairs it falls through.
TEST(LinkContactTest, SmallHumanoidDroppedOnAPlaneStaysAboveIt) {
  LoadOptions o;
  o.tool_name = "none";
  const Model m = LoadModel(test::WriteTempFile("small_humanoid.xml", SmallHumanoidXml(0.05)), o);
  ASSERT_EQ(m.trees.size(), 1u);
  Data d = MakeData(m);
  const TickInput in;
  double lowest = 1e9;
  int floor_contacts = 0;
  for (int s = 0; s < 2000; ++s) {
    Tick(m, d, in);
    lowest = std::min(lowest, LowestLinkPoint(m, d));
    for (int i = 0; i < d.ncontact; ++i) {
      floor_contacts += m.geoms[d.contacts[i].geom_b].tree < 0;
    }
  }
  const double root_z = d.trees[0]->qpos[2];
  EXPECT_GT(floor_contacts, 0);
  EXPECT_GT(lowest, -1e-2) << "lowest point " << lowest << " m";
  EXPECT_GT(root_z, 0.05) << "the torso sank into the floor";
  std::printf("humanoid-like tree: lowest point %.4g m over 2 s, root height %.4g m\n", lowest,
              root_z);
}

// ticks with a tree resting on a floor (link-static rows, impulses at the landing) and links
// touching each other allocate nothing
TEST(LinkContactTest, NoHeapAllocationWithATreeOnAFloor) {
  if (!test::kMallocCounting) GTEST_SKIP() << "malloc is owned by the sanitizer";
  LoadOptions o;
  o.tool_name = "none";
  const Model m = LoadModel(test::WriteTempFile("humanoid_alloc.xml", SmallHumanoidXml(0.05)), o);
  Data d = MakeData(m);
  const TickInput in;
  int impulses = 0, contacts = 0;
  test::LimitMalloc guard;
  for (int s = 0; s < 1500; ++s) {
    Tick(m, d, in);
    impulses += d.nimpulse;
    contacts += d.ncontact;
  }
  EXPECT_EQ(guard.allocations(), 0);
  EXPECT_GT(impulses, 0);
  EXPECT_GT(contacts, 0);
}

}  // namespace
}  // namespace rigidtouch
