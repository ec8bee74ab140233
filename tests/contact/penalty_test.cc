// The penalty law and the explicit contact of tick stage 4 against closed forms: the law of a
// contact, the normal force k d - b ddot(d) that never pulls, and Coulomb friction through the
// stick anchor (sticking inside the cone, sliding on its edge).
#include "contact/penalty.h"

#include <gtest/gtest.h>

#include "contact/contact_forces.h"
#include "contact/friction.h"
#include "dynamics/kinematics.h"

namespace rigidtouch::contact {
namespace {

// two geoms: geom 0 on body 0 (the tool unless `tool` is false), geom 1 static
Model TwoGeomModel(bool tool, double mu_0, double mu_1) {
  Model m;
  m.bodies.resize(2);
  for (BodyModel& b : m.bodies) {
    b.mass_kg = 0.5;
    b.inertia_kgm2 = Vec3(1e-3, 1e-3, 1e-3);
  }
  m.tool = tool ? 0 : 1;
  m.geoms.resize(2);
  m.geoms[0].body = 0;
  m.geoms[0].friction = mu_0;
  m.geoms[1].body = -1;
  m.geoms[1].friction = mu_1;
  m.timestep_s = 1e-3;
  return m;
}

Contact PlaneContact(double depth_m, int points = 1) {
  Contact c;
  c.geom_a = 0;
  c.geom_b = 1;
  c.body_a = 0;
  c.body_b = -1;
  c.n_W = Vec3::UnitZ();
  c.depth_m = depth_m;
  c.pair_points = points;
  return c;
}

TEST(PenaltyTest, ToolContactTakesTheHapticStiffnessSharedByThePairsPoints) {
  Model m = TwoGeomModel(true, 0.3, 0.5);
  m.contact.stiffness_N_per_m = 1200.0;
  m.contact.damping_Ns_per_m = 3.0;
  m.contact.tangential_ratio = 0.5;
  const PenaltyLaw law = LawFor(m, PlaneContact(1e-3, 4));
  EXPECT_FALSE(law.implicit);
  EXPECT_DOUBLE_EQ(law.k_N_per_m, 300.0);  // 1200 / 4 points
  EXPECT_DOUBLE_EQ(law.b_Ns_per_m, 0.75);
  EXPECT_DOUBLE_EQ(law.kt_N_per_m, 150.0);
  EXPECT_DOUBLE_EQ(law.bt_Ns_per_m, 0.375);
  // MuJoCo's rule: the larger of the two geoms' friction, static = kinetic
  EXPECT_DOUBLE_EQ(law.mu_kinetic, 0.5);
  EXPECT_DOUBLE_EQ(law.mu_static, 0.5);
}

TEST(PenaltyTest, SceneContactIsImplicitWithTheSceneStiffnessAndConfiguredFriction) {
  Model m = TwoGeomModel(false, 0.3, 0.5);
  m.contact.scene_stiffness_N_per_m = 2e5;
  m.contact.scene_damping_Ns_per_m = 100.0;
  m.contact.friction_static = 0.6;
  m.contact.friction_kinetic = 0.4;
  const PenaltyLaw law = LawFor(m, PlaneContact(1e-3));
  EXPECT_TRUE(law.implicit);
  EXPECT_DOUBLE_EQ(law.k_N_per_m, 2e5);
  EXPECT_DOUBLE_EQ(law.b_Ns_per_m, 100.0);
  EXPECT_DOUBLE_EQ(law.mu_static, 0.6);
  EXPECT_DOUBLE_EQ(law.mu_kinetic, 0.4);
}

TEST(PenaltyTest, NormalForceIsSpringDamperThatNeverPulls) {
  PenaltyLaw law;
  law.k_N_per_m = 1000.0;
  law.b_Ns_per_m = 2.0;
  // approaching at 0.1 m/s, 2 mm deep: 1000 * 0.002 + 2 * 0.1 = 2.2 N
  EXPECT_DOUBLE_EQ(NormalForce(law, 2e-3, -0.1), 2.2);
  // separating at 0.5 m/s: 2 - 1 = 1 N
  EXPECT_DOUBLE_EQ(NormalForce(law, 2e-3, 0.5), 1.0);
  // separating faster than the spring pushes: zero, never negative
  EXPECT_EQ(NormalForce(law, 2e-3, 5.0), 0.0);
  EXPECT_EQ(NormalForce(law, -1e-3, 0.0), 0.0);
}

struct OneContact {
  Model model = TwoGeomModel(true, 0.5, 0.5);
  Data data;
  dynamics::VelocityScratch forces;
  PenaltyLaw law;

