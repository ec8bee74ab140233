// The passivity observer and controller (Hannaford and Ryu 2002) against closed forms: one tick
// at a time, with a hand-made model (tool mass 0.6 kg, h = 1 ms).
#include "render/passivity.h"

#include <gtest/gtest.h>

#include <cmath>

namespace rigidtouch::render {
namespace {

Model PortModel(double max_damping = 0.0, double max_force = 0.0) {
  Model m;
  m.timestep_s = 1e-3;
  m.bodies.resize(1);
  m.bodies[0].mass_kg = 0.6;
  m.tool = 0;
  m.render.passivity_control = true;
  m.device.coupling = Coupling::kDirect;
  m.device.limits.max_damping_Ns_per_m = max_damping;
  m.device.limits.max_force_N = max_force;
  return m;
}

DeviceState At(double z, double vz) {
  DeviceState s;
  s.position_m = Vec3(0, 0, z);
  s.velocity_mps = Vec3(0, 0, vz);
  return s;
}

DeviceCommand Force(double fz) {
  DeviceCommand c;
  c.force_N = Vec3(0, 0, fz);
  return c;
}

// a wall pushing out (+z) on a tool moving in (-z) absorbs energy: the controller stays idle, and
// the observer books exactly F dx = 2 N x 0.1 mm
TEST(PassivityTest, PassiveContactIsLeftAloneAndObserved) {
  const Model m = PortModel();
  Data d;
  DeviceCommand c = Force(2.0);
  PassivityControl(m, d, At(0.0, -0.1), true, c);
  EXPECT_EQ(c.force_N.z(), 2.0);
  EXPECT_EQ(d.passivity.damping_Ns_per_m, 0.0);
  DeviceCommand c2 = Force(2.0);
  PassivityControl(m, d, At(-1e-4, -0.1), true, c2);
  EXPECT_NEAR(d.passivity.observed_J, 2e-4, 1e-15);
  EXPECT_EQ(d.passivity.dissipated_J, 0.0);
}

// pushing the tool out (+z) as it moves out gives the user F v h: alpha = -E / (h |v|^2)
// = 2e-4 / (1e-3 x 0.01) = 20 N s/m cancels the force exactly; the next tick measures what that
// damping dissipated, alpha v . dx = 20 x 0.1 x 1e-4 = 2e-4 J
TEST(PassivityTest, ActiveContactGetsTheDampingThatRestoresTheEnergy) {
  const Model m = PortModel();
  Data d;
  DeviceCommand c = Force(2.0);
  PassivityControl(m, d, At(0.0, 0.1), true, c);
  EXPECT_NEAR(d.passivity.damping_Ns_per_m, 20.0, 1e-9);
  EXPECT_NEAR(c.force_N.z(), 0.0, 1e-12);
  DeviceCommand c2 = Force(2.0);
  PassivityControl(m, d, At(1e-4, 0.1), true, c2);
  EXPECT_NEAR(d.passivity.step_dissipated_J, 2e-4, 1e-15);
  EXPECT_NEAR(d.passivity.dissipated_J, 2e-4, 1e-15);
  // the held force was zero: a new contact, the observer restarts at 0 and acts again
  EXPECT_NEAR(d.passivity.observed_J, 0.0, 1e-15);
  EXPECT_NEAR(c2.force_N.z(), 0.0, 1e-12);
}

// an observed budget pays for activity: E = 2e-4 J absorbed, then a tick that would give
// 1e-4 J back is left alone, and one that would give 3e-4 J gets alpha for the 1e-4 J it lacks
TEST(PassivityTest, AbsorbedEnergyPaysForLaterActivity) {
  const Model m = PortModel();
  Data d;
  DeviceCommand c = Force(2.0);
  PassivityControl(m, d, At(0.0, -0.1), true, c);
  c = Force(2.0);
  PassivityControl(m, d, At(-1e-4, 0.1), true, c);  // observed 2e-4 J
  EXPECT_NEAR(d.passivity.observed_J, 2e-4, 1e-15);
  EXPECT_EQ(c.force_N.z(), 2.0);  // predicted 2e-4 - 2 x 0.1 x 1e-3 = 0: idle
  EXPECT_EQ(d.passivity.damping_Ns_per_m, 0.0);
  DeviceCommand c3 = Force(3.0);
  PassivityControl(m, d, At(0.0, 0.1), true, c3);
  // observed 2e-4 - 2 x 1e-4 = 0; predicted -3e-4: alpha = 3e-4 / (1e-3 x 0.01) = 30
  EXPECT_NEAR(d.passivity.damping_Ns_per_m, 30.0, 1e-9);
}

// bounded: by the device's damping, by m / h without one, idle near v = 0, and the force limit
TEST(PassivityTest, DampingIsBounded) {
  {
    const Model m = PortModel(/*max_damping=*/4.0);
    Data d;
    DeviceCommand c = Force(2.0);
    PassivityControl(m, d, At(0.0, 0.1), true, c);
    EXPECT_EQ(d.passivity.damping_Ns_per_m, 4.0);
    EXPECT_NEAR(c.force_N.z(), 2.0 - 0.4, 1e-12);
  }
  {
    const Model m = PortModel();
    EXPECT_NEAR(MaxControlDamping(m), 600.0, 1e-9);  // 0.6 kg / 1 ms
    Data d;
    DeviceCommand c = Force(100.0);
    PassivityControl(m, d, At(0.0, 0.1), true, c);  // asks alpha = 1000
    EXPECT_NEAR(d.passivity.damping_Ns_per_m, 600.0, 1e-9);
  }
  {
    const Model m = PortModel();
    Data d;
    DeviceCommand c = Force(2.0);
    PassivityControl(m, d, At(0.0, 0.5 * kPassivityMinSpeed_mps), true, c);
    EXPECT_EQ(d.passivity.damping_Ns_per_m, 0.0);
    EXPECT_EQ(c.force_N.z(), 2.0);
  }
  {
    // a deficit of 2e-3 J observed (the handle moved 1 mm out under 2 N), then the tool moves
    // in at 0.5 m/s: alpha = (2e-3 + 0.1 x 0.5 x 1e-3) / (1e-3 x 0.25) = 8.2 N s/m asks
    // -0.1 + 8.2 x 0.5 = 4 N, beyond the 3 N limit
    const Model m = PortModel(0.0, /*max_force=*/3.0);
    Data d;
    DeviceCommand c = Force(2.0);
    PassivityControl(m, d, At(0.0, -0.1), true, c);
    DeviceCommand c2 = Force(-0.1);
    PassivityControl(m, d, At(1e-3, -0.5), true, c2);
    EXPECT_NEAR(d.passivity.observed_J, -2e-3, 1e-15);
    EXPECT_NEAR(d.passivity.damping_Ns_per_m, 8.2, 1e-9);
    EXPECT_LE(c2.force_N.norm(), 3.0);
    EXPECT_NEAR(c2.force_N.z(), 3.0, 1e-12);
    EXPECT_TRUE(c2.clipped);
  }
}

// with a position quantum q the controller keeps the observer's worst error in reserve:
// |e| (sum |dF| + |F|), |e| = sqrt(3) q / 2. A first tick of 2 N with q = 1 mm reserves
// 0.866e-3 x (2 + 2) = 3.46e-3 J: a passive-looking tick (F . v h = -2e-4 J absorbed) still gets
// alpha = (3.46e-3 - 2e-4) / (1e-3 x 0.01)
TEST(PassivityTest, QuantizedPositionsKeepAReserve) {
  Model m = PortModel();
  m.device.position_resolution_m = 1e-3;
  Data d;
  DeviceCommand c = Force(2.0);
  PassivityControl(m, d, At(0.0, -0.1), true, c);
  const double reserve = 0.5 * std::sqrt(3.0) * 1e-3 * 4.0;
  EXPECT_NEAR(d.passivity.damping_Ns_per_m, (reserve - 2e-4) / 1e-5, 1e-6);
  // exact positions: no reserve, idle
  m.device.position_resolution_m = 0.0;
  Data exact;
  DeviceCommand c2 = Force(2.0);
  PassivityControl(m, exact, At(0.0, -0.1), true, c2);
  EXPECT_EQ(exact.passivity.damping_Ns_per_m, 0.0);
}

TEST(PassivityTest, OffOrWithoutADeviceNothingChanges) {
  Model m = PortModel();
  m.render.passivity_control = false;
  Data d;
  DeviceCommand c = Force(2.0);
  PassivityControl(m, d, At(0.0, 0.1), true, c);
  EXPECT_EQ(c.force_N.z(), 2.0);
  m.render.passivity_control = true;
  m.device.coupling = Coupling::kNone;
  PassivityControl(m, d, At(0.0, 0.1), true, c);
  EXPECT_EQ(c.force_N.z(), 2.0);
  // an invalid device state restarts the observer and applies nothing
  m.device.coupling = Coupling::kDirect;
  PassivityControl(m, d, At(0.0, 0.1), false, c);
  EXPECT_EQ(c.force_N.z(), 2.0);
  EXPECT_FALSE(d.passivity.has_last);
}

}  // namespace
}  // namespace rigidtouch::render
