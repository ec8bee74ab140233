// What the device can display, checked by the tick: the force limit (closed form k d on a sphere
// resting in a plane), overflow-safe clipping, stiffness and damping refused above the device's
// limits, implausible device states, and stale readings (DeviceState::fresh) that start no
// window and apply no impulse.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <string>

#include "draw.h"
#include "engine/workspace.h"
#include "render/output.h"
#include "rigidtouch/rigidtouch.h"
#include "test_util.h"

namespace rigidtouch {
namespace {

using test::TestScene;

constexpr double kRadius_m = 0.005;  // the tool sphere of sphere_plane.xml, on the plane z = 0

// the sphere scene with the tool coupled directly to the device; no gravity, no friction
Model DirectModel(RendererKind kind, double k_N_per_m, double max_force_N = 0.0) {
  LoadOptions o;
  o.contact.stiffness_N_per_m = k_N_per_m;
  o.contact.damping_Ns_per_m = 0.0;
  o.contact.friction_static = 0.0;
  o.contact.friction_kinetic = 0.0;
  o.render.renderer = kind;
  o.device.coupling = Coupling::kDirect;
  o.device.limits.max_force_N = max_force_N;
  Model m = LoadModel(TestScene("sphere_plane.xml"), o);
  m.gravity_W.setZero();
  return m;
}

TickInput DeviceAt(double z_m, double vz_mps = 0.0, std::uint64_t sequence = 1) {
  TickInput in;
  in.device.sequence = sequence;
  in.device.position_m = Vec3(0.0, 0.0, z_m);
  in.device.velocity_mps = Vec3(0.0, 0.0, vz_mps);
  return in;
}

int Count(const Data& d, Warning w) {
  return d.warnings[static_cast<int>(w)].count;
}

// a sphere held 1 mm deep in the plane feels k d = 2 N; a 1.5 N limit clips it to exactly
// 1.5 N along the normal, flagged and counted
TEST(DeviceLimitsTest, RenderStageClipsThePenaltyForceToTheModelsLimit) {
  const double k = 2000.0, depth = 1e-3;
  {
    const Model m = DirectModel(RendererKind::kPenalty, k);
    Data d = MakeData(m);
    const DeviceCommand out = Tick(m, d, DeviceAt(kRadius_m - depth));
    EXPECT_NEAR(out.force_N.z(), k * depth, 1e-9);
    EXPECT_FALSE(out.clipped);
  }
  const Model m = DirectModel(RendererKind::kPenalty, k, 1.5);
  Data d = MakeData(m);
  const DeviceCommand out = Tick(m, d, DeviceAt(kRadius_m - depth));
  EXPECT_NEAR(out.penalty_force_N.z(), k * depth, 1e-9);  // before the limit
  EXPECT_LE(out.force_N.norm(), 1.5);
  EXPECT_NEAR(out.force_N.z(), 1.5, 1e-12);
  EXPECT_TRUE(out.clipped);
  EXPECT_FALSE(out.safe_fallback);
  EXPECT_EQ(Count(d, Warning::kForceClipped), 1);
}

// the limit is a hard bound, whatever the rounding; direction and torque scale with the force
TEST(DeviceLimitsTest, LimitForceIsAHardBoundAndKeepsTheDirection) {
  Vec3 f(3.0, 4.0, 0.0), t(1.0, 2.0, 3.0);
  EXPECT_TRUE(render::LimitForce(2.5, f, t));
  EXPECT_NEAR((f - Vec3(1.5, 2.0, 0.0)).norm(), 0.0, 1e-15);
  EXPECT_NEAR((t - Vec3(0.5, 1.0, 1.5)).norm(), 0.0, 1e-15);
  Vec3 small(0.1, 0.0, 0.0), t0 = Vec3::Zero();
  EXPECT_FALSE(render::LimitForce(2.5, small, t0));
  EXPECT_FALSE(render::LimitForce(0.0, f, t0));  // 0: no limit

  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> unit(-1.0, 1.0), exponent(-3.0, 300.0);
  int scaled = 0;
  for (int i = 0; i < 100000; ++i) {
    const double scale = std::pow(10.0, exponent(rng));
    Vec3 v = scale * test::Draw3(unit, rng);
    const Vec3 direction = v.stableNormalized();
    const double limit = std::pow(10.0, exponent(rng) / 100.0);  // 0.9 N .. 1000 N
    Vec3 torque = Vec3::Zero();
    if (!render::LimitForce(limit, v, torque)) continue;
    ++scaled;
    ASSERT_TRUE(v.allFinite()) << i;
    ASSERT_LE(v.norm(), limit) << i;
    ASSERT_NEAR(v.norm(), limit, 1e-12 * limit) << i;
    ASSERT_NEAR(v.stableNormalized().dot(direction), 1.0, 1e-12) << i;
  }
  EXPECT_GT(scaled, 90000);
}

// components whose squared norm overflows (and an impulse over h that overflows) still give
// the finite clipped answer along the true direction
TEST(DeviceLimitsTest, OverflowingForceIsClippedNotLost) {
  Vec3 f(1e300, -1e300, 0.0), t = Vec3::Zero();
  ASSERT_FALSE(std::isfinite(f.squaredNorm()));
  EXPECT_TRUE(render::LimitForce(3.3, f, t));
  EXPECT_LE(f.norm(), 3.3);
  EXPECT_NEAR(f.x(), 3.3 / std::sqrt(2.0), 1e-12);
  EXPECT_NEAR(f.y(), -3.3 / std::sqrt(2.0), 1e-12);
  Vec3 huge = Vec3::Constant(std::numeric_limits<double>::max());
  EXPECT_TRUE(render::LimitForce(1.0, huge, t));
  EXPECT_NEAR(huge.x(), 1.0 / std::sqrt(3.0), 1e-12);

  // Eq. 9 with an impulse of 1e306 N s over h = 1 ms is beyond the double range
  for (const double limit : {3.3, 0.0}) {
    const Model m = DirectModel(RendererKind::kTrain, 0.0, limit);
    Data d = MakeData(m);
    d.ncontact = 0;
    d.tool_impulse_Ns_W = Vec3(0.0, 1e306, 1e306);
    DeviceCommand out = render::DeviceWrench(m, d, d.workspace->contact, 0);
    render::Safeguard(d, true, out);
    EXPECT_TRUE(out.force_N.allFinite());
    if (limit > 0.0) {
      EXPECT_TRUE(out.clipped);
      EXPECT_FALSE(out.safe_fallback);
      EXPECT_LE(out.force_N.norm(), limit);
      EXPECT_NEAR(out.force_N.y(), limit / std::sqrt(2.0), 1e-12);
      EXPECT_NEAR(out.force_N.z(), limit / std::sqrt(2.0), 1e-12);
      EXPECT_EQ(Count(d, Warning::kImpulseClipped), 1);
    } else {
      // no limit to clip to: the true answer is not a double, so the safe zero wrench
      EXPECT_TRUE(out.safe_fallback);
      EXPECT_EQ(out.force_N, Vec3::Zero());
    }
  }
}

// a rendered stiffness or damping above the device's is refused, naming the parameter and the
// limit; under virtual coupling the device renders the coupling, so that is what is checked
TEST(DeviceLimitsTest, ConfigureRefusesWhatTheDeviceCannotDisplay) {
  Model m = DirectModel(RendererKind::kTrain, 400.0);
  m.device.limits.max_stiffness_N_per_m = 400.0;
  m.device.limits.max_damping_Ns_per_m = 4.0;
  m.contact.damping_Ns_per_m = 4.0;
  EXPECT_NO_THROW(Configure(m));  // at the limits
  const auto message = [](Model model) -> std::string {
    try {
      Configure(model);
    } catch (const Error& e) {
      return e.what();
    }
    return "";
  };
  for (const double k : {401.0, 1e300, std::numeric_limits<double>::max()}) {
    Model bad = m;
    bad.contact.stiffness_N_per_m = k;
    const std::string what = message(bad);
    EXPECT_NE(what.find("stiffness_N_per_m"), std::string::npos) << what;
    EXPECT_NE(what.find("max_stiffness_N_per_m = 400 N/m"), std::string::npos) << what;
  }
  Model bad = m;
  bad.contact.damping_Ns_per_m = 4.5;
  const std::string what = message(bad);
  EXPECT_NE(what.find("damping_Ns_per_m = 4.5"), std::string::npos) << what;
  EXPECT_NE(what.find("max_damping_Ns_per_m = 4"), std::string::npos) << what;

  Model coupled = m;
  coupled.device.coupling = Coupling::kVirtual;
  coupled.contact.stiffness_N_per_m = 5000.0;  // the wall may be stiffer than the device
  coupled.device.coupling_stiffness_N_per_m = 400.0;
  coupled.device.coupling_damping_Ns_per_m = 2.0;
  EXPECT_NO_THROW(Configure(coupled));
  coupled.device.coupling_stiffness_N_per_m = 500.0;
  EXPECT_NE(message(coupled).find("coupling_stiffness_N_per_m = 500"), std::string::npos);

  Model unknown = m;  // 0: the device's limits are unknown, nothing to check against
  unknown.device.limits.max_stiffness_N_per_m = 0.0;
  unknown.contact.stiffness_N_per_m = 1e6;
  EXPECT_NO_THROW(Configure(unknown));
}

// a finite state beyond the plausible reach or speeds gives zero force and its own warning;
// one within them is rendered; the bounds are the model's
TEST(DeviceLimitsTest, ImplausibleDeviceStatesGiveZeroForce) {
  const Model m = DirectModel(RendererKind::kPenalty, 2000.0);
  EXPECT_EQ(m.device.plausible_radius_m, 1.0);
  EXPECT_EQ(m.device.plausible_speed_mps, 10.0);
  struct Case {
    Vec3 x_m, v_mps, w_radps;
  };
  const Case bad[] = {
      {Vec3(1.5, 0.0, 0.0), Vec3::Zero(), Vec3::Zero()},
      {Vec3(0.0, 0.0, 1e300), Vec3::Zero(), Vec3::Zero()},
      {Vec3(0.0, 0.0, 0.004), Vec3(0.0, 0.0, -10.5), Vec3::Zero()},
      {Vec3(0.0, 0.0, 0.004), Vec3(1e300, 1e300, 1e300), Vec3::Zero()},
      {Vec3(0.0, 0.0, 0.004), Vec3::Zero(), Vec3(0.0, 0.0, 150.0)},
  };
  for (const Case& c : bad) {
    Data d = MakeData(m);
    TickInput in;
    in.device.position_m = c.x_m;
    in.device.velocity_mps = c.v_mps;
    in.device.angular_velocity_radps = c.w_radps;
    const DeviceCommand out = Tick(m, d, in);
    EXPECT_TRUE(out.safe_fallback) << c.x_m.transpose() << " " << c.v_mps.transpose();
    EXPECT_EQ(out.force_N, Vec3::Zero());
    EXPECT_EQ(Count(d, Warning::kImplausibleDeviceState), 1);
    EXPECT_TRUE(d.bodies[m.tool].x_W.allFinite());
  }
  // 1 mm deep, pulling out at 9 m/s: rendered, k d
  Data d = MakeData(m);
  TickInput in = DeviceAt(kRadius_m - 1e-3, 9.0);
  const DeviceCommand out = Tick(m, d, in);
  EXPECT_FALSE(out.safe_fallback);
  EXPECT_NEAR(out.force_N.z(), 2.0, 1e-9);
  EXPECT_EQ(Count(d, Warning::kImplausibleDeviceState), 0);

  Model wide = m;
  wide.device.plausible_radius_m = 2.0;
  Configure(wide);
  Data dw = MakeData(wide);
  TickInput far;
  far.device.position_m = Vec3(1.5, 0.0, 0.1);
  EXPECT_FALSE(Tick(wide, dw, far).safe_fallback);
  wide.device.plausible_speed_mps = 0.0;
  EXPECT_THROW(Configure(wide), Error);
}

// Eq. 5 at onset, p = m v: a fresh reading gets the impulse, a repeated one neither the impulse
// nor a window
TEST(DeviceLimitsTest, StaleReadingStartsNoWindow) {
  const Model m = DirectModel(RendererKind::kImpulse, 0.0);
  const double v = -0.2, mass = m.bodies[m.tool].mass_kg;
  for (const bool fresh : {true, false}) {
    Data d = MakeData(m);
    Tick(m, d, DeviceAt(kRadius_m + 5e-4, v, 1));  // above the plane
    TickInput in = DeviceAt(kRadius_m - 1e-4, v, 2);
    in.device.fresh = fresh;
    const DeviceCommand out = Tick(m, d, in);
    ASSERT_GT(d.ncontact, 0);
    if (fresh) {
      ASSERT_EQ(d.nimpulse, 1);
      EXPECT_NEAR(out.impulsive_force_N.z(), -mass * v / m.timestep_s, 1e-6);
    } else {
      EXPECT_EQ(d.nimpulse, 0);
      EXPECT_EQ(d.window[m.tool].onset_step, -1);
      EXPECT_EQ(out.impulsive_force_N, Vec3::Zero());
    }
  }
}

// a train (250 Hz at h = 1 ms: every 4 steps) whose reading goes stale skips the impulses due
// while it is, instead of pushing against a hand that may have gone
TEST(DeviceLimitsTest, StaleReadingAppliesNoImpulseOfARunningTrain) {
  const Model m = DirectModel(RendererKind::kTrain, 0.0);
  ASSERT_EQ(m.schedule.interval_steps, 4);
  for (const bool fresh : {true, false}) {
    Data d = MakeData(m);
    std::uint64_t seq = 1;
    Tick(m, d, DeviceAt(kRadius_m + 5e-4, -0.1, seq++));
    Tick(m, d, DeviceAt(kRadius_m - 1e-4, -0.1, seq++));
    ASSERT_EQ(d.nimpulse, 1);  // onset
    for (int k = 1; k < 4; ++k) Tick(m, d, DeviceAt(kRadius_m - 1e-4, -0.1, seq++));
    TickInput due = DeviceAt(kRadius_m - 1e-4, -0.1, fresh ? seq : seq - 1);
    due.device.fresh = fresh;
    const DeviceCommand out = Tick(m, d, due);
    EXPECT_EQ(d.nimpulse, fresh ? 1 : 0);
    EXPECT_EQ(out.impulsive_force_N.squaredNorm() > 0.0, fresh);
  }
}

// the device goes invalid (the watchdog) or implausible while the tool is in a train's window:
// the directly coupled tool stays where the last good state put it, at rest, with no impulse; a
// good state moves it again
TEST(DeviceLimitsTest, WithoutAUsableStateTheToolIsHeldAtRest) {
  const Model m = DirectModel(RendererKind::kTrain, 2000.0);
  for (const bool implausible : {false, true}) {
    Data d = MakeData(m);
    std::uint64_t seq = 1;
    Tick(m, d, DeviceAt(kRadius_m + 5e-4, -0.2, seq++));
    Tick(m, d, DeviceAt(kRadius_m - 2e-4, -0.2, seq++));
    ASSERT_EQ(d.nimpulse, 1);  // onset: the train's window is open
    const Vec3 held = d.bodies[m.tool].x_W;
    for (int k = 0; k < 40; ++k) {  // ten of the train's impulses would fall in here
      TickInput in = DeviceAt(kRadius_m - 2e-4, -0.2, seq++);
      if (implausible) {
        in.device.velocity_mps.z() = -50.0;
      } else {
        in.device.valid = false;
      }
      const DeviceCommand out = Tick(m, d, in);
      EXPECT_EQ(out.force_N, Vec3::Zero()) << k;
      EXPECT_EQ(d.nimpulse, 0) << k;
      EXPECT_EQ(d.bodies[m.tool].x_W, held) << k;  // exactly: the penalty does not move it
      EXPECT_EQ(d.bodies[m.tool].v_W, Vec3::Zero()) << k;
    }
    const DeviceCommand back = Tick(m, d, DeviceAt(kRadius_m - 1e-4, 0.0, seq++));
    EXPECT_FALSE(back.safe_fallback);
    // at the handle, then one step of the tick's own dynamics (k d h^2 / m = 2 um)
    EXPECT_NEAR(d.bodies[m.tool].x_W.z(), kRadius_m - 1e-4, 5e-6);
    EXPECT_NEAR(back.force_N.z(), 2000.0 * 1e-4, 1e-9);
  }
}

}  // namespace
}  // namespace rigidtouch
