#include "device/presets.h"

#include <gtest/gtest.h>

#include <string>

#include "rigidtouch/types.h"

namespace rigidtouch::device {
namespace {

TEST(PresetsTest, TableHoldsChai3dValues) {
  // exact values from CHAI3D 3.x device classes (see presets.cc)
  const auto presets = Presets();
  ASSERT_EQ(presets.size(), 6u);
  EXPECT_EQ(presets[0].name, "touch");
  EXPECT_EQ(presets[1].name, "omni");
  EXPECT_EQ(presets[2].name, "falcon");
  EXPECT_EQ(presets[3].name, "omega3");
  EXPECT_EQ(presets[4].name, "generic");
  EXPECT_EQ(presets[5].name, "ideal");

  const DeviceLimits& touch = FindPreset("touch");
  EXPECT_DOUBLE_EQ(touch.max_force_N, 3.3);
  EXPECT_DOUBLE_EQ(touch.max_stiffness_N_per_m, 400.0);
  EXPECT_DOUBLE_EQ(touch.max_damping_Ns_per_m, 4.0);
  const DeviceLimits& omni = FindPreset("omni");
  EXPECT_DOUBLE_EQ(omni.max_force_N, 3.3);
  EXPECT_DOUBLE_EQ(omni.max_stiffness_N_per_m, 700.0);
  EXPECT_DOUBLE_EQ(omni.max_damping_Ns_per_m, 5.0);
  const DeviceLimits& falcon = FindPreset("falcon");
  EXPECT_DOUBLE_EQ(falcon.max_force_N, 8.0);
  EXPECT_DOUBLE_EQ(falcon.max_stiffness_N_per_m, 3000.0);
  EXPECT_DOUBLE_EQ(falcon.max_damping_Ns_per_m, 20.0);
  const DeviceLimits& omega = FindPreset("omega3");
  EXPECT_DOUBLE_EQ(omega.max_force_N, 12.0);
  EXPECT_DOUBLE_EQ(omega.max_stiffness_N_per_m, 5000.0);
  EXPECT_DOUBLE_EQ(omega.max_damping_Ns_per_m, 30.0);
  const DeviceLimits& generic = FindPreset("generic");
  EXPECT_GT(generic.max_force_N, 0.0);
  EXPECT_GT(generic.max_stiffness_N_per_m, 0.0);
  EXPECT_GT(generic.max_damping_Ns_per_m, 0.0);
}

TEST(PresetsTest, FindReturnsTheTableEntry) {
  for (const DeviceLimits& preset : Presets()) {
    EXPECT_EQ(&FindPreset(preset.name), &preset) << preset.name;
  }
}

TEST(PresetsTest, UnknownPresetListsValidNames) {
  try {
    FindPreset("phantom");
    FAIL() << "expected rigidtouch::Error";
  } catch (const Error& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("'phantom'"), std::string::npos) << message;
    EXPECT_NE(message.find("touch, omni, falcon, omega3, generic, ideal"), std::string::npos)
        << message;
  }
  // lookup is exact: no case folding
  EXPECT_THROW(FindPreset("Touch"), Error);
  EXPECT_THROW(FindPreset(""), Error);
}

// the default wall: a device's own stiffness and k h capped at its damping; the ideal device
// (no limits) the contact law's stiffness and k times 20 ms
TEST(PresetsTest, DefaultWallFollowsTheDevicesLimits) {
  const double h = 0.001;
  const Wall touch = DefaultWall(FindPreset("touch"), h, 2000.0);
  EXPECT_EQ(touch.stiffness_N_per_m, 400.0);
  EXPECT_DOUBLE_EQ(touch.damping_Ns_per_m, 0.4);  // k h = 0.4 under the Touch's 4 N s/m
  const Wall omega = DefaultWall(FindPreset("omega3"), 0.01, 2000.0);
  EXPECT_EQ(omega.stiffness_N_per_m, 5000.0);
  EXPECT_EQ(omega.damping_Ns_per_m, 30.0);  // k h = 50 capped at the omega.3's 30 N s/m
  const Wall ideal = DefaultWall(FindPreset("ideal"), h, 2000.0);
  EXPECT_EQ(ideal.stiffness_N_per_m, 2000.0);
  EXPECT_DOUBLE_EQ(ideal.damping_Ns_per_m, 40.0);
  // a stiffness limit without a damping limit keeps the sampled bound k h
  DeviceLimits stiff_only{"lab", 5.0, 1500.0, 0.0};
  EXPECT_DOUBLE_EQ(DefaultDamping(stiff_only, h, 1500.0), 1.5);
}

}  // namespace
}  // namespace rigidtouch::device
