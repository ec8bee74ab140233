// Contact defaults from the scene (docs/method.md): the scene-contact stiffness and damping left at
// their defaults are derived from the bodies' masses and h, so a heavy body rests and a light one
// stays stable; a law the user set that cannot hold a body or is unstable for it is reported in
// Model::load_warnings, naming the body; the shipped scenes keep today's values.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "rigidtouch/rigidtouch.h"
#include "test_util.h"

namespace rigidtouch {
namespace {

// A 20 kg box (half-size 50 mm) on the floor, the tool (a 0.1 kg sphere) resting far from it.
std::string HeavyBox() {
  return test::WriteTempFile("heavy.xml",
                             "<mujoco><option timestep=\"0.001\"/><worldbody>"
                             "<geom name=\"floor\" type=\"plane\" size=\"1 1 0.1\"/>"
                             "<body name=\"heavy\" pos=\"0 0 0.05\"><freejoint/>"
                             "<geom type=\"box\" size=\"0.05 0.05 0.05\" mass=\"20\"/></body>"
                             "<body name=\"tool\" pos=\"0.5 0 0.005\"><freejoint/>"
                             "<geom type=\"sphere\" size=\"0.005\" mass=\"0.1\"/></body>"
                             "</worldbody></mujoco>");
}

// A 0.2 g plate (20 x 20 x 1 mm) dropped tilted from 20 mm onto the floor at h = 2 ms.
std::string LightPlate() {
  return test::WriteTempFile(
      "plate.xml",
      "<mujoco><option timestep=\"0.002\"/><worldbody>"
      "<geom name=\"floor\" type=\"plane\" size=\"1 1 0.1\"/>"
      "<body name=\"plate\" pos=\"0.2 0 0.02\" euler=\"20 10 0\"><freejoint/>"
      "<geom type=\"box\" size=\"0.01 0.01 0.0005\" mass=\"0.0002\"/></body>"
      "<body name=\"tool\" pos=\"0.5 0 0.005\"><freejoint/>"
      "<geom type=\"sphere\" size=\"0.005\" mass=\"0.1\"/></body>"
      "</worldbody></mujoco>");
}

bool Mentions(const Model& model, const std::string& a, const std::string& b) {
  for (const std::string& w : model.load_warnings) {
    if (w.find(a) != std::string::npos && w.find(b) != std::string::npos) return true;
  }
  return false;
}

TEST(DefaultsTest, HeavyBoxRestsWithinOnePercentOfItsSize) {
  const Model model = LoadModel(HeavyBox(), LoadOptions{});
  EXPECT_TRUE(model.load_warnings.empty());
  Data data = MakeData(model);
  for (int k = 0; k < 2000; ++k) Tick(model, data, TickInput{});
  const double sink = 0.05 - data.bodies[0].x_W.z();
  std::printf("20 kg box: k = %g N/m, b = %g N s/m, sink %.4f mm\n",
              model.contact.scene_stiffness_N_per_m, model.contact.scene_damping_Ns_per_m,
              sink * 1e3);
  // m g / k <= 1 % of the smallest half-size (0.5 mm); the default 2e5 N/m sinks 0.98 mm
  EXPECT_LT(sink, 0.01 * 0.05 * 1.001);
  EXPECT_GT(sink, 0.0);
  EXPECT_LT(data.bodies[0].v_W.norm(), 1e-3);
}

TEST(DefaultsTest, LightPlateAtTwoMillisecondsStaysFiniteAndRests) {
  const Model model = LoadModel(LightPlate(), LoadOptions{});
  Data data = MakeData(model);
  for (int k = 0; k < 1000; ++k) Tick(model, data, TickInput{});  // 2 s
  std::printf("0.2 g plate: k = %g N/m, b = %g N s/m, z %.6f m\n",
              model.contact.scene_stiffness_N_per_m, model.contact.scene_damping_Ns_per_m,
              data.bodies[0].x_W.z());
  EXPECT_EQ(data.warnings[static_cast<int>(Warning::kNonFiniteState)].count, 0);
  EXPECT_TRUE(data.bodies[0].x_W.allFinite() && data.bodies[0].v_W.allFinite());
  // at rest on the floor: centre within its half-thickness of 0.5 mm, slower than 1 mm/s
  EXPECT_NEAR(data.bodies[0].x_W.z(), 0.0005, 0.0005);
  EXPECT_LT(data.bodies[0].v_W.norm(), 1e-3);
  // the scene law is stable for the plate; the tool's explicit law would not be if it pushed it
  EXPECT_LE(model.contact.scene_stiffness_N_per_m * 0.002 * 0.002 / 0.0002, 8.0 + 1e-12);
  EXPECT_LE(model.contact.scene_damping_Ns_per_m * 0.002 / 0.0002, 4.0 + 1e-12);
  EXPECT_TRUE(Mentions(model, "stiffness_N_per_m = 2000", "body 'plate'"));
}

TEST(DefaultsTest, UserSetTooSoftSceneStiffnessIsWarnedNamingTheBody) {
  LoadOptions options;
  options.contact.scene_stiffness_N_per_m = 1000.0;  // 20 kg sinks 0.196 m > 0.05 m
  const Model model = LoadModel(HeavyBox(), options);
  EXPECT_EQ(model.contact.scene_stiffness_N_per_m, 1000.0);  // kept
  ASSERT_EQ(model.load_warnings.size(), 1u);
  EXPECT_TRUE(Mentions(model, "scene_stiffness_N_per_m = 1000 N/m cannot hold", "body 'heavy'"))
      << model.load_warnings[0];
  EXPECT_TRUE(Mentions(model, "0.1962", "0.05 m")) << model.load_warnings[0];
}

TEST(DefaultsTest, UserSetUnstableSceneStiffnessIsWarnedNamingTheLightestBody) {
  LoadOptions options;
  options.contact.scene_stiffness_N_per_m = 1e5;  // k h^2 / m = 2000 for the plate
  options.contact.scene_damping_Ns_per_m = 50.0;  // b h / m = 500
  const Model model = LoadModel(LightPlate(), options);
  EXPECT_TRUE(Mentions(model, "scene_stiffness_N_per_m = 100000 N/m may be unstable", "'plate'"));
  EXPECT_TRUE(Mentions(model, "scene_damping_Ns_per_m = 50 N s/m may be unstable", "'plate'"));
}

TEST(DefaultsTest, AGivenValueEqualToTheDefaultIsKept) {
  LoadOptions options;
  options.contact.scene_stiffness_given = true;  // 2e5 N/m, as written by the user
  Model model = LoadModel(HeavyBox(), options);
  EXPECT_EQ(model.contact.scene_stiffness_N_per_m, 2.0e5);
  EXPECT_GT(model.contact.scene_damping_Ns_per_m, 100.0);  // not given: derived
  // without the flag the same value derives the stiffness that holds the box
  model = LoadModel(HeavyBox(), LoadOptions{});
  EXPECT_NEAR(model.contact.scene_stiffness_N_per_m, 20.0 * 9.81 / (0.01 * 0.05), 1e-6);
}

TEST(DefaultsTest, ATooHeavyUncompensatedToolIsWarned) {
  const std::string path = test::WriteTempFile(
      "heavy_tool.xml",
      "<mujoco><worldbody><geom name=\"floor\" type=\"plane\" size=\"1 1 0.1\"/>"
      "<body name=\"tool\" pos=\"0 0 0.05\"><freejoint/>"
      "<geom type=\"box\" size=\"0.05 0.05 0.05\" mass=\"20\"/></body></worldbody></mujoco>");
  const Model model = LoadModel(path, LoadOptions{});
  EXPECT_TRUE(Mentions(model, "stiffness_N_per_m = 2000 N/m cannot hold", "body 'tool' (20 kg)"));
}

TEST(DefaultsTest, ConfigureAgainKeepsTheDerivedLawAndDoesNotRepeatWarnings) {
  Model model = LoadModel(LightPlate(), LoadOptions{});
  const double k = model.contact.scene_stiffness_N_per_m, b = model.contact.scene_damping_Ns_per_m;
  const std::size_t n = model.load_warnings.size();
  Configure(model);
  EXPECT_EQ(model.contact.scene_stiffness_N_per_m, k);
  EXPECT_EQ(model.contact.scene_damping_Ns_per_m, b);
  EXPECT_EQ(model.load_warnings.size(), n);
  // a changed time step derives again: twice the step, a quarter of the stable stiffness
  model.timestep_s = 0.004;
  Configure(model);
  EXPECT_DOUBLE_EQ(model.contact.scene_stiffness_N_per_m, k / 4.0);
}

TEST(DefaultsTest, ShippedScenesKeepTodaysLawAndLoadWithoutWarnings) {
  for (const char* name : {"stack", "pile", "wall", "tap"}) {
    const Model model =
        LoadModel(std::string(RIGIDTOUCH_SCENES) + "/" + name + ".xml", LoadOptions{});
    EXPECT_EQ(model.contact.scene_stiffness_N_per_m, 2.0e5) << name;
    EXPECT_EQ(model.contact.scene_damping_Ns_per_m, 100.0) << name;
    EXPECT_EQ(model.contact.stiffness_N_per_m, 2000.0) << name;
    EXPECT_EQ(model.contact.damping_Ns_per_m, 2.0) << name;
    EXPECT_TRUE(model.load_warnings.empty()) << name << ": " << model.load_warnings.front();
  }
}

}  // namespace
}  // namespace rigidtouch
