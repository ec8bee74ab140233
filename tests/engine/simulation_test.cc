// Whole-simulation sanity checks over seconds of simulated time (issue: simulation sanity).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "rigidtouch/rigidtouch.h"
#include "test_util.h"

namespace rigidtouch {
namespace {

using test::TestScene;

void SimulateFor(const Model& m, Data& d, double seconds, const Vec3& tool_force = Vec3::Zero()) {
  TickInput in;
  in.tool_wrench.force_N = tool_force;
  const long steps = std::lround(seconds / m.timestep_s);
  for (long s = 0; s < steps; ++s) Tick(m, d, in);
}

int BodyIndex(const Model& m, const std::string& name) {
  for (std::size_t i = 0; i < m.bodies.size(); ++i) {
    if (m.bodies[i].name == name) return static_cast<int>(i);
  }
  ADD_FAILURE() << "no body " << name;
  return 0;
}

// a box resting on a plane for 10 s drifts less than 0.1 mm
TEST(SimulationTest, BoxRestingOnPlaneDriftsLessThanATenthOfAMillimetre) {
  const Model m = LoadModel(TestScene("box_plane.xml"), {});
  Data d = MakeData(m);
  const Vec3 start = m.initial[0].x_W;
  SimulateFor(m, d, 10.0);
  EXPECT_LT((d.bodies[0].x_W - start).norm(), 1e-4);
  EXPECT_LT(d.bodies[0].w_W.norm(), 1e-3);  // no spurious spin
  // it rests flat: orientation within 0.1 degree of the initial one
  EXPECT_LT(d.bodies[0].q_WB.angularDistance(m.initial[0].q_WB), 0.1 * M_PI / 180.0);
}

// a stack of 10 boxes stands for 10 s with the tool pressing on top with 2 N: the top box
// moves less than 1 mm
TEST(SimulationTest, StackOfTenStandsForTenSeconds) {
  const Model m = LoadModel(TestScene("stack10.xml"), {});
  Data d = MakeData(m);
  const int top = BodyIndex(m, "box_9");
  const Vec3 start = m.initial[top].x_W;
  SimulateFor(m, d, 10.0, Vec3(0.0, 0.0, -2.0));
  EXPECT_LT((d.bodies[top].x_W - start).norm(), 1e-3);
  for (const BodyState& s : d.bodies) EXPECT_TRUE(s.x_W.allFinite());
}

// Nudges the top box of the pressed 10-box stack (1e-2 rad/s about y at 1 s), then runs to
// `seconds`, the tool held from rotating (as a device's handle would hold it) or free. Returns the
// top box's largest sideways distance from the axis after the nudge, and sets its final one.
double NudgedStack(double seconds, bool hold_tool, double& final_m) {
  const Model m = LoadModel(TestScene("stack10.xml"), {});
  Data d = MakeData(m);
  const int top = BodyIndex(m, "box_9");
  TickInput in;
  in.tool_wrench.force_N = Vec3(0.0, 0.0, -2.0);
  const long steps = std::lround(seconds / m.timestep_s);
  double largest_m = 0.0;
  for (long s = 0; s < steps; ++s) {
    if (s == 1000) d.bodies[top].w_W.y() += 1e-2;
    if (hold_tool) d.bodies[m.tool].w_W.setZero();
    Tick(m, d, in);
    final_m = std::hypot(d.bodies[top].x_W.x(), d.bodies[top].x_W.y());
    if (s >= 1000) largest_m = std::max(largest_m, final_m);
  }
  return largest_m;
}

// The pressed stack is a physically unstable system because of the tool alone: a free sphere
// rolls towards the low side of a tilted top face, and its load there tilts the column further.
// With the tool held from rotating, a nudge dies out and the stack stands for 30 s (measured:
// at most 1.6e-7 m sideways, 1.1e-8 m at the end; bounds 1e-6 and 1e-7 m); the same nudge with a
// free tool moves the top box by millimetres within 15 s (measured 4.5 mm by 10 s), so the held
// case is tested against a disturbance that matters. docs/performance.md: the benchmark's stack
// has this mode.
TEST(SimulationTest, PressedStackStandsForThirtySecondsWhenTheToolCannotRoll) {
  double final_m = 0.0;
  const double held_m = NudgedStack(30.0, true, final_m);
  EXPECT_LT(held_m, 1e-6);
  EXPECT_LT(final_m, 1e-7);
  const double free_m = NudgedStack(15.0, false, final_m);
  EXPECT_GT(free_m, 1e-3);
}

// Virtual coupling drags the tool sphere over a rough floor at 50 mm/s, the device 2 mm below the
// height at which the tool rests on the floor. The tool turns with the handle (here: not at all),
// so it slides, and the coupling carries the contact's kinetic friction mu N, steady: over the
// second second of sliding the ratio of the coupling's sideways force to the contact's normal force
// is mu = 0.4 within 1e-9 (equal static and kinetic coefficients, so the anchor slips every tick).
// The tool's spin never exceeds what one tick's largest friction torque gives, h mu N_max r / I
// with I = 2/5 m r^2 (measured 2.5 rad/s against a bound of 5.6). A tool free to turn rolls and
// stick-slips instead: with the same input that ratio swung between -0.81 and +0.65 and the tool
// spun at up to 129 rad/s.
TEST(SimulationTest, VirtualCouplingDragsTheToolWithSteadyKineticFriction) {
  constexpr double kMu = 0.4;
  LoadOptions o;
  o.device.coupling = Coupling::kVirtual;
  o.contact.friction_static = o.contact.friction_kinetic = kMu;
  const Model m = LoadModel(TestScene("sphere_plane.xml"), o);
  Data d = MakeData(m);
  TickInput in;
  double lowest = 1e9, highest = -1e9, fastest_spin_radps = 0.0, largest_normal_N = 0.0;
  for (int s = 0; s < 3000; ++s) {
    const double t_s = s * m.timestep_s;
    const bool moving = t_s > 1.0;
    in.device.position_m = Vec3(moving ? 0.05 * (t_s - 1.0) : 0.0, 0.0, 0.003);
    in.device.velocity_mps = Vec3(moving ? 0.05 : 0.0, 0.0, 0.0);
    Tick(m, d, in);
    fastest_spin_radps = std::max(fastest_spin_radps, d.bodies[m.tool].w_W.norm());
    if (d.ncontact > 0) largest_normal_N = std::max(largest_normal_N, d.contacts[0].normal_force_N);
    if (t_s < 2.0) continue;
    ASSERT_EQ(d.ncontact, 1);
    ASSERT_GT(d.contacts[0].normal_force_N, 0.5);
    const double ratio = d.tool_coupling_force_N_W.x() / d.contacts[0].normal_force_N;
    lowest = std::min(lowest, ratio);
    highest = std::max(highest, ratio);
  }
  EXPECT_NEAR(lowest, kMu, 1e-9);
  EXPECT_NEAR(highest, kMu, 1e-9);
  double r_m = 0.0;
  for (const GeomModel& g : m.geoms) {
    if (g.body == m.tool) r_m = g.size.x();
  }
  const double inertia = 0.4 * m.bodies[m.tool].mass_kg * r_m * r_m;
  EXPECT_LE(fastest_spin_radps, m.timestep_s * kMu * largest_normal_N * r_m / inertia);
}

// a sphere pressed with 2 N (no gravity) settles at penetration 2/k within 1%
TEST(SimulationTest, PressedSphereSettlesAtForceOverStiffness) {
  for (const RendererKind kind : {RendererKind::kPenalty, RendererKind::kTrain}) {
    LoadOptions o;
    o.render.renderer = kind;
    Model m = LoadModel(TestScene("sphere_plane.xml"), o);
    m.gravity_W.setZero();
    Data d = MakeData(m);
    SimulateFor(m, d, 3.0, Vec3(0.0, 0.0, -2.0));
    const double expected = 2.0 / m.contact.stiffness_N_per_m;
    EXPECT_NEAR(d.tool_penetration_m, expected, 0.01 * expected);
    // and the device is shown the force that holds it: 2 N up
    EXPECT_NEAR(d.tool_penalty_force_N_W.z(), 2.0, 0.02);
  }
}

// a box on a 20 degree incline stays put with friction 0.5 and slides with friction 0.2 at
// acceleration g (sin 20 - 0.2 cos 20) within 5%
TEST(SimulationTest, InclineStickAndSlide) {
  const double theta = 20.0 * M_PI / 180.0;
  // the ramp's normal is (sin, 0, cos): downhill is +x and down
  const Vec3 downhill(std::cos(theta), 0.0, -std::sin(theta));
  {
    LoadOptions o;
    o.contact.friction_static = o.contact.friction_kinetic = 0.5;
    const Model m = LoadModel(TestScene("incline.xml"), o);
    Data d = MakeData(m);
    SimulateFor(m, d, 0.2);
    const Vec3 settled = d.bodies[0].x_W;
    SimulateFor(m, d, 2.0);
    EXPECT_LT((d.bodies[0].x_W - settled).norm(), 1e-4) << "the box crept with friction 0.5";
  }
  {
    LoadOptions o;
    o.contact.friction_static = o.contact.friction_kinetic = 0.2;
    const Model m = LoadModel(TestScene("incline.xml"), o);
    Data d = MakeData(m);
    SimulateFor(m, d, 0.2);
    const double v1 = d.bodies[0].v_W.dot(downhill);
    SimulateFor(m, d, 0.5);
    const double v2 = d.bodies[0].v_W.dot(downhill);
    const double a = (v2 - v1) / 0.5;
    const double expected = 9.81 * (std::sin(theta) - 0.2 * std::cos(theta));
    EXPECT_NEAR(a, expected, 0.05 * expected);
  }
}

}  // namespace
}  // namespace rigidtouch
