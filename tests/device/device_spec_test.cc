// Device specs: the presets (with `ideal`) and JSON files, whose every mistake names the field.
#include "device/device_spec.h"

#include <gtest/gtest.h>

#include <unistd.h>
#include <filesystem>
#include <fstream>
#include <string>

#include "rigidtouch/types.h"

namespace rigidtouch::device {
namespace {

const char kFull[] =
    R"({"name": "lab", "max_force_N": 1.5, "max_stiffness_N_per_m": 800,
        "max_damping_Ns_per_m": 6, "apparent_mass_kg": 0.1, "encoder_resolution_m": 1e-5,
        "velocity_filter_hz": 200, "delay_ticks": 1})";

std::string Write(const std::string& name, const std::string& text) {
  const auto path = std::filesystem::temp_directory_path() /
                    ("rigidtouch_spec_" + std::to_string(::getpid()) + "_" + name);
  std::ofstream(path) << text;
  return path.string();
}

std::string SpecErrorOf(const std::string& text) {
  try {
    ParseDeviceSpec(text);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(DeviceSpecTest, IdealHasNoLimitAFineEncoderAndNoDelay) {
  const DeviceSpec ideal = ParseDeviceSpec("ideal");
  EXPECT_EQ(ideal.limits.name, "ideal");
  EXPECT_EQ(ideal.limits.max_force_N, 0.0);
  EXPECT_EQ(ideal.limits.max_stiffness_N_per_m, 0.0);
  EXPECT_EQ(ideal.limits.max_damping_Ns_per_m, 0.0);
  EXPECT_EQ(ideal.model.encoder_resolution_m, 1e-6);
  EXPECT_EQ(ideal.model.delay_ticks, 0);
  EXPECT_TRUE(ideal.file.empty());
  // a real preset keeps its limits and the default sensing (the Omni's 55 um encoder)
  const DeviceSpec touch = ParseDeviceSpec("touch");
  EXPECT_EQ(touch.limits.max_force_N, 3.3);
  EXPECT_EQ(touch.limits.max_torque_Nm, 0.0);  // force only (3-DoF)
  EXPECT_EQ(ideal.limits.max_torque_Nm, 0.0);
  EXPECT_EQ(touch.model.encoder_resolution_m, DeviceModelParams{}.encoder_resolution_m);
}

TEST(DeviceSpecTest, AFileGivesEveryField) {
  const std::string path = Write("full.json", kFull);
  const DeviceSpec s = ParseDeviceSpec(path);
  EXPECT_EQ(s.file, path);
  EXPECT_EQ(s.limits.name, "lab");
  EXPECT_EQ(s.limits.max_force_N, 1.5);
  EXPECT_EQ(s.limits.max_stiffness_N_per_m, 800.0);
  EXPECT_EQ(s.limits.max_damping_Ns_per_m, 6.0);
  EXPECT_EQ(s.model.apparent_mass_kg, 0.1);
  EXPECT_EQ(s.model.encoder_resolution_m, 1e-5);
  EXPECT_EQ(s.model.velocity_cutoff_hz, 200.0);
  EXPECT_EQ(s.model.delay_ticks, 1);
  EXPECT_EQ(s.limits.max_torque_Nm, 0.0);  // not given: a 3-DoF force device, no torque
  std::string with_torque = kFull;
  with_torque.replace(with_torque.find(R"("delay_ticks": 1)"), 16,
                      R"("delay_ticks": 1, "max_torque_Nm": 0.4)");
  const std::string torque_path = Write("torque.json", with_torque);
  EXPECT_EQ(ParseDeviceSpec(torque_path).limits.max_torque_Nm, 0.4);
  std::filesystem::remove(torque_path);
  // without a name, the file's stem
  std::string unnamed = kFull;
  unnamed.replace(unnamed.find(R"("name": "lab", )"), 15, "");
  const std::string unnamed_path = Write("mydev.json", unnamed);
  EXPECT_EQ(ParseDeviceSpec(unnamed_path).limits.name,
            "rigidtouch_spec_" + std::to_string(::getpid()) + "_mydev");
  std::filesystem::remove(path);
  std::filesystem::remove(unnamed_path);
}

TEST(DeviceSpecTest, BadSpecsNameTheField) {
  struct Case {
    std::string from, to, field, says;
  };
  const Case cases[] = {
      {R"("max_force_N": 1.5)", R"("max_force_N": -1)", "max_force_N", "out of range"},
      {R"("max_force_N": 1.5, )", "", "max_force_N", "missing"},
      {R"("apparent_mass_kg": 0.1)", R"("apparent_mass_kg": "heavy")", "apparent_mass_kg",
       "number"},
      {R"("apparent_mass_kg": 0.1)", R"("apparent_mass_kg": -0.1)", "apparent_mass_kg",
       "out of range"},
      {R"("encoder_resolution_m": 1e-5)", R"("encoder_resolution_m": 1)", "encoder_resolution_m",
       "out of range"},
      {R"("velocity_filter_hz": 200)", R"("velocity_filter_hz": 0)", "velocity_filter_hz",
       "out of range"},
      {R"("delay_ticks": 1)", R"("delay_ticks": 3)", "delay_ticks", ""},
      {R"(, "delay_ticks": 1)", "", "delay_ticks", "missing"},
      {R"("delay_ticks": 1)", R"("delay_ticks": 1, "max_torque_N": 1)", "max_torque_N", ""},
      {R"("delay_ticks": 1)", R"("delay_ticks": 1, "max_torque_Nm": -1)", "max_torque_Nm",
       "out of range"},
      {R"("max_stiffness_N_per_m": 800)", R"("max_stiffness_N_per_m": 1e9)",
       "max_stiffness_N_per_m", "out of range"},
  };
  for (const Case& c : cases) {
    std::string text = kFull;
    const std::size_t at = text.find(c.from);
    ASSERT_NE(at, std::string::npos) << c.from;
    text.replace(at, c.from.size(), c.to);
    const std::string path = Write("bad.json", text);
    const std::string e = SpecErrorOf(path);
    EXPECT_NE(e.find(path), std::string::npos) << e;
    EXPECT_NE(e.find(c.field), std::string::npos) << c.to << ": " << e;
    EXPECT_NE(e.find(c.says), std::string::npos) << c.to << ": " << e;
    std::filesystem::remove(path);
  }
  // neither a preset nor a .json file: the valid forms are listed
  const std::string e = SpecErrorOf("phantom");
  EXPECT_NE(e.find("'phantom'"), std::string::npos) << e;
  EXPECT_NE(e.find("ideal"), std::string::npos) << e;
  EXPECT_NE(e.find("FILE.json"), std::string::npos) << e;
  EXPECT_NE(SpecErrorOf("/no/such/spec.json").find("/no/such/spec.json"), std::string::npos);
}

}  // namespace
}  // namespace rigidtouch::device
