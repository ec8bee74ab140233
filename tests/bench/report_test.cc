#include "bench_test_config.h"

#ifdef RIGIDTOUCH_BENCH_ENABLED

#include "bench/report.h"

namespace rigidtouch::bench {
namespace {

RunResult Result(const std::string& scene, const std::string& engine, double median_ns,
                 double p999_ns) {
  RunResult result;
  result.scene = scene;
  result.engine = engine;
  result.time.count = 100;
  result.time.median_ns = median_ns;
  result.time.p99_ns = p999_ns;
  result.time.p999_ns = p999_ns;
  result.time.max_ns = p999_ns;
  return result;
}

TEST(Report, RatioIsReferenceOverPeerForMedianAndTail) {
  const std::vector<RunResult> results = {Result("tap", "rigidtouch", 3000, 9000),
                                          Result("tap", "mujoco", 1500, 4500)};
  const std::string table = FormatRatioTable(results, "rigidtouch", {"mujoco"});
  // 3000 / 1500 = 2.00, 9000 / 4500 = 2.00
  EXPECT_NE(table.find("rigidtouch/mujoco"), std::string::npos) << table;
  EXPECT_NE(table.find("2.00 (2.00)"), std::string::npos) << table;
  EXPECT_EQ(table.find("!"), table.find("!: a gate failed")) << table;
}

TEST(Report, MissingRunsReadNotAvailableAndGateFailuresAreFlagged) {
  RunResult failed = Result("stack", "bullet", 1000, 2000);
  failed.gates.failures.push_back("box_9 moved 4 mm over 10000 steps (limit 1 mm)");
  const std::vector<RunResult> results = {Result("stack", "rigidtouch", 500, 1000), failed,
                                          Result("pile", "mujoco", 10, 20)};
  const std::string table = FormatRatioTable(results, "rigidtouch", {"bullet", "mujoco"});
  EXPECT_NE(table.find("0.50 (0.50) !"), std::string::npos) << table;
  EXPECT_NE(table.find("n/a"), std::string::npos) << table;

  const std::string runs = FormatResultTable(results);
  EXPECT_NE(runs.find("FAILED"), std::string::npos) << runs;
  EXPECT_NE(runs.find("stack / bullet: box_9 moved 4 mm"), std::string::npos) << runs;
  // 1000 ns median is printed as 1.0 us
  EXPECT_NE(runs.find("1.0"), std::string::npos) << runs;
}

}  // namespace
}  // namespace rigidtouch::bench

#else
RIGIDTOUCH_BENCH_SKIPPED_TEST(Report)
#endif
