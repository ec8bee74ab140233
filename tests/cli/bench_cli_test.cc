// `rigidtouch bench --reference`: the fixed job timed after each step is reported beside the
// steps, leaves the scene's run as it was, and needs the warm-up it is sized from. No timing is
// asserted (machines are noisy): only what the report must hold whatever the times are.
#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "cli/cli_util.h"

namespace rigidtouch::test {
namespace {

nlohmann::json Json(const CliResult& r) {
  EXPECT_EQ(r.exit_code, 0) << r.err;
  return r.exit_code == 0 ? nlohmann::json::parse(r.out) : nlohmann::json::object();
}

const std::string kBench =
    "bench --json --steps 50 --warmup 200 --scene " + std::string(RIGIDTOUCH_SCENES) + "/pile.xml";

TEST(BenchCliTest, TheReferenceJobIsReportedBesideTheStepsAndLeavesTheRunAsItWas) {
  const auto plain = Json(RunCli(kBench));
  const auto with = Json(RunCli(kBench + " --reference"));
  EXPECT_FALSE(plain.contains("reference"));
  ASSERT_TRUE(with.contains("reference"));
  // the scene ran the same steps: the job touches nothing of it
  for (const char* key : {"contacts", "max_contacts", "impulses", "deepest_penetration_m"}) {
    EXPECT_EQ(with[key], plain[key]) << key;
  }
  const nlohmann::json& r = with["reference"];
  EXPECT_GE(r["units"].get<long>(), 1);
  EXPECT_TRUE(std::isfinite(r["checksum"].get<double>()));
  const double job_median = r["median_ns"].get<double>();
  ASSERT_GT(job_median, 0.0);
  EXPECT_LE(job_median, r["p99_ns"].get<double>());
  EXPECT_LE(r["p99_ns"].get<double>(), r["p999_ns"].get<double>());
  EXPECT_LE(r["p999_ns"].get<double>(), r["max_ns"].get<double>());
  // the ratios are the steps' over the job's, and each one's tail over its own median (1e-12
  // relative: one division each)
  for (const char* key : {"median_ns", "p99_ns", "p999_ns", "max_ns"}) {
    const double expected = with[key].get<double>() / r[key].get<double>();
    EXPECT_NEAR(r["step_over_job"][key].get<double>(), expected, 1e-12 * expected) << key;
  }
  const double steps_tail = with["p999_ns"].get<double>() / with["median_ns"].get<double>();
  const double job_tail = r["p999_ns"].get<double>() / job_median;
  EXPECT_NEAR(r["tail_over_median"]["steps"]["p999"].get<double>(), steps_tail, 1e-12 * steps_tail);
  EXPECT_NEAR(r["tail_over_median"]["job"]["p999"].get<double>(), job_tail, 1e-12 * job_tail);
}

TEST(BenchCliTest, TheReferenceNeedsTheWarmUpItIsSizedFrom) {
  const CliResult r = RunCli("bench --steps 10 --warmup 199 --reference --scene " +
                             std::string(RIGIDTOUCH_SCENES) + "/pile.xml");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("rigidtouch: error: --reference needs --warmup >= 200 (got 199)"),
            std::string::npos)
      << r.err;
  EXPECT_TRUE(r.out.empty()) << r.out;
}

// bench's own flags: a non-finite tool force (refused by simulate too) and a negative step
// count are refused, naming the flag, instead of being run or reported as given
TEST(BenchCliTest, NonFiniteToolForceAndNegativeStepCountsAreRefused) {
  const std::string bench = "bench --json --scene " + std::string(RIGIDTOUCH_SCENES) + "/wall.xml";
  for (const auto& [args, message] : std::vector<std::pair<std::string, std::string>>{
           {" --steps 1 --warmup 0 --tool-force 0 0 nan", "--tool-force must be finite"},
           {" --steps 1 --warmup 0 --tool-force inf 0 0", "--tool-force must be finite"},
           {" --steps 1 --warmup -5", "--warmup must be >= 0, got -5"},
           {" --steps -3 --warmup 0", "--steps must be >= 1, got -3"}}) {
    const CliResult r = RunCli(bench + args);
    EXPECT_EQ(r.exit_code, 2) << args << "\n" << r.err;
    EXPECT_NE(r.err.find("rigidtouch: error: " + message), std::string::npos) << args << r.err;
    EXPECT_TRUE(r.out.empty()) << args << r.out;
  }
  EXPECT_EQ(Json(RunCli(bench + " --steps 1 --warmup 0"))["warmup_steps"], 0);
}

}  // namespace
}  // namespace rigidtouch::test
