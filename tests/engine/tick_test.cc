// Closed-form checks of the whole tick: impulses (Eq. 5, Eq. 8) on real contact geometry.
#include <gtest/gtest.h>

#include <cmath>

#include "engine/workspace.h"
#include "rigidtouch/rigidtouch.h"
#include "test_util.h"

namespace rigidtouch {
namespace {

using test::TestScene;

// no penalty, no gravity: only impulses change the velocities (scene files set gravity; the
// tests zero it in the model so one file serves several cases)
Model ImpulseOnlyModel(const std::string& scene, RendererKind kind, double e = 0.0,
                       double f = 250.0) {
  LoadOptions o;
  o.contact.stiffness_N_per_m = 0.0;
  o.contact.damping_Ns_per_m = 0.0;
  o.contact.scene_stiffness_N_per_m = 0.0;
  o.contact.scene_damping_Ns_per_m = 0.0;
  o.contact.friction_static = 0.0;
  o.contact.friction_kinetic = 0.0;
  o.render.renderer = kind;
  o.render.restitution = e;
  o.render.frequency_hz = f;
  Model m = LoadModel(scene, o);
  m.gravity_W.setZero();
  return m;
}

// ticks until the first impulse; returns false if none within `max_steps`
bool TickUntilImpulse(const Model& m, Data& d, int max_steps = 100) {
  for (int s = 0; s < max_steps; ++s) {
    Tick(m, d, {});
    if (d.nimpulse > 0) return true;
  }
  return false;
}

// single sphere-plane contact, Eq. 5: p = -(1+e) m v_n, post-impulse normal velocity -e v_n
TEST(TickTest, SphereOnPlaneSingleImpulseRestitution) {
  for (const double e : {0.0, 0.5, 1.0}) {
    const Model m = ImpulseOnlyModel(TestScene("sphere_plane.xml"), RendererKind::kImpulse, e);
    Data d = MakeData(m);
    const double v_n = -0.3;  // approaching the floor
    d.bodies[m.tool].v_W = Vec3(0.0, 0.0, v_n);
    ASSERT_TRUE(TickUntilImpulse(m, d)) << "e = " << e;
    const double mass = m.bodies[m.tool].mass_kg;
    // tolerance: 1e-9 relative, the solver's regularisation
    EXPECT_NEAR(d.bodies[m.tool].v_W.z(), -e * v_n, 1e-9) << "e = " << e;
    EXPECT_NEAR(d.impulses[0].tool_impulse_Ns_W.z(), -(1.0 + e) * mass * v_n, 1e-9) << "e = " << e;
    EXPECT_EQ(d.impulses[0].contacts, 1);
    EXPECT_LE(d.impulses[0].kinetic_energy_after_J, d.impulses[0].kinetic_energy_before_J + 1e-15);
  }
}

// a train with k = 0, no gravity and no user force: after impulse i the approach speed is
// v0 (N - i) / N (each impulse removes 1/(N-i+1) of what is left)
TEST(TickTest, TrainWithoutPenaltyRemovesEqualShares) {
  const Model m = ImpulseOnlyModel(TestScene("sphere_plane.xml"), RendererKind::kTrain, 0.0, 250.0);
  ASSERT_EQ(m.schedule.impulses, 25);
  Data d = MakeData(m);
  const double v0 = 0.05;  // slow enough to stay in contact through the window
  d.bodies[m.tool].v_W = Vec3(0.0, 0.0, -v0);
  int seen = 0;
  std::int64_t last_step = -1;
  for (int s = 0; s < 200 && seen < 25; ++s) {
    Tick(m, d, {});
    if (d.nimpulse == 0) continue;
    ++seen;
    if (last_step >= 0) {
      EXPECT_EQ(d.impulses[0].step - last_step, 4);
    }
    last_step = d.impulses[0].step;
    EXPECT_EQ(d.impulses[0].index, seen);
    const double expected = v0 * (25 - seen) / 25.0;
    EXPECT_NEAR(-d.bodies[m.tool].v_W.z(), expected, 1e-9 * v0) << "impulse " << seen;
  }
  EXPECT_EQ(seen, 25);
  EXPECT_NEAR(d.bodies[m.tool].v_W.z(), 0.0, 1e-12);
}

// redundant contacts: a box landing flat on a plane stops with zero normal velocity at every
// contact and no angular velocity
TEST(TickTest, BoxLandingFlatStopsWithoutSpin) {
  LoadOptions o;
  const Model m = ImpulseOnlyModel(TestScene("box_plane.xml"), RendererKind::kImpulse, 0.0);
  Data d = MakeData(m);
  d.bodies[0].v_W = Vec3(0.0, 0.0, -0.4);
  ASSERT_TRUE(TickUntilImpulse(m, d));
  EXPECT_GE(d.impulses[0].contacts, 4);  // the face gives a manifold, not one point
  EXPECT_NEAR(d.bodies[0].v_W.z(), 0.0, 1e-9);
  EXPECT_NEAR(d.bodies[0].w_W.norm(), 0.0, 1e-9);
  for (int c = 0; c < d.ncontact; ++c) {
    const Contact& con = d.contacts[c];
    const Vec3 r = con.p_W - d.bodies[0].x_W;  // after integration; the velocity is zero anyway
    const Vec3 v = d.bodies[0].v_W + d.bodies[0].w_W.cross(r);
    EXPECT_NEAR(v.dot(con.n_W), 0.0, 1e-9);
  }
}

// two free bodies head-on with e = 0 move on with the common velocity (m1 v1 + m2 v2)/(m1 + m2)
TEST(TickTest, HeadOnPlasticCollisionGivesCommonVelocity) {
  const Model m = ImpulseOnlyModel(TestScene("two_spheres.xml"), RendererKind::kImpulse, 0.0);
  Data d = MakeData(m);
  const double m1 = 0.2, v1 = 0.5, m2 = 0.3, v2 = -0.2;
  ASSERT_TRUE(TickUntilImpulse(m, d));
  const double common = (m1 * v1 + m2 * v2) / (m1 + m2);
  EXPECT_NEAR(d.bodies[0].v_W.x(), common, 1e-9);
  EXPECT_NEAR(d.bodies[1].v_W.x(), common, 1e-9);
  // momentum is conserved exactly by equal and opposite impulses
  EXPECT_NEAR(m1 * d.bodies[0].v_W.x() + m2 * d.bodies[1].v_W.x(), m1 * v1 + m2 * v2, 1e-12);
}

// the tool striking the top of a stack resting on a static floor, e = 0: every velocity into the
// floor becomes zero (a box on a table is as hard as the table)
TEST(TickTest, StrikeOnStackIsAsHardAsTheFloor) {
  const Model m = ImpulseOnlyModel(TestScene("stack3.xml"), RendererKind::kImpulse, 0.0);
  Data d = MakeData(m);
  // overlap every interface by 1 um so the resting contacts exist, and let the tool arrive
  for (int i = 0; i < 3; ++i) d.bodies[i].x_W.z() = 0.025 + 0.05 * i - 1e-6 * (i + 1);
  d.bodies[m.tool].x_W.z() = 0.15 + 0.005 - 1e-6 * 3 - 1e-6;
  d.bodies[m.tool].v_W = Vec3(0.0, 0.0, -0.3);
  ASSERT_TRUE(TickUntilImpulse(m, d, 1));
  EXPECT_EQ(d.impulses[0].tool, true);
  EXPECT_GE(d.impulses[0].contacts, 1 + 3 * 4);
  for (int i = 0; i < 4; ++i) {
    EXPECT_NEAR(d.bodies[i].v_W.z(), 0.0, 1e-9) << m.bodies[i].name;
    EXPECT_NEAR(d.bodies[i].w_W.norm(), 0.0, 1e-9) << m.bodies[i].name;
  }
  // the tool felt the whole plastic impulse m v
  EXPECT_NEAR(d.impulses[0].tool_impulse_Ns_W.z(), 0.1 * 0.3, 1e-9);
}

// penalty renderer: never an impulse
TEST(TickTest, PenaltyRendererAppliesNoImpulse) {
  const Model m = ImpulseOnlyModel(TestScene("sphere_plane.xml"), RendererKind::kPenalty);
  Data d = MakeData(m);
  d.bodies[m.tool].v_W = Vec3(0.0, 0.0, -0.3);
  EXPECT_FALSE(TickUntilImpulse(m, d, 50));
  EXPECT_GT(d.tool_contacts, 0);
}

// Eq. 9: the impulsive force shown to the device is the tool's impulse over one step
TEST(TickTest, ImpulsiveForceIsImpulseOverStep) {
  const Model m = ImpulseOnlyModel(TestScene("sphere_plane.xml"), RendererKind::kImpulse, 0.0);
  Data d = MakeData(m);
  d.bodies[m.tool].v_W = Vec3(0.0, 0.0, -0.2);
  DeviceCommand out;
  for (int s = 0; s < 100; ++s) {
    out = Tick(m, d, {});
    if (d.nimpulse > 0) break;
  }
  ASSERT_GT(d.nimpulse, 0);
  EXPECT_NEAR(out.impulsive_force_N.z(), 0.1 * 0.2 / m.timestep_s, 1e-6);
  EXPECT_NEAR((out.force_N - out.penalty_force_N - out.impulsive_force_N).norm(), 0.0, 1e-12);
}

// bad device input inside the loop: no throw, zero force, counted
TEST(TickTest, NonFiniteInputGivesSafeZeroForce) {
  const Model m = ImpulseOnlyModel(TestScene("sphere_plane.xml"), RendererKind::kPenalty);
  Data d = MakeData(m);
  TickInput in;
  in.tool_wrench.force_N = Vec3(NAN, 0.0, 0.0);
  const DeviceCommand out = Tick(m, d, in);
  EXPECT_TRUE(out.safe_fallback);
  EXPECT_EQ(out.force_N, Vec3::Zero());
  EXPECT_EQ(d.warnings[static_cast<int>(Warning::kBadDeviceState)].count, 1);
  EXPECT_TRUE(d.bodies[m.tool].x_W.allFinite());
}

// a non-finite state inside the loop puts every part of the state back to initial (bodies,
// contacts, windows, the group solver's kept factor), as ResetData does, and keeps the time and
// the warnings: the run then repeats a fresh run bit for bit
TEST(TickTest, NonFiniteStateResetsTheWholeStateToInitial) {
  LoadOptions o;
  o.render.renderer = RendererKind::kTrain;
  const Model m = LoadModel(std::string(RIGIDTOUCH_SCENES) + "/stack.xml", o);
  Data d = MakeData(m);
  TickInput in;
  in.tool_wrench.force_N = Vec3(0.0, 0.0, -2.0);
  int impulses = 0;
  for (int s = 0; s < 400; ++s) {
    Tick(m, d, in);
    impulses += d.nimpulse;
  }
  ASSERT_GT(impulses, 0);  // windows were opened
  const std::int64_t step = d.step;
  d.bodies[3].v_W.x() = NAN;
  const DeviceCommand out = Tick(m, d, in);
  EXPECT_TRUE(out.safe_fallback);
  EXPECT_EQ(out.force_N, Vec3::Zero());
  EXPECT_EQ(d.warnings[static_cast<int>(Warning::kNonFiniteState)].count, 1);
  EXPECT_EQ(d.step, step + 1);  // the time goes on
  EXPECT_EQ(d.ncontact, 0);
  EXPECT_EQ(d.workspace->collision.matching.nprevious, 0);
  EXPECT_EQ(d.workspace->collision.matching.next_contact_id, 0);
  for (std::size_t i = 0; i < d.bodies.size(); ++i) {
    EXPECT_EQ(d.bodies[i].x_W, m.initial[i].x_W);
    EXPECT_EQ(d.bodies[i].v_W, m.initial[i].v_W);
    EXPECT_EQ(d.window[i].onset_step, -1);
    EXPECT_EQ(d.R_WB[i], m.initial[i].q_WB.toRotationMatrix());
  }
  Data fresh = MakeData(m);
  for (int s = 0; s < 400; ++s) {
    const DeviceCommand a = Tick(m, d, in);
    const DeviceCommand b = Tick(m, fresh, in);
    ASSERT_EQ(a.force_N, b.force_N) << "tick " << s;
  }
  for (std::size_t i = 0; i < d.bodies.size(); ++i) {
    EXPECT_EQ(d.bodies[i].x_W, fresh.bodies[i].x_W) << "body " << i;
    EXPECT_EQ(d.bodies[i].w_W, fresh.bodies[i].w_W) << "body " << i;
  }
}

// each contact's phase: colliding inside its group's window, resting outside it
TEST(TickTest, ContactPhaseFollowsTheCollisionWindow) {
  const Model m = ImpulseOnlyModel(TestScene("sphere_plane.xml"), RendererKind::kTrain, 0.0, 250.0);
  Data d = MakeData(m);
  d.bodies[m.tool].v_W = Vec3(0.0, 0.0, -0.3);
  ASSERT_TRUE(TickUntilImpulse(m, d));
  ASSERT_GT(d.ncontact, 0);
  EXPECT_EQ(d.contacts[0].phase, ContactPhase::kColliding);
  // past the window (t_c = 0.1 s by default) the contact rests, if it is still there
  const int window = m.schedule.window_steps;
  bool rested = false;
  for (int s = 0; s < window + 5 && !rested; ++s) {
    Tick(m, d, {});
    const bool inside = d.step - 1 - d.window[m.tool].onset_step < window;
    for (int k = 0; k < d.ncontact; ++k) {
      EXPECT_EQ(d.contacts[k].phase, inside ? ContactPhase::kColliding : ContactPhase::kResting);
      rested = rested || !inside;
    }
  }
  EXPECT_TRUE(rested);
}

// the impulse solver's hint (WindowState::interior) lives while the group keeps colliding: an
// onset less than 0.1 s after the last one keeps it, a later one clears it. The event renderer
// marks onsets but solves no impulse, so only the window's rule changes the hint here
TEST(TickTest, SolverHintLastsWhileTheGroupKeepsColliding) {
  LoadOptions o;
  o.contact.stiffness_N_per_m = 0.0;  // nothing but the hand's velocity moves the tool
  o.contact.damping_Ns_per_m = 0.0;
  o.render.renderer = RendererKind::kEvent;
  o.render.material = {"test", 20.0, 60.0, 100.0};
  Model m = LoadModel(TestScene("sphere_plane.xml"), o);
  m.gravity_W.setZero();
  const auto window = std::lround(0.1 / m.timestep_s);
  ASSERT_EQ(window, 100);
  Data d = MakeData(m);
  const Vec3 down(0.0, 0.0, -0.3);
  d.bodies[m.tool].v_W = down;
  d.window[m.tool].interior = true;
  auto tick_until_onset = [&]() {
    for (int s = 0; s < 1000; ++s) {
      Tick(m, d, {});
      if (d.window[m.tool].onset_step == d.step - 1) return true;
    }
    return false;
  };
  // the first onset of all: nothing to keep
  ASSERT_TRUE(tick_until_onset());
  EXPECT_FALSE(d.window[m.tool].interior);
  const double z_contact_m = d.bodies[m.tool].x_W.z();
  // lifted 3 mm and moving down at 0.3 m/s: the next onset comes about 10 steps later
  d.window[m.tool].interior = true;
  std::int64_t last_onset = d.window[m.tool].onset_step;
  d.bodies[m.tool].x_W.z() = z_contact_m + 0.003;
  d.bodies[m.tool].v_W = down;
  ASSERT_TRUE(tick_until_onset());
  ASSERT_LT(d.window[m.tool].onset_step - last_onset, window);
  EXPECT_TRUE(d.window[m.tool].interior);
  // lifted 45 mm: the next onset comes about 150 steps later, after 0.1 s
  last_onset = d.window[m.tool].onset_step;
  d.bodies[m.tool].x_W.z() = z_contact_m + 0.045;
  d.bodies[m.tool].v_W = down;
  ASSERT_TRUE(tick_until_onset());
  ASSERT_GE(d.window[m.tool].onset_step - last_onset, window);
  EXPECT_FALSE(d.window[m.tool].interior);
}

}  // namespace
}  // namespace rigidtouch
