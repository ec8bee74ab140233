// End-to-end tests of `rigidtouch simulate`.
#include <gtest/gtest.h>

#include <algorithm>

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

// a mesh whose vertices are all one point: refused in rigidtouch's words, naming the mesh and
// its line, never with Qhull's own report (issue 51; before: "QH6421 qhull internal error ...
// Please send the input and output to qhull_bug@qhull.org" and "Object name = point, id = 0")
TEST(SimulateCliTest, ADegenerateMeshIsRefusedInRigidtouchsWords) {
  const CliResult r = RunCli("simulate --scene " + Scene("tests/scenes/degenerate_mesh.xml"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_TRUE(r.out.empty()) << r.out;
  EXPECT_EQ(r.err.rfind("rigidtouch: error: scene file '", 0), 0u) << r.err;
  EXPECT_NE(r.err.find("degenerate_mesh.xml"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("mesh 'point' (line 6)"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("convex hull cannot be built"), std::string::npos) << r.err;
  for (const char* foreign : {"qhull internal error", "qhull_bug", "Object name",
                              "Error:", "While executing", "Options selected"}) {
    EXPECT_EQ(r.err.find(foreign), std::string::npos) << foreign << " in: " << r.err;
  }
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << "one line: " << r.err;
}

}  // namespace
}  // namespace rigidtouch::test
