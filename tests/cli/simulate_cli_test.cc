// End-to-end tests of `rigidtouch simulate`.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "cli/cli_util.h"

namespace rigidtouch::test {
namespace {

std::string Scene(const std::string& name) {
  return std::string(RIGIDTOUCH_SOURCE_DIR) + "/" + name;
}

TEST(SimulateCliTest, JsonReportsBodiesImpulsesAndContacts) {
  const CliResult r = RunCli("simulate --scene " + Scene("scenes/tap.xml") +
                             " --steps 300 --tool-force 0 0 -2 --renderer train --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  ASSERT_EQ(j["bodies"].size(), 1u);
  EXPECT_EQ(j["bodies"][0]["name"], "tool");
  for (const char* key : {"position_m", "velocity_mps", "angular_velocity_radps"}) {
    EXPECT_EQ(j["bodies"][0][key].size(), 3u) << key;
  }
  EXPECT_EQ(j["timestep_s"], 0.001);  // the MJCF option timestep
  ASSERT_GE(j["impulses"].size(), 1u);
  const auto& first = j["impulses"][0];
  for (const char* key : {"step", "time_s", "contacts", "kinetic_energy_before_J",
                          "kinetic_energy_after_J", "impulse_norm_Ns"}) {
    EXPECT_TRUE(first.contains(key)) << key;
  }
  for (const auto& e : j["impulses"]) {
    EXPECT_LE(e["kinetic_energy_after_J"].get<double>(),
              e["kinetic_energy_before_J"].get<double>() + 1e-15);
  }
  EXPECT_EQ(j["max_contacts"], 1);
  EXPECT_TRUE(j["warnings"].is_object());
}

TEST(SimulateCliTest, ErrorsGoToStderrWithNonZeroExit) {
  CliResult r = RunCli("simulate --scene " + Scene("tests/scenes/malformed.xml"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("malformed.xml"), std::string::npos) << r.err;
  EXPECT_TRUE(r.out.empty());
  r = RunCli("simulate --scene " + Scene("scenes/tap.xml") + " --renderer train --frequency 5000");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("frequency_hz"), std::string::npos) << r.err;
  r = RunCli("simulate --scene " + Scene("scenes/tap.xml") + " --renderer train --restitution 0.5");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("perfectly plastic"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace rigidtouch::test
