// End-to-end: the articulated test scenes (written in the style of MuJoCo's model files) load and
// step with `simulate --tool none`, and the JSON report lists every joint.
#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>

#include "cli/cli_util.h"

namespace rigidtouch::test {
namespace {

bool AllFinite(const nlohmann::json& v) {
  if (v.is_number()) return std::isfinite(v.get<double>());
  if (v.is_array()) {
    for (const auto& x : v) {
      if (!AllFinite(x)) return false;
    }
    return true;
  }
  return false;
}

// each scene: 300 steps, every joint's position and velocity finite, the types and sizes as the
// file says (a ball's position is a unit quaternion w x y z, its velocity 3 numbers)
TEST(ArticulatedCliTest, TestScenesStepThreeHundredStepsWithFiniteJointStates) {
  struct Expected {
    const char* file;
    int joints, balls;
  };
  for (const Expected& e : {Expected{"humanoid_like.xml", 9, 4}, Expected{"arm.xml", 4, 0},
                            Expected{"door.xml", 2, 0}}) {
    const CliResult r =
        RunCli("simulate --scene " + std::string(RIGIDTOUCH_SOURCE_DIR) +
               "/tests/scenes/articulated/" + e.file + " --tool none --steps 300 --json");
    ASSERT_EQ(r.exit_code, 0) << e.file << ": " << r.err;
    const auto j = nlohmann::json::parse(r.out);
    ASSERT_EQ(j["joints"].size(), static_cast<std::size_t>(e.joints)) << e.file;
    int balls = 0;
    for (const auto& joint : j["joints"]) {
      EXPECT_TRUE(AllFinite(joint["position"]) && AllFinite(joint["velocity"])) << joint.dump();
      EXPECT_TRUE(joint["at_limit"].is_boolean());
      if (joint["type"] == "ball") {
        ++balls;
        ASSERT_EQ(joint["position"].size(), 4u);
        double norm2 = 0.0;
        for (const auto& c : joint["position"]) norm2 += c.get<double>() * c.get<double>();
        EXPECT_NEAR(norm2, 1.0, 1e-9);
        EXPECT_EQ(joint["velocity"].size(), 3u);
      }
    }
    EXPECT_EQ(balls, e.balls) << e.file;
    EXPECT_EQ(j["bodies"].size(), 0u) << e.file;  // no free body, no placeholder tool shown
    EXPECT_TRUE(j["non_finite_state"].is_null()) << e.file;  // the state stayed finite
  }
}

// the door, opened at 1 rad/s from -0.5 rad, reaches its stop at 0 rad within 0.6 s and the report
// says so; the drawer's spring pulls it towards springref -0.1 m
// the door swings onto its stop at q = 0 (from -0.5 rad at 1 rad/s) and stays there: the limit
// is a row of its contact group (before, it only reported at_limit while passing it)
TEST(ArticulatedCliTest, DoorStopsAtItsHingeLimit) {
  const CliResult r = RunCli("simulate --scene " + std::string(RIGIDTOUCH_SOURCE_DIR) +
                             "/tests/scenes/articulated/door.xml --tool none --steps 600 --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["joints"][0]["name"], "hinge");
  const double q = j["joints"][0]["position"].get<double>();
  EXPECT_LT(q, 1e-3) << j["joints"][0].dump();   // not through its stop
  EXPECT_GT(q, -0.05) << j["joints"][0].dump();  // stopped there, not bounced off
  EXPECT_LT(j["joints"][1]["position"].get<double>(), 0.0);
}

TEST(ArticulatedCliTest, ToolForceWithoutAToolIsRefused) {
  for (const std::string command : {"simulate", "bench"}) {
    const CliResult r = RunCli(command + " --scene " + std::string(RIGIDTOUCH_SOURCE_DIR) +
                               "/tests/scenes/articulated/door.xml --tool none --tool-force 0 0 1");
    EXPECT_EQ(r.exit_code, 2) << command;
    EXPECT_NE(r.err.find("rigidtouch: error: --tool-force needs a tool"), std::string::npos)
        << command << ": " << r.err;
  }
}

TEST(ArticulatedCliTest, BenchRunsASceneWithoutATool) {
  const CliResult r =
      RunCli("bench --scene " + std::string(RIGIDTOUCH_SOURCE_DIR) +
             "/tests/scenes/articulated/arm.xml --tool none --steps 200 --warmup 10 --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["steps"], 200);
  EXPECT_GT(j["median_ns"].get<double>(), 0.0);
}

// --joint-limit-renderer sets render.joint_limit_renderer: with the walls' renderer at penalty,
// the door of door.xml swung onto its stop gets no impulse (penalty), single impulses of one
// (impulse) or the impulses of a train (train); event is refused naming the flag
TEST(ArticulatedCliTest, JointLimitRendererFlagChoosesHowTheDoorStopRenders) {
  const std::string door =
      std::string(RIGIDTOUCH_SOURCE_DIR) + "/tests/scenes/articulated/door.xml";
  const auto impulses = [&door](const std::string& renderer) {
    const CliResult r = RunCli("simulate --scene " + door +
                               " --tool none --steps 1000 --json --renderer penalty "
                               "--joint-limit-renderer " +
                               renderer);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return nlohmann::json::parse(r.out)["impulses"];
  };
  EXPECT_EQ(impulses("penalty").size(), 0u);
  const auto single = impulses("impulse");
  ASSERT_GE(single.size(), 1u);
  for (const auto& e : single) EXPECT_EQ(e["total"], 1);
  const auto train = impulses("train");
  ASSERT_GT(train.size(), single.size());
  EXPECT_GT(train[0]["total"].get<int>(), 1);
  const CliResult bad =
      RunCli("simulate --scene " + door + " --tool none --steps 10 --joint-limit-renderer event");
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("--joint-limit-renderer"), std::string::npos) << bad.err;
}

}  // namespace
}  // namespace rigidtouch::test
