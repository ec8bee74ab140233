// <flag contact="disable"/> and <flag constraint="disable"/> in a scene without a tool and
// without free bodies are honoured as MuJoCo honours them: no contacts (and, for constraint, no
// joint limits or frictionloss); with a tool they are still refused.
#include <gtest/gtest.h>

#include <string>

#include "dynamics/tree.h"
#include "rigidtouch/rigidtouch.h"
#include "test_util.h"

namespace rigidtouch {
namespace {

// a slider 5 cm above a floor, falling; limited to +-1 cm, with dry friction below its weight
std::string SliderXml(const std::string& flag) {
  return R"(<mujoco><option timestep="0.001">)" + flag + R"(</option><worldbody>
    <geom name="floor" type="plane" size="1 1 0.1"/>
    <body pos="0 0 0.05"><joint name="s" type="slide" axis="0 0 1" range="-0.01 0.01"
        limited="true" frictionloss="0.1"/>
      <geom type="sphere" size="0.01" mass="0.1"/></body></worldbody></mujoco>)";
}

double SlideAfter(const Model& m, int steps) {
  Data d = MakeData(m);
  const TickInput in;
  for (int s = 0; s < steps; ++s) Tick(m, d, in);
  return d.trees[0]->qpos[0];
}

TEST(DisabledConstraintsTest, ConstraintDisableWithoutAToolFreesTheJointAsInMuJoCo) {
  LoadOptions o;
  o.tool_name = "none";
  // 0.5 s of free fall: -g t^2 / 2 = -1.226 m, through the limit (-1 cm), past the friction
  // (0.1 N against 0.98 N would slow it) and through the floor (the sphere at -1.18 m)
  const Model free = LoadModel(
      test::WriteTempFile("slider_free.xml", SliderXml(R"(<flag constraint="disable"/>)")), o);
  std::string warnings;
  for (const std::string& w : free.load_warnings) warnings += w;
  EXPECT_NE(warnings.find("<flag constraint=\"disable\"/> honoured as in MuJoCo"),
            std::string::npos)
      << warnings;
  // explicit Euler in velocity: x_n = -g h^2 n (n + 1) / 2 with n = 500 (tolerance: rounding)
  const double h = 0.001, n = 500.0, g = 9.81;
  EXPECT_NEAR(SlideAfter(free, 500), -g * h * h * n * (n + 1) / 2, 1e-9);
  // without the flag the limit holds it near -1 cm
  const Model held = LoadModel(test::WriteTempFile("slider_held.xml", SliderXml("")), o);
  EXPECT_GT(SlideAfter(held, 500), -0.012);
}

TEST(DisabledConstraintsTest, ContactDisableWithAToolIsStillRefused) {
  const std::string xml = R"(<mujoco><option><flag contact="disable"/></option><worldbody>
    <geom name="floor" type="plane" size="1 1 0.1"/>
    <body name="tool" pos="0 0 0.05"><freejoint/><geom type="sphere" size="0.01" mass="0.1"/>
    </body></worldbody></mujoco>)";
  try {
    LoadModel(test::WriteTempFile("tool_contact_off.xml", xml), {});
    FAIL() << "loaded";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("<flag contact=\"disable\"/>"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace rigidtouch
