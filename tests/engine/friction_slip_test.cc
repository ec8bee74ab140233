// Coulomb friction between scene bodies (implicit contacts) from the first step of sliding
// (issue 16, item 1), against closed forms: a box sliding on a plane, a box landing while sliding,
// and a box on an incline just below and just above the friction angle. Scenes are generated
// here: a 0.2 kg box of half-size 25 mm on a floor (or a ramp), the tool resting far away.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <tuple>

#include "rigidtouch/rigidtouch.h"
#include "test_util.h"

namespace rigidtouch {
namespace {

constexpr double kG = 9.81;
constexpr double kMu = 0.45;  // static = kinetic
constexpr double kMass = 0.2;

// a box on a plane tilted by theta about y (normal (sin, 0, cos); downhill +x), its centre
// `lift` above the resting height along the normal
std::string BoxXml(double theta_rad, double lift_m) {
  const double deg = theta_rad * 180.0 / M_PI;
  const double r = 0.025 + lift_m;
  return "<mujoco model=\"friction\"><option timestep=\"0.001\" gravity=\"0 0 -9.81\"/>"
         "<worldbody><geom name=\"floor\" type=\"plane\" size=\"2 2 0.1\" euler=\"0 " +
         test::ExactNumber(deg) + " 0\"/><body name=\"box\" pos=\"" +
         test::ExactNumber(r * std::sin(theta_rad)) + " 0 " +
         test::ExactNumber(r * std::cos(theta_rad)) + "\" euler=\"0 " + test::ExactNumber(deg) +
         " 0\"><freejoint/><geom type=\"box\" size=\"0.025 0.025 0.025\" mass=\"" +
         test::ExactNumber(kMass) +
         "\"/></body><body name=\"tool\" pos=\"0 1.5 0.5\"><freejoint/>"
         "<geom type=\"sphere\" size=\"0.005\" mass=\"0.1\"/></body></worldbody></mujoco>";
}

Model LoadBox(const std::string& name, double theta_rad, double lift_m, double mu_static = kMu,
              double mu_kinetic = kMu) {
  LoadOptions o;
  o.contact.friction_static = mu_static;
  o.contact.friction_kinetic = mu_kinetic;
  return LoadModel(test::WriteTempFile(name + ".xml", BoxXml(theta_rad, lift_m)), o);
}

// the box's contacts this tick: the sum of their normal forces and the norm of their friction
// forces' resultant (the box is body a or b; the friction on the box either way)
struct BoxContact {
  int n = 0;
  double normal_N = 0.0;
  Vec3 friction_W = Vec3::Zero();
};
BoxContact BoxContacts(const Data& d, int box) {
  BoxContact out;
  for (int ci = 0; ci < d.ncontact; ++ci) {
    const Contact& c = d.contacts[ci];
    if (c.body_a != box && c.body_b != box) continue;
    ++out.n;
    out.normal_N += c.normal_force_N;
    out.friction_W += c.body_a == box ? c.friction_force_N_W : Vec3(-c.friction_force_N_W);
  }
  return out;
}

void SimulateSeconds(const Model& m, Data& d, double seconds) {
  const long steps = std::lround(seconds / m.timestep_s);
  for (long s = 0; s < steps; ++s) Tick(m, d, TickInput{});
}

// A box resting on the floor is given 0.8 m/s along x. Coulomb: it decelerates at mu g from the
// first step on, and stops after V^2 / (2 mu g) = 72.5 mm, without hopping or turning.
// Tolerances: first-step loss at most mu g h (1 + 1e-9) (rounding) and at least 0.98 of it;
// deceleration over 20..120 ms within 2% of mu g; stopping distance within 3%; |v_z| < 1e-4 m/s
// (a hop of the old law was +0.04 m/s); yaw rate < 1e-9 rad/s and yaw angle < 1e-9 rad (the
// scene is symmetric about the sliding line); every tick the friction on the box is at most mu
// times its normal force (relative 1e-9).
TEST(FrictionSlipTest, SlidingBoxDeceleratesAtMuGFromTheFirstStep) {
  const Model m = LoadBox("slide", 0.0, 0.0);
  Data d = MakeData(m);
  const int box = 0;
  const double h = m.timestep_s;
  SimulateSeconds(m, d, 0.5);  // settle at rest
  ASSERT_LT(d.bodies[box].v_W.norm(), 1e-9);
  constexpr double kV = 0.8;
  const Vec3 start = d.bodies[box].x_W;
  const Quat q0 = d.bodies[box].q_WB;
  d.bodies[box].v_W.x() = kV;
  Tick(m, d, TickInput{});
  const double loss = kV - d.bodies[box].v_W.x();
  const double coulomb = kMu * kG * h;
  std::printf("first-step loss %.9g m/s (mu g h %.9g)\n", loss, coulomb);
  EXPECT_LE(loss, coulomb * (1.0 + 1e-9));
  EXPECT_GE(loss, 0.98 * coulomb);
  double v_20ms = 0.0, v_120ms = 0.0, largest_vz = 0.0, largest_yaw_rate = 0.0, worst_ratio = 0.0;
  long step = 1;
  for (; step < 2000 && d.bodies[box].v_W.x() > 0.0; ++step) {
    Tick(m, d, TickInput{});
    if (step == 20) v_20ms = d.bodies[box].v_W.x();
    if (step == 120) v_120ms = d.bodies[box].v_W.x();
    largest_vz = std::max(largest_vz, std::abs(d.bodies[box].v_W.z()));
    largest_yaw_rate = std::max(largest_yaw_rate, std::abs(d.bodies[box].w_W.z()));
    const BoxContact bc = BoxContacts(d, box);
    if (bc.normal_N > 0.0) worst_ratio = std::max(worst_ratio, bc.friction_W.norm() / bc.normal_N);
  }
  SimulateSeconds(m, d, 0.2);  // at rest: the anchors hold it
  const double decel = (v_20ms - v_120ms) / (100 * h);
  const double distance = d.bodies[box].x_W.x() - start.x();
  const double expected = kV * kV / (2.0 * kMu * kG);
  const Quat turn = q0.conjugate() * d.bodies[box].q_WB;
  const double yaw = 2.0 * std::atan2(turn.z(), turn.w());
  std::printf(
      "deceleration %.6g (mu g %.6g), stopped after %ld steps at %.6g m (V^2/(2 mu g) %.6g)"
      ", |v_z| <= %.3g, |w_z| <= %.3g, yaw %.3g, friction/normal <= %.12g\n",
      decel, kMu * kG, step, distance, expected, largest_vz, largest_yaw_rate, yaw, worst_ratio);
  EXPECT_NEAR(decel, kMu * kG, 0.02 * kMu * kG);
  EXPECT_NEAR(distance, expected, 0.03 * expected);
  EXPECT_LT(largest_vz, 1e-4);
  EXPECT_LT(largest_yaw_rate, 1e-9);
  EXPECT_LT(std::abs(yaw), 1e-9);
  EXPECT_LT(std::abs(d.bodies[box].x_W.y() - start.y()), 1e-9);
  EXPECT_LE(worst_ratio, kMu * (1.0 + 1e-9));
}

// The box falls from 5 mm with 1.5 m/s along x and lands sliding. At the landing tick the
// friction impulse on it is at most mu times the normal impulse of its contacts (the penalty's,
// h sum N; the collision impulse is frictionless by design, so it is not counted: the bound is
// the stricter), and so is every tick's friction (relative 1e-9). From 50 ms after landing the
// horizontal deceleration is mu g within 2% (over 100 ms).
TEST(FrictionSlipTest, BoxLandingWhileSlidingIsCoulombBounded) {
  const Model m = LoadBox("landing", 0.0, 0.005);
  Data d = MakeData(m);
  const int box = 0;
  const double h = m.timestep_s;
  d.bodies[box].v_W.x() = 1.5;
  long landing = -1;
  double worst_ratio = 0.0;
  for (long step = 0; step < 200; ++step) {
    const double vx = d.bodies[box].v_W.x();
    Tick(m, d, TickInput{});
    const BoxContact bc = BoxContacts(d, box);
    if (bc.n == 0) continue;
    if (landing < 0) {
      landing = step;
      // only friction acts along x: m dv_x is the friction impulse
      const double friction_impulse = kMass * (vx - d.bodies[box].v_W.x());
      const double normal_impulse = h * bc.normal_N;
      std::printf("landing tick %ld: friction impulse %.6g N s, normal impulse %.6g N s\n", step,
                  friction_impulse, normal_impulse);
      EXPECT_NEAR(friction_impulse, h * std::abs(bc.friction_W.x()), 1e-12);
      EXPECT_LE(friction_impulse, kMu * normal_impulse * (1.0 + 1e-9));
    }
    if (bc.normal_N > 0.0) worst_ratio = std::max(worst_ratio, bc.friction_W.norm() / bc.normal_N);
  }
  ASSERT_GE(landing, 0) << "never landed";
  const double v1 = d.bodies[box].v_W.x();  // (200 - landing) ms after landing, > 50 ms
  ASSERT_GT(200 - landing, 50);
  SimulateSeconds(m, d, 0.1);
  const double v2 = d.bodies[box].v_W.x();
  ASSERT_GT(v2, 0.0);
  const double decel = (v1 - v2) / 0.1;
  std::printf("after landing: deceleration %.6g (mu g %.6g), friction/normal <= %.12g\n", decel,
              kMu * kG, worst_ratio);
  EXPECT_NEAR(decel, kMu * kG, 0.02 * kMu * kG);
  EXPECT_LE(worst_ratio, kMu * (1.0 + 1e-9));
}

// The same slide with the box as the tool, whose contacts are explicit (the haptic law, 2000 N/m):
// the explicit and the implicit law agree on the closed form. Both: first-step loss mu g h within
// 1e-6 (relative), stopping distance V^2 / (2 mu g) within 3%, and the two distances within 1% of
// each other.
double SlideDistance(bool explicit_law, double* first_loss) {
  LoadOptions o;
  o.contact.friction_static = o.contact.friction_kinetic = kMu;
  if (explicit_law) o.tool_name = "box";
  const Model m = LoadModel(test::WriteTempFile("law.xml", BoxXml(0.0, 0.0)), o);
  Data d = MakeData(m);
  const int box = 0;
  SimulateSeconds(m, d,
                  3.0);  // settle at rest (the explicit law is lightly damped: 0.05 of critical)
  constexpr double kV = 0.8;
  const double x0 = d.bodies[box].x_W.x();
  d.bodies[box].v_W.x() = kV;
  Tick(m, d, TickInput{});
  *first_loss = kV - d.bodies[box].v_W.x();
  for (int step = 0; step < 2000 && d.bodies[box].v_W.x() > 0.0; ++step) Tick(m, d, TickInput{});
  SimulateSeconds(m, d, 0.2);
  return d.bodies[box].x_W.x() - x0;
}

TEST(FrictionSlipTest, ExplicitAndImplicitLawsAgreeOnTheSlidingBox) {
  double loss_explicit = 0.0, loss_implicit = 0.0;
  const double explicit_m = SlideDistance(true, &loss_explicit);
  const double implicit_m = SlideDistance(false, &loss_implicit);
  const double expected = 0.8 * 0.8 / (2.0 * kMu * kG);
  const double coulomb = kMu * kG * 0.001;
  std::printf("explicit: loss %.9g, distance %.6g; implicit: loss %.9g, distance %.6g (%.6g)\n",
              loss_explicit, explicit_m, loss_implicit, implicit_m, expected);
  EXPECT_NEAR(loss_explicit, coulomb, 1e-6 * coulomb);
  EXPECT_NEAR(loss_implicit, coulomb, 1e-6 * coulomb);
  EXPECT_NEAR(explicit_m, expected, 0.03 * expected);
  EXPECT_NEAR(implicit_m, expected, 0.03 * expected);
  EXPECT_NEAR(explicit_m, implicit_m, 0.01 * expected);
}

// A box placed on a ramp at rest. With tan(theta) = 0.44 < mu = 0.45 it sticks: after settling
// for 0.2 s it moves less than 0.1 mm in 1 s (and launched, it stops where Coulomb says and sticks
// again). With tan(theta) = 0.46 > mu it slides, at
// g (sin - mu cos) = 0.0892 m/s^2 within 2% (measured over 0.2..1.2 s). With mu_s = 0.5 and
// mu_k = 0.45 the box rests there; launched down the ramp at 0.2 m/s it slides at
// g (sin - mu_k cos) from the first step on (within 2% over the first 0.5 s, the launch step
// included).
TEST(FrictionSlipTest, InclineJustBelowTheFrictionAngleSticks) {
  const double theta = std::atan(0.44);
  const Model m = LoadBox("incline_stick", theta, 0.0);
  Data d = MakeData(m);
  SimulateSeconds(m, d, 0.2);
  const Vec3 settled = d.bodies[0].x_W;
  SimulateSeconds(m, d, 1.0);
  const double drift = (d.bodies[0].x_W - settled).norm();
  std::printf("tan 0.44: drift over 1 s %.3g m\n", drift);
  EXPECT_LT(drift, 1e-4);
  // launched down the ramp at 0.05 m/s: it slows at g (mu cos - sin) = 0.0909 m/s^2, stops after
  // v^2 / (2 a) = 13.8 mm (within 3%), and then sticks (less than 0.1 mm in the next 1 s)
  const Vec3 downhill(std::cos(theta), 0.0, -std::sin(theta));
  const double decel = kG * (kMu * std::cos(theta) - std::sin(theta));
  constexpr double kV = 0.05;
  d.bodies[0].v_W += kV * downhill;
  const Vec3 launch = d.bodies[0].x_W;
  for (int step = 0; step < 2000 && d.bodies[0].v_W.dot(downhill) > 0.0; ++step) {
    Tick(m, d, TickInput{});
  }
  SimulateSeconds(m, d, 0.1);
  const Vec3 stopped = d.bodies[0].x_W;
  const double distance = (stopped - launch).dot(downhill);
  const double expected = kV * kV / (2.0 * decel);
  SimulateSeconds(m, d, 1.0);
  const double creep = (d.bodies[0].x_W - stopped).norm();
  std::printf(
      "tan 0.44, launched at 0.05 m/s: stopped after %.6g m (v^2 / (2 a) %.6g), then moved "
      "%.3g m in 1 s\n",
      distance, expected, creep);
  EXPECT_NEAR(distance, expected, 0.03 * expected);
  EXPECT_LT(creep, 1e-4);
}

TEST(FrictionSlipTest, InclineJustAboveTheFrictionAngleSlidesAtCoulombAcceleration) {
  const double theta = std::atan(0.46);
  const Vec3 downhill(std::cos(theta), 0.0, -std::sin(theta));
  const Model m = LoadBox("incline_slide", theta, 0.0);
  Data d = MakeData(m);
  SimulateSeconds(m, d, 0.2);
  const double v1 = d.bodies[0].v_W.dot(downhill);
  SimulateSeconds(m, d, 1.0);
  const double v2 = d.bodies[0].v_W.dot(downhill);
  const double a = v2 - v1;
  const double expected = kG * (std::sin(theta) - kMu * std::cos(theta));
  std::printf("tan 0.46: acceleration %.6g (g (sin - mu cos) %.6g)\n", a, expected);
  EXPECT_NEAR(a, expected, 0.02 * expected);
  // launched: the first steps of sliding are Coulomb's too. With mu_s = 0.5 the box rests on
  // this ramp (settled with mu_s = mu_k = 0.5, so that it does not slide while its normal force
  // builds up); launched, it slides with mu_k
  const Model m_rest = LoadBox("incline_rest", theta, 0.0, 0.5, 0.5);
  Data rest = MakeData(m_rest);
  SimulateSeconds(m_rest, rest, 0.2);
  ASSERT_LT(rest.bodies[0].v_W.norm(), 1e-9);
  const Model m_s = LoadBox("incline_launch", theta, 0.0, 0.5);
  Data launched = MakeData(m_s);
  launched.bodies = rest.bodies;
  launched.bodies[0].v_W += 0.2 * downhill;
  const double v0 = launched.bodies[0].v_W.dot(downhill);
  SimulateSeconds(m_s, launched, 0.5);
  const double a_launched = (launched.bodies[0].v_W.dot(downhill) - v0) / 0.5;
  std::printf("tan 0.46, launched at 0.2 m/s: acceleration %.6g\n", a_launched);
  EXPECT_NEAR(a_launched, expected, 0.02 * expected);
}

// A coefficient is >= 0, or exactly -1 for the MJCF geom friction (docs/config.md): any other
// negative value is refused naming the parameter and the range (it was read as -1); the model is
// not loaded.
TEST(FrictionSlipTest, NegativeCoefficientsOtherThanMinusOneAreRefused) {
  const std::string range = "is out of range: valid >= 0, or -1 for the MJCF geom friction";
  for (const auto& [mu_static, mu_kinetic, message] :
       {std::tuple{-0.5, -0.2, "parameter friction_static = -0.5 " + range},
        std::tuple{-1.0, -0.2, "parameter friction_kinetic = -0.2 " + range},
        std::tuple{-1e-9, 0.0, "parameter friction_static = -1e-09 " + range},
        std::tuple{0.3, -1.5, "parameter friction_kinetic = -1.5 " + range}}) {
    try {
      LoadBox("refused", 0.0, 0.0, mu_static, mu_kinetic);
      ADD_FAILURE() << mu_static << ", " << mu_kinetic << " was accepted";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
    }
  }
  // -1 (either or both) and 0 are accepted
  EXPECT_NO_THROW(LoadBox("mjcf", 0.0, 0.0, -1.0, -1.0));
  EXPECT_NO_THROW(LoadBox("mixed", 0.0, 0.0, -1.0, 0.0));
  EXPECT_NO_THROW(LoadBox("zero", 0.0, 0.0, 0.0, 0.0));
}

}  // namespace
}  // namespace rigidtouch