  OneContact(double depth_m, const Vec3& v_W, const Vec3& stretch_W) {
    model.contact.stiffness_N_per_m = 1000.0;
    model.contact.damping_Ns_per_m = 2.0;
    model.contact.tangential_ratio = 1.0;
    data.bodies.resize(2);
    data.R_WB.resize(2);
    data.bodies[0].x_W = Vec3(0.0, 0.0, 0.01 - depth_m);
    data.bodies[0].v_W = v_W;
    dynamics::ComputeKinematics(data);
    Contact c = PlaneContact(depth_m);
    c.p_W = Vec3(0.0, 0.0, -depth_m / 2);
    c.p_A = c.p_W - data.bodies[0].x_W;
    c.p_B = c.p_W;
    // the anchor on a is where the contact point was before the stretch
    c.anchor_A = c.p_A;
    c.anchor_B = c.p_B - stretch_W;
    data.contacts.push_back(c);
    data.ncontact = 1;
    forces.Reserve(2, 1, 2);
    for (int i = 0; i < 2; ++i) forces.force_W[i] = forces.torque_W[i] = Vec3::Zero();
    law = LawFor(model, c);
  }
};

TEST(PenaltyTest, StickingContactHoldsWithTheAnchorSpringInsideTheCone) {
  // 2 mm deep at rest: fn = 2 N; a 0.5 mm stretch along x: |ft| = 0.5 N < mu fn = 1 N
  OneContact t(2e-3, Vec3::Zero(), Vec3(5e-4, 0.0, 0.0));
  ExplicitContact(t.data, t.law, 0, t.forces);
  const Contact& c = t.data.contacts[0];
  EXPECT_TRUE(c.sticking);
  EXPECT_NEAR(c.normal_force_N, 2.0, 1e-12);
  EXPECT_NEAR(c.friction_force_N_W.x(), -0.5, 1e-12);
  EXPECT_NEAR(c.friction_force_N_W.y(), 0.0, 1e-12);
  EXPECT_NEAR(c.friction_force_N_W.z(), 0.0, 1e-12);
  // the body gets the force and its moment about the centre of mass
  const Vec3 f = c.normal_force_N * c.n_W + c.friction_force_N_W;
  EXPECT_TRUE(t.forces.force_W[0].isApprox(f, 1e-12));
  const Vec3 r = c.p_W - t.data.bodies[0].x_W;
  EXPECT_TRUE(t.forces.torque_W[0].isApprox(r.cross(f), 1e-12));
}

TEST(PenaltyTest, SlidingContactIsOnTheConesEdgeAndItsAnchorFollows) {
  // sliding along +y at 0.2 m/s with a 5 mm stretch: the trial force 5 + 0.4 N is outside the
  // cone mu fn = 0.5 * 2 N (at rest along the normal), so |ft| = 1 N against the trial force
  OneContact t(2e-3, Vec3(0.0, 0.2, 0.0), Vec3(0.0, 5e-3, 0.0));
  ExplicitContact(t.data, t.law, 0, t.forces);
  const Contact& c = t.data.contacts[0];
  EXPECT_FALSE(c.sticking);
  EXPECT_NEAR(c.normal_force_N, 2.0, 1e-12);
  EXPECT_NEAR(c.friction_force_N_W.norm(), 0.5 * 2.0, 1e-12);
  EXPECT_NEAR(c.friction_force_N_W.y(), -1.0, 1e-12);
  // the anchor slid: the spring alone now exerts the kinetic force, kt |s| = mu fn
  const Vec3 s = AnchorDisplacement(t.data, c);
  EXPECT_NEAR(t.law.kt_N_per_m * s.norm(), 1.0, 1e-12);
}

TEST(PenaltyTest, UnloadedContactReleasesItsAnchor) {
  // touching but separating fast: no force, and the anchor is put back on the contact point
  OneContact t(1e-4, Vec3(0.0, 0.0, 1.0), Vec3(1e-3, 0.0, 0.0));
  ExplicitContact(t.data, t.law, 0, t.forces);
  const Contact& c = t.data.contacts[0];
  EXPECT_EQ(c.normal_force_N, 0.0);
  EXPECT_EQ(c.friction_force_N_W, Vec3::Zero());
  EXPECT_FALSE(c.sticking);
  EXPECT_EQ(c.anchor_B, c.p_B);
  EXPECT_EQ(t.forces.force_W[0], Vec3::Zero());
}

}  // namespace
}  // namespace rigidtouch::contact
