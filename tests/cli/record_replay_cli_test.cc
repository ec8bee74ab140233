// `serve --record` and `--device replay:LOG` end to end: a session recorded on the simulated
// device replays through the same renderer to the same record byte for byte (paced and unpaced),
// through another renderer to a trace the tap metrics read, and bad replays are refused.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>

#include "analysis/tap_metrics.h"
#include "cli/cli_util.h"
#include "io/trace_csv.h"

namespace rigidtouch::test {
namespace {

TEST(RecordReplayCliTest, ReplayThroughTheSameRendererReproducesTheRecordBitForBit) {
  const auto dir = TempDir("record_replay");
  const std::string rec = (dir / "session.csv").string();
  const CliResult a = RunCli("serve --device sim --taps 2 --record " + rec + " --json");
  ASSERT_EQ(a.exit_code, 0) << a.err;
  const auto ja = nlohmann::json::parse(a.out);
  ASSERT_GT(ja["impulses"].get<long>(), 0);  // the taps hit the wall with the default train
  EXPECT_EQ(ja["record_queue"]["dropped"].get<long>(), 0);
  const std::string recorded = ReadAll(rec);
  ASSERT_GT(recorded.size(), 1000u);

  for (const char* pace : {"max", "rate"}) {
    const std::string again = (dir / (std::string("again_") + pace + ".csv")).string();
    const CliResult b = RunCli("serve --device replay:" + rec + " --replay-pace " + pace +
                               " --record " + again + " --json");
    ASSERT_EQ(b.exit_code, 0) << b.err;
    const auto jb = nlohmann::json::parse(b.out);
    EXPECT_EQ(jb["device"]["replayed_ticks"], jb["device"]["recorded_ticks"]) << pace;
    EXPECT_EQ(jb["device"]["recorded_ticks"].get<long>(), ja["loop"]["ticks"].get<long>());
    EXPECT_EQ(jb["impulses"], ja["impulses"]) << pace;
    // every state, command and annotation, as the same shortest-round-trip text
    EXPECT_TRUE(ReadAll(again) == recorded) << pace;
  }
  std::filesystem::remove_all(dir);
}

TEST(RecordReplayCliTest, ReplayThroughAnotherRendererGivesATraceTheTapMetricsRead) {
  const auto dir = TempDir("record_replay_other");
  const std::string rec = (dir / "session.csv").string();
  ASSERT_EQ(RunCli("serve --device sim --taps 2 --replay-pace rate --record " + rec).exit_code,
            2);  // --replay-pace belongs to a replay
  ASSERT_EQ(RunCli("serve --device sim --taps 2 --record " + rec).exit_code, 0);
  const std::string trace = (dir / "penalty.csv").string();
  const CliResult r = RunCli("serve --device replay:" + rec +
                             " --replay-pace max --renderer penalty --trace " + trace + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(nlohmann::json::parse(r.out)["impulses"].get<long>(), 0);  // penalty only

  const std::vector<TraceSample> samples = io::ReadTraceCsv(trace);
  const auto taps = analysis::SplitTaps(samples);
  ASSERT_EQ(taps.size(), 2u);  // the recorded tap indices came through the replay
  for (const auto& tap : taps) {
    const analysis::TapMetrics m = analysis::ComputeTapMetrics(tap);
    EXPECT_TRUE(m.contact);
    EXPECT_GT(m.peak_force_N, 0.5);
    EXPECT_LE(m.peak_force_N, 3.3);  // the Touch's limit
    EXPECT_TRUE(m.impulses.empty());
    EXPECT_GT(m.approach_speed_mps, 0.05);
    EXPECT_GT(m.max_penetration_m, 0.0);
  }
  std::filesystem::remove_all(dir);
}

TEST(RecordReplayCliTest, BadReplaysAreRefused) {
  const auto dir = TempDir("record_replay_bad");
  const std::string rec = (dir / "session.csv").string();
  ASSERT_EQ(RunCli("serve --device sim --taps 1 --record " + rec).exit_code, 0);
  const struct {
    std::string args, message;
  } cases[] = {
      {"serve --device replay:" + rec + " --rate 2000", "differs from the record's rate 1000 Hz"},
      {"serve --device replay:" + rec + " --taps 3", "a replay moves the handle as recorded"},
      {"serve --device replay:" + (dir / "none.csv").string(), "none.csv"},
      {"serve --device replay:", "needs the record file's path"},
      {"serve --device replay:" + rec + " --replay-pace fast", "--replay-pace"},
      {"serve --device sim --taps 1 --record " + (dir / "no" / "r.csv").string(), "r.csv"},
  };
  for (const auto& c : cases) {
    const CliResult r = RunCli(c.args);
    EXPECT_EQ(r.exit_code, 2) << c.args;
    EXPECT_NE(r.err.find("rigidtouch: error:"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(c.message), std::string::npos) << c.args << ": " << r.err;
  }
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace rigidtouch::test
