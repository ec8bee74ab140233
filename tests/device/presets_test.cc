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

}  // namespace
}  // namespace rigidtouch::device
