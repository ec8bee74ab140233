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

TEST(Report, RepetitionsArePooledInSceneAndEngineOrder) {
  // two repetitions of stack / rigidtouch, interleaved with a pile run: durations 1..3 and 4..6
  // pool to six, whose median (nearest rank, the 3rd) is 3; contacts are weighted by steps
  RunResult first = Result("stack", "rigidtouch", 2, 3);
  first.durations_ns = {1, 2, 3};
  first.mean_contacts = 10.0;
  first.gates.failures = {"top box moved"};
  RunResult second = Result("stack", "rigidtouch", 5, 6);
  second.durations_ns = {4, 5, 6};
  second.mean_contacts = 20.0;
  second.gates.failures = {"top box moved", "NaN"};
  second.gates.deepest_penetration_m = 2e-3;
  RunResult pile = Result("pile", "rigidtouch", 7, 7);
  pile.durations_ns = {7};
  const std::vector<RunResult> merged =
      MergeRepetitions({first, pile, second}, {"stack", "pile", "tap"}, {"rigidtouch", "bullet"});
  ASSERT_EQ(merged.size(), 2u);  // tap and bullet never ran
  EXPECT_EQ(merged[0].scene, "stack");
  EXPECT_EQ(merged[1].scene, "pile");
  EXPECT_EQ(merged[0].time.count, 6);
  EXPECT_EQ(merged[0].time.median_ns, 3.0);
  EXPECT_EQ(merged[0].time.max_ns, 6.0);
  EXPECT_EQ(merged[0].durations_ns.size(), 6u);
  EXPECT_DOUBLE_EQ(merged[0].mean_contacts, 15.0);
  EXPECT_EQ(merged[0].gates.failures, (std::vector<std::string>{"top box moved", "NaN"}));
  EXPECT_EQ(merged[0].gates.deepest_penetration_m, 2e-3);
  EXPECT_EQ(merged[1].time.count, 1);
}

}  // namespace
}  // namespace rigidtouch::bench

#else
RIGIDTOUCH_BENCH_SKIPPED_TEST(Report)
#endif
