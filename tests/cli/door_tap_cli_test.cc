// `rigidtouch tap` on a link of a jointed body (the shipped door's panel): the JSON reports the
// moving wall and its joint, and --compare-joint-limit refuses what it cannot compare.
#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <string>

#include "cli/cli_util.h"

namespace rigidtouch::test {
namespace {

std::string Door() {
  return std::string(RIGIDTOUCH_SOURCE_DIR) + "/scenes/door.xml";
}

// one tap on the panel from -y (towards the stop): the wall is the panel's face under the tool and
// moves; the joint's motion is in the JSON tick by tick (the same length as its times) and per
// tap; the door pushed into its stop went past it (the limit's row pushed back), so no damped
// swing is claimed; the tap gave the hand no energy and no force beyond the device's limit
TEST(DoorTapCliTest, TappingThePanelReportsTheMovingWallAndItsHinge) {
  const CliResult r =
      RunCli("tap --scene " + Door() +
             " --wall-geom panel --device omega3 --speed 0.2 --taps 1 --json --quiet");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_TRUE(j["wall"]["moving"].get<bool>());
  EXPECT_EQ(j["wall"]["geom"], "panel");
  EXPECT_NEAR(j["wall"]["normal"][1].get<double>(), -1.0, 1e-12);
  EXPECT_EQ(j["joint_limit_renderer"], "train");
  const auto& joint = j["joint"];
  EXPECT_EQ(joint["name"], "hinge");
  EXPECT_EQ(joint["position_unit"], "rad");
  ASSERT_GT(joint["time_s"].size(), 100u);
  EXPECT_EQ(joint["position"].size(), joint["time_s"].size());
  EXPECT_EQ(joint["velocity"].size(), joint["time_s"].size());
  ASSERT_EQ(j["taps"].size(), 1u);
  const auto& tap = j["taps"][0];
  EXPECT_TRUE(tap["joint"]["past_limit"].get<bool>());
  EXPECT_TRUE(tap["joint"]["damped_swing"].is_null());
  EXPECT_LE(tap["energy_to_user_J"].get<double>(), 0.0);
  EXPECT_LE(tap["peak_force_N"].get<double>(), j["max_force_N"].get<double>());
  EXPECT_TRUE(std::isfinite(tap["rate_hardness_N_per_m"].get<double>()));
}

TEST(DoorTapCliTest, CompareJointLimitRefusesWhatItCannotCompare) {
  struct Case {
    std::string args, message;
  };
  const std::string out = " --out-dir " + TempDir("door").string();
  for (const Case& c : {
           Case{"--compare-joint-limit penalty,event",
                "--compare-joint-limit: 'event' is not a "
                "joint-limit renderer; valid: penalty, "
                "impulse, train"},
           Case{"--compare-joint-limit penalty,wall1", "'wall1' is not a joint-limit renderer"},
           Case{"--compare-joint-limit penalty --joint-limit-renderer train",
                "give either --joint-limit-renderer or --compare-joint-limit"},
           Case{"--compare-joint-limit penalty --compare-walls",
                "give either --compare-joint-limit or --compare"},
           Case{"--compare-joint-limit penalty,penalty", "penalty"},
       }) {
    const CliResult r =
        RunCli("tap --scene " + Door() + " --wall-geom panel --quiet " + c.args + out);
    EXPECT_EQ(r.exit_code, 2) << c.args << ": " << r.err;
    EXPECT_NE(r.err.find("rigidtouch: error: "), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(c.message), std::string::npos) << c.args << ": " << r.err;
  }
  // a static wall has no joint whose limit could render
  const CliResult r =
      RunCli("tap --scene " + std::string(RIGIDTOUCH_SOURCE_DIR) +
             "/scenes/wall.xml --taps 1 --quiet --compare-joint-limit penalty" + out);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("--compare-joint-limit: the wall 'wall' of scene file"), std::string::npos)
      << r.err;
}

}  // namespace
}  // namespace rigidtouch::test
