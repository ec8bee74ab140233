// The mouse device's handle follows the target as a first-order lag (closed form), reports it as an
// encoder would (quantized, filtered velocity that converges to the true speed) and taps straight
// down at the set speed when asked.
#include "device/mouse_device.h"

#include <gtest/gtest.h>

#include <cmath>

namespace rigidtouch::device {
namespace {

constexpr double kH = 1e-3;

TEST(MouseDevice, HandleFollowsTheTargetWithTheTimeConstant) {
  MouseDeviceParams p;
  const double res = p.sensing.encoder_resolution_m;
  MouseDevice dev(DeviceLimits{}, p, Vec3::Zero());
  dev.SetTarget(Vec3(0.1, 0.0, 0.0));
  for (int k = 0; k < 20; ++k) dev.EndPeriod(kH);  // 20 ms = one time constant
  const double expected = 0.1 * (1.0 - std::exp(-0.02 / p.follow_time_constant_s));
  EXPECT_NEAR(dev.position_m().x(), expected, 1e-12);
  const DeviceState s = dev.Read();
  EXPECT_NEAR(s.position_m.x(), expected, 0.5 * res + 1e-12);  // quantized to the encoder
  EXPECT_EQ(std::fmod(std::abs(s.position_m.x() / res) + 1e-9, 1.0) < 2e-9, true);
  EXPECT_EQ(s.sequence, 20u);
  dev.SetTarget(Vec3(NAN, 0.0, 0.0));  // ignored
  dev.EndPeriod(kH);
  EXPECT_TRUE(dev.position_m().allFinite());
}

TEST(MouseDevice, TapMovesDownAtTheTapSpeedAndTheVelocityEstimateFollows) {
  MouseDeviceParams p;
  MouseDevice dev(DeviceLimits{}, p, Vec3(0.0, 0.0, 0.05));
  TraceSample t;
  dev.AnnotateTrace(t);
  EXPECT_EQ(t.tap, -1);
  dev.RequestTap();
  for (int k = 0; k < 100; ++k) dev.EndPeriod(kH);  // 0.1 s of the 0.15 s descent
  EXPECT_NEAR(dev.position_m().z(), 0.05 - p.tap_speed_mps * 0.1, 1e-9);
  // after 10 filter time constants (1.6 ms each at 100 Hz) the estimate is the true speed,
  // within what quantization of one period's travel (0.2 mm) leaves: one count per period
  EXPECT_NEAR(dev.Read().velocity_mps.z(), -p.tap_speed_mps, p.sensing.encoder_resolution_m / kH);
  dev.AnnotateTrace(t);
  EXPECT_EQ(t.tap, 0);
  dev.SetTarget(Vec3(1.0, 1.0, 1.0));  // ignored during the tap
  for (int k = 0; k < 1000; ++k) dev.EndPeriod(kH);
  EXPECT_NEAR(dev.position_m().z(), 0.05, 1e-9);  // back where the tap started
  dev.AnnotateTrace(t);
  EXPECT_EQ(t.tap, -1);
}

TEST(MouseDevice, BadParametersAreRefused) {
  MouseDeviceParams p;
  p.follow_time_constant_s = 0.0;
  EXPECT_THROW(MouseDevice(DeviceLimits{}, p, Vec3::Zero()), Error);
  EXPECT_THROW(MouseDevice(DeviceLimits{}, MouseDeviceParams{}, Vec3(NAN, 0, 0)), Error);
}

}  // namespace
}  // namespace rigidtouch::device
