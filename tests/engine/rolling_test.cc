// Friction on bodies that roll and spin, against closed forms: a ball sliding on a floor (a scene
// contact, implicit) and the free tool sphere spinning on a floor (a tool contact, explicit). The
// stick anchors are placed at the contact point every tick; anchors kept on the bodies left the
// contact as the ball turned, so the spring resisted rolling and, its force acting at the contact
// point, did work its energy did not account for: the ball below gained 6 times its energy in 1 s
// and the spinning tool left the floor at 1 m/s. And a slip that one step of kinetic friction
// reverses sticks instead: a rolling ball's friction no longer flips sign every tick.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "rigidtouch/rigidtouch.h"
#include "test_util.h"

namespace rigidtouch {
namespace {

constexpr double kGravity = 9.81;

// a floor, a ball of radius `ball_r` and mass `ball_m` resting on it (body 0), and the tool
// sphere (5 mm, 0.1 kg, body 1) at `tool_pos`
std::string BallXml(double ball_r, double ball_m, const std::string& tool_pos) {
  return "<mujoco model=\"rolling\"><option timestep=\"0.001\" gravity=\"0 0 -9.81\"/>"
         "<worldbody><geom name=\"floor\" type=\"plane\" size=\"5 5 0.1\"/>"
         "<body name=\"ball\" pos=\"0 0 " +
         test::ExactNumber(ball_r) + "\"><freejoint/><geom type=\"sphere\" size=\"" +
         test::ExactNumber(ball_r) + "\" mass=\"" + test::ExactNumber(ball_m) +
         "\"/></body><body name=\"tool\" pos=\"" + tool_pos +
         "\"><freejoint/><geom name=\"tool\" type=\"sphere\" size=\"0.005\" mass=\"0.1\"/>"
         "</body></worldbody></mujoco>";
}

// kinetic energy of a solid sphere of mass m and radius r  [J]
double SphereEnergy(const BodyState& s, double m, double r) {
  return 0.5 * m * s.v_W.squaredNorm() + 0.5 * (0.4 * m * r * r) * s.w_W.squaredNorm();
}

// a body's contacts this tick: how many, the friction on the body, and the (last) contact
// point's offset from the body's centre
struct BallContact {
  int n = 0;
  Vec3 friction_W = Vec3::Zero();
  Vec3 r_W = Vec3::Zero();  // contact point from the centre
};
BallContact ContactOf(const Data& d, int body) {
  BallContact out;
  for (int ci = 0; ci < d.ncontact; ++ci) {
    const Contact& c = d.contacts[ci];
    if (c.body_a != body && c.body_b != body) continue;
    ++out.n;
    out.friction_W += c.body_a == body ? c.friction_force_N_W : Vec3(-c.friction_force_N_W);
    out.r_W = c.p_W - d.bodies[body].x_W;
  }
  return out;
}

// A solid ball (I = 2/5 m R^2) sliding without spin at v0 on a floor with friction mu: kinetic
// friction slows it at mu g and spins it up at 5 mu g / (2 R) until it rolls, at
// t* = 2 v0 / (7 mu g), with v = 5/7 v0; then it rolls on at that speed with no friction.
// Tolerances: the contact point lies d/2 = m g / (2 k) = 2.5 um inside the surface (1.2e-4 of R),
// so rolling is v = w (R - d/2); 1e-3 of v0 covers that and the discrete onset of rolling.
TEST(RollingTest, SlidingBallRollsAtFiveSeventhsOfItsSpeedWithoutGainingEnergy) {
  constexpr double kR = 0.02, kM = 0.1, kMu = 1.0, kV0 = 0.5;
  LoadOptions o;
  o.contact.friction_static = kMu;
  o.contact.friction_kinetic = kMu;
  const Model model = LoadModel(test::WriteTempFile("ball.xml", BallXml(kR, kM, "2 2 0.5")), o);
  Data data = MakeData(model);
  TickInput in;
  for (int k = 0; k < 200; ++k) Tick(model, data, in);  // settle into the floor
  ASSERT_LT(data.bodies[0].v_W.norm(), 1e-6);
  data.bodies[0].v_W = Vec3(kV0, 0.0, 0.0);
  data.bodies[0].w_W.setZero();

  const double t_roll = 2.0 * kV0 / (7.0 * kMu * kGravity);  // 29 ms
  double energy = SphereEnergy(data.bodies[0], kM, kR);
  double lowest = energy;
  const double kt = model.contact.tangential_ratio * model.contact.scene_stiffness_N_per_m;
  const double spring_max = std::pow(kMu * kM * kGravity, 2) / (2.0 * kt);
  int first_rolling_tick = -1;
  for (int k = 1; k <= 1000; ++k) {
    Tick(model, data, in);
    const BodyState& s = data.bodies[0];
    const double e = SphereEnergy(s, kM, kR);
    // friction never adds energy: the kinetic energy rises above its lowest so far by at most
    // what the anchor spring can hold and give back, (mu m g)^2 / (2 kt) = 2.4 uJ
    ASSERT_LE(e, lowest + spring_max) << "tick " << k;
    lowest = std::min(lowest, e);
    energy = e;
    const BallContact c = ContactOf(data, 0);
    ASSERT_EQ(c.n, 1) << "tick " << k;
    // the speed of the ball's material point at the contact (the contact point lies below the
    // centre; c.r_W also holds this tick's motion, as the point is found before the bodies move)
    const double slip = (s.v_W + s.w_W.cross(Vec3(0.0, 0.0, c.r_W.z()))).norm();
    if (first_rolling_tick < 0 && slip < 1e-3 * kV0) first_rolling_tick = k;
    EXPECT_LE(c.friction_W.norm(), kMu * kM * kGravity * (1.0 + 1e-9)) << "tick " << k;
    if (first_rolling_tick > 0) {
      // rolling: no slip from here on, and once the anchor spring has let go of the stretch it
      // had at the slip limit (10 ms: its period on the ball is 2.4 ms, damping ratio 0.66),
      // no friction either, in every tick (it used to flip between +-mu m g every tick)
      EXPECT_LT(slip, 1e-3 * kV0) << "tick " << k;
      if (k >= first_rolling_tick + 10) {
        EXPECT_LT(c.friction_W.norm(), 1e-3 * kMu * kM * kGravity) << "tick " << k;
      }
    }
  }
  ASSERT_GT(first_rolling_tick, 0);
  // friction of at most mu m g cannot make it roll sooner; the anchor spring's ringing at the
  // onset delays the measured onset by a few ticks
  EXPECT_GE(first_rolling_tick * model.timestep_s, t_roll - model.timestep_s);
  EXPECT_LE(first_rolling_tick * model.timestep_s, t_roll + 5.0 * model.timestep_s);
  const BodyState& s = data.bodies[0];
  EXPECT_NEAR(s.v_W.x(), 5.0 / 7.0 * kV0, 1e-3 * kV0);
  EXPECT_NEAR(s.w_W.y() * kR, 5.0 / 7.0 * kV0, 1e-3 * kV0);
  EXPECT_NEAR(s.v_W.y(), 0.0, 1e-9);
  // 5/14 m v0^2 is left of 1/2 m v0^2
  EXPECT_NEAR(energy, 5.0 / 14.0 * kM * kV0 * kV0, 2e-3 * kM * kV0 * kV0);
}

// The free tool sphere (no device coupling: offline simulation) pressed onto the floor by 2 N and
// spinning at w0 about a horizontal axis, without moving. Friction acts at the contact point, so
// the angular momentum about it, I w + m R_c v (R_c the centre's height above the contact
// point), keeps its value I w0, and the ball ends rolling: w R_c = v. Tolerance: the tool
// contact's anchor spring-damper (2000 N/m, 2 N s/m, damping ratio 0.13 on the ball's
// tangential effective mass) has rung down by e^-17 after 0.5 s; 1e-3 of w0 R.
TEST(RollingTest, SpinningToolSphereRollsOffWithItsAngularMomentumAboutTheContact) {
  constexpr double kR = 0.005, kM = 0.1, kW0 = 100.0;
  const Model model = LoadModel(
      test::WriteTempFile("tool.xml", BallXml(0.02, 0.1, "0.5 0 " + test::ExactNumber(kR))),
      LoadOptions{});
  Data data = MakeData(model);
  TickInput in;
  in.tool_wrench.force_N = Vec3(0.0, 0.0, -2.0);
  const int tool = model.tool;
  ASSERT_EQ(tool, 1);
  // pressed into the floor (2000 N/m, 2 N s/m: a damping ratio of 0.07), at rest after 2 s
  for (int k = 0; k < 2000; ++k) Tick(model, data, in);
  ASSERT_LT(data.bodies[tool].v_W.norm(), 1e-6);
  data.bodies[tool].w_W = Vec3(0.0, kW0, 0.0);
  const double inertia = 0.4 * kM * kR * kR;
  double energy = SphereEnergy(data.bodies[tool], kM, kR);
  const double energy0 = energy;
  for (int k = 1; k <= 500; ++k) {
    Tick(model, data, in);
    const double e = SphereEnergy(data.bodies[tool], kM, kR);
    // the applied force is vertical and the tool stays on the floor: nothing feeds it energy
    ASSERT_LE(e, energy0 + 1e-12) << "tick " << k;
    energy = e;
  }
  const BodyState& s = data.bodies[tool];
  const BallContact c = ContactOf(data, tool);
  ASSERT_EQ(c.n, 1);
  const double r_c = -c.r_W.z();  // the centre's height above the contact point
  ASSERT_GT(r_c, 0.5 * kR);
  // rolling, w y R_c = v x (spin about +y rolls the ball towards +x)
  EXPECT_NEAR(s.w_W.y() * r_c, s.v_W.x(), 1e-3 * kW0 * kR);
  // the angular momentum about the contact point: I w0 = I w + m R_c v
  EXPECT_NEAR(inertia * s.w_W.y() + kM * r_c * s.v_W.x(), inertia * kW0, 1e-3 * inertia * kW0);
  EXPECT_GT(s.v_W.x(), 0.1 * kW0 * kR);  // it rolled off, not stuck spinning
  EXPECT_LT(energy, energy0);
}

}  // namespace
}  // namespace rigidtouch
