// Packed scenes settle without a dropped pair or contact (issue 16): boxes packed face to face
// overlap many neighbours' bounding boxes at once, more than a fixed number of pairs per geom.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "rigidtouch/rigidtouch.h"
#include "test_util.h"

namespace rigidtouch {
namespace {

struct Settled {
  std::string warnings;  // every warning counted, "name xN" each
  double max_speed_mps = 0.0;
};

// runs the scene for 1 s with no input and reports its warnings and the fastest body's speed
Settled RunOneSecond(const std::string& path) {
  const Model m = LoadModel(path, {});
  Data d = MakeData(m);
  const long steps = std::lround(1.0 / m.timestep_s);
  for (long s = 0; s < steps; ++s) Tick(m, d, TickInput{});
  Settled out;
  for (int w = 0; w < static_cast<int>(Warning::kCount); ++w) {
    const WarningStat& stat = d.warnings[w];
    if (stat.count > 0) {
      out.warnings += std::string(WarningName(static_cast<Warning>(w))) + " x" +
                      std::to_string(stat.count) + " ";
    }
  }
  for (const BodyState& b : d.bodies) {
    out.max_speed_mps = std::max(out.max_speed_mps, b.v_W.norm());
  }
  return out;
}

class PackedSceneTest : public ::testing::TestWithParam<std::string> {};

TEST_P(PackedSceneTest, SettlesWithoutAnyWarningWithinOneSecond) {
  const Settled s = RunOneSecond(GetParam());
  EXPECT_EQ(s.warnings, "");
  EXPECT_LT(s.max_speed_mps, 0.05);
}

INSTANTIATE_TEST_SUITE_P(Scenes, PackedSceneTest,
                         ::testing::Values(test::TestScene("columns4x6.xml"),
                                           test::TestScene("cube3.xml"),
                                           test::TestScene("cube5.xml"),
                                           std::string(RIGIDTOUCH_SCENES) + "/pile.xml"));

}  // namespace
}  // namespace rigidtouch
