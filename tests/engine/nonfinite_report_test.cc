// A run whose state goes non-finite is an error of `rigidtouch simulate` (issue 16): the results
// are printed, then an error line on stderr names the count and the first step, exit status 2.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>

#include "cli/cli_util.h"

namespace rigidtouch::test {
namespace {

std::string Squeeze() {
  return std::string(RIGIDTOUCH_SOURCE_DIR) + "/tests/scenes/squeeze.xml";
}

TEST(NonFiniteReportTest, SimulateReportsTheNonFiniteStateOnStderrAndExitsWithTwo) {
  const CliResult r = RunCli("simulate --scene " + Squeeze() + " --steps 1000");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  // the load warned first that the tool's law is unstable for its mass at this step
  EXPECT_EQ(r.err.rfind("rigidtouch: warning: stiffness_N_per_m = 2000 N/m is unstable", 0), 0u)
      << r.err;
  EXPECT_NE(r.err.find("\nrigidtouch: error: the simulated state became non-finite"),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("first at step "), std::string::npos) << r.err;
  // the counted warning in the one warning voice, on stderr: what it counts, in how many ticks
  EXPECT_NE(r.err.find("rigidtouch: warning: a non-finite simulation state (the state reset) in "),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find(" ticks (non_finite_state)\n"), std::string::npos) << r.err;
  EXPECT_EQ(r.out.find("warning"), std::string::npos) << r.out;
}

TEST(NonFiniteReportTest, SimulateJsonSaysSoAndExitsWithTwo) {
  const CliResult r = RunCli("simulate --scene " + Squeeze() + " --steps 1000 --json");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  const auto& nf = j["non_finite_state"];
  ASSERT_TRUE(nf.is_object()) << r.out;
  const int count = nf["count"].get<int>();
  EXPECT_GE(count, 1);
  EXPECT_EQ(j["warnings"]["non_finite_state"], count);
  EXPECT_GE(nf["first_step"].get<long>(), 0);
  EXPECT_GT(nf["first_time_s"].get<double>(), 0.0);
  // the same words on stderr as in the JSON
  EXPECT_NE(r.err.find(nf["error"].get<std::string>()), std::string::npos) << r.err;
}

// a run that stays finite exits 0 and says so with null
TEST(NonFiniteReportTest, AFiniteRunExitsWithZero) {
  const CliResult r = RunCli("simulate --scene " + Squeeze() + " --steps 50 --json");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(nlohmann::json::parse(r.out)["non_finite_state"].is_null()) << r.out;
}

}  // namespace
}  // namespace rigidtouch::test
