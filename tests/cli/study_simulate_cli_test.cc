// `rigidtouch study simulate` killed with SIGKILL at random points and resumed gives the same
// answers as an uninterrupted run with the same seed: none lost, none duplicated (end to end,
// through the real tap experiment).
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <random>
#include <regex>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "cli/cli_util.h"

namespace rigidtouch::test {
namespace {

namespace fs = std::filesystem;

// participant log file name -> its answers (test, series, condition, answer), in log order
std::map<std::string, std::vector<std::vector<int>>> Answers(const fs::path& dir) {
  std::map<std::string, std::vector<std::vector<int>>> out;
  if (!fs::exists(dir)) return out;
  for (const auto& entry : fs::directory_iterator(dir)) {
    std::ifstream in(entry.path());
    std::string line;
    auto& answers = out[entry.path().filename().string()];
    while (std::getline(in, line)) {
      const auto r = nlohmann::json::parse(line, nullptr, false);
      if (r.is_discarded() || r.value("type", "") != "answer") continue;  // a torn last line
      answers.push_back({r["test"].get<int>(), r["series"].get<int>(), r["condition"].get<int>(),
                         r["answer"].get<int>()});
    }
  }
  return out;
}

std::size_t AnswerCount(const std::map<std::string, std::vector<std::vector<int>>>& a) {
  std::size_t n = 0;
  for (const auto& [k, v] : a) n += v.size();
  return n;
}

// a seed is a whole decimal number from 0 to 2^64 - 1 in every study subcommand (CLI11 alone
// wrapped -1 to 2^64 - 1 and read 010 as octal)
TEST(StudySimulateCliTest, SeedsOutsideTheirRangeAreRefused) {
  const std::string protocol = std::string(RIGIDTOUCH_SOURCE_DIR) + "/studies/walls.json";
  const fs::path dir = TempDir("simseed");
  for (const std::string& cmd :
       {"study predict --protocol " + protocol + " --seed ",
        "study simulate --protocol " + protocol + " --participants 1 --log-dir " +
            (dir / "logs").string() + " --seed ",
        "study run --protocol " + protocol + " --presenter text --participant p1 --log " +
            (dir / "run.jsonl").string() + " --seed "}) {
    for (const std::string seed : {"-1", "18446744073709551616"}) {
      const CliResult r = RunCli(cmd + seed);
      EXPECT_EQ(r.exit_code, 2) << cmd << seed << "\n" << r.err;
      EXPECT_NE(r.err.find("--seed: " + seed + " is out of range"), std::string::npos)
          << cmd << seed << "\n"
          << r.err;
    }
  }
  EXPECT_FALSE(fs::exists(dir / "logs")) << "nothing is written for a refused seed";
  EXPECT_FALSE(fs::exists(dir / "run.jsonl"));
}

// the text presenter renders nothing: a device flag with it is refused, before any log exists
TEST(StudySimulateCliTest, TheTextPresenterRefusesTheDevicesFlags) {
  const std::string protocol = std::string(RIGIDTOUCH_SOURCE_DIR) + "/studies/walls.json";
  const fs::path dir = TempDir("textflags");
  const std::string run = "study run --protocol " + protocol +
                          " --presenter text --participant p1 --log " +
                          (dir / "run.jsonl").string();
  for (const std::string flag :
       {"--scene scenes/stack.xml", "--device omega3", "--connect sim", "--key k.key"}) {
    const CliResult r = RunCli(run + " " + flag);
    EXPECT_EQ(r.exit_code, 2) << flag << "\n" << r.err;
    const std::string name = flag.substr(0, flag.find(' '));
    EXPECT_NE(r.err.find("rigidtouch: error: " + name + " has no effect with --presenter text"),
              std::string::npos)
        << r.err;
  }
  EXPECT_FALSE(fs::exists(dir / "run.jsonl"));
}

// a simulated study of `participants` killed (SIGKILL) at random moments and resumed until it
// ends: its answers are those of a run never interrupted; returns the number of kills
int KillAndResumeUntilDone(int participants, const std::string& name) {
  const fs::path dir = TempDir(name);
  const std::string protocol = std::string(RIGIDTOUCH_SOURCE_DIR) + "/studies/walls.json";
  const std::string common = "study simulate --protocol " + protocol + " --participants " +
                             std::to_string(participants) + " --seed 77 --log-dir ";
  const CliResult ref = RunCli(common + (dir / "reference").string());
  EXPECT_EQ(ref.exit_code, 0) << ref.err;
  const auto expected = Answers(dir / "reference");
  const auto n = static_cast<std::size_t>(participants);
  EXPECT_EQ(expected.size(), n);
  EXPECT_EQ(AnswerCount(expected), n * 40u);  // 2 tests x 20 series each
  if (ref.exit_code != 0 || AnswerCount(expected) != n * 40u) return 0;

  const fs::path crashy = dir / "crashy";
  std::mt19937 rng(4242);
  int kills = 0;
  bool finished = false;
  std::size_t last = 0;
  for (int attempt = 0; attempt < 60 && !finished; ++attempt) {
    const std::string cmd = std::string("exec ") + RIGIDTOUCH_CLI + " " + common + crashy.string() +
                            " --resume >/dev/null 2>" + (dir / "err.txt").string();
    const pid_t pid = ::fork();
    if (pid == 0) {
      ::execl("/bin/sh", "sh", "-c", cmd.c_str(), static_cast<char*>(nullptr));
      ::_exit(127);
    }
    // kill at a random moment, but only once the run has made progress since the last kill
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
    const std::size_t target = last + 1 + rng() % 25;
    int status = 0;
    while (std::chrono::steady_clock::now() < deadline) {
      if (::waitpid(pid, &status, WNOHANG) == pid) {
        finished = WIFEXITED(status) && WEXITSTATUS(status) == 0;
        EXPECT_TRUE(finished) << ReadAll(dir / "err.txt");
        if (!finished) return kills;
        break;
      }
      if (AnswerCount(Answers(crashy)) >= target) {
        std::this_thread::sleep_for(std::chrono::microseconds(rng() % 2000));
        ::kill(pid, SIGKILL);
        ::waitpid(pid, &status, 0);
        ++kills;
        break;
      }
      std::this_thread::sleep_for(std::chrono::microseconds(200));
    }
    last = AnswerCount(Answers(crashy));
  }
  EXPECT_TRUE(finished);
  EXPECT_EQ(Answers(crashy), expected);
  fs::remove_all(dir);
  return kills;
}

// three participants (120 answers): a release-build test (label slow-cli)
TEST(StudySimulateCliTest, SlowKilledAndResumedEqualsAnUninterruptedRun) {
  EXPECT_GE(KillAndResumeUntilDone(3, "simkill3"), 3);  // several kill points
}

// its fast counterpart, run under the sanitizers too: one participant (40 answers; measured: 3
// kills)
TEST(StudySimulateCliTest, KilledAndResumedEqualsAnUninterruptedRun) {
  EXPECT_GE(KillAndResumeUntilDone(1, "simkill1"), 2);
}

// a study simulate that runs for several seconds: progress lines on stderr (none on stdout) while
// it works; SIGINT stops it with status 130 and resumable logs; --resume --quiet finishes it with
// no progress printed and every answer given once
TEST(StudySimulateCliTest, ProgressOnStderrAndCtrlCKeepsResumableLogs) {
  const fs::path dir = TempDir("simprogress");
  const std::string protocol = std::string(RIGIDTOUCH_SOURCE_DIR) + "/studies/walls.json";
  // a run long enough for three progress lines (6 s) before the stop: a participant takes about
  // 0.35 s in the release build and 12 s under AddressSanitizer, where the resumed run's 24 would
  // take 290 s
#if defined(RIGIDTOUCH_SANITIZE) || defined(RIGIDTOUCH_SANITIZE_THREAD)
  const int participants = 3;
#else
  const int participants = 24;
#endif
  const std::string common = "study simulate --protocol " + protocol + " --participants " +
                             std::to_string(participants) + " --seed 77 --log-dir " +
                             (dir / "logs").string();
  const fs::path err = dir / "err.txt", out = dir / "out.txt";
  const pid_t pid =
      SpawnCommand(std::string(RIGIDTOUCH_CLI) + " " + common + " 2>" + err.string(), out.string());
  // the arrival times of the progress lines
  std::vector<double> arrivals;
  const auto start = std::chrono::steady_clock::now();
  auto seconds = [&start] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  };
  std::size_t seen = 0;
  int early_status = 0;
  bool ended = false;
  while (arrivals.size() < 3 && seconds() < 120.0) {
    if (::waitpid(pid, &early_status, WNOHANG) == pid) {
      ended = true;  // finished before three progress lines: the run is too short for the test
      break;
    }
    const std::string text = ReadAll(err);
    std::size_t lines = 0;
    for (std::size_t at = text.find("rigidtouch: progress: study simulate: ");
         at != std::string::npos;
         at = text.find("rigidtouch: progress: study simulate: ", at + 1)) {
      ++lines;
    }
    for (; seen < lines; ++seen) arrivals.push_back(seconds());
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  ASSERT_FALSE(ended) << ReadAll(err);
  ::kill(pid, SIGINT);
  const int status = Wait(pid);
  const std::string stderr_text = ReadAll(err);
  ASSERT_GE(arrivals.size(), 3u) << stderr_text;
  // nothing before 2 s; then one every 2 s, give or take one simulated series on a loaded machine
  // (tolerance 1.5 s)
  EXPECT_GE(arrivals[0], 2.0);
  for (std::size_t k = 1; k < arrivals.size(); ++k) {
    EXPECT_LE(arrivals[k] - arrivals[k - 1], 3.5) << "line " << k;
  }
  EXPECT_EQ(status, 130) << stderr_text;
  EXPECT_EQ(ReadAll(out), "") << "progress and the stop message go to stderr only";
  EXPECT_NE(stderr_text.find("rigidtouch: interrupted: study simulate stopped at participant "),
            std::string::npos)
      << stderr_text;
  EXPECT_NE(stderr_text.find("run again with --resume to continue"), std::string::npos)
      << stderr_text;
  const std::size_t before = AnswerCount(Answers(dir / "logs"));
  EXPECT_GT(before, 0u);
  EXPECT_LT(before, participants * 40u);
  // the signal lands inside a session (its log says why it stopped) or, now and then on a loaded
  // machine, between two participants (every log written is then complete: nothing to say)
  int unfinished = 0;
  for (const auto& [log, list] : Answers(dir / "logs")) {
    if (list.size() == 40u) continue;
    ++unfinished;
    EXPECT_NE(ReadAll(dir / "logs" / log).find("interrupted by a signal"), std::string::npos)
        << log << ": the stopped session's log says why it stopped";
  }
  EXPECT_LE(unfinished, 1) << "only the session the signal reached is unfinished";

  const CliResult resumed = RunCli(common + " --resume --quiet");
  EXPECT_EQ(resumed.exit_code, 0) << resumed.err;
  EXPECT_EQ(resumed.err.find("progress"), std::string::npos) << resumed.err;
  const auto answers = Answers(dir / "logs");
  EXPECT_EQ(answers.size(), static_cast<std::size_t>(participants));
  for (const auto& [log, list] : answers) {
    EXPECT_EQ(list.size(), 40u) << log;  // 2 tests x 20 series, none lost or given twice
    std::set<std::pair<int, int>> series;
    for (const auto& a : list) series.insert({a[0], a[1]});
    EXPECT_EQ(series.size(), list.size()) << log;
  }
  fs::remove_all(dir);
}

// a protocol on an articulated scene: two conditions on scenes/door.xml that differ only in how
// the door's stop renders (penalty, or a train at the stop), the simulated taps aimed at the
// panel's -y face, pushing the door into its stop; `study simulate` runs it end to end and the
// log keeps each condition's joint-limit renderer
TEST(StudySimulateCliTest, DoorStopProtocolWithTwoJointLimitRenderers) {
  const fs::path dir = TempDir("simdoor");
  const std::string door = std::string(RIGIDTOUCH_SOURCE_DIR) + "/scenes/door.xml";
  const std::string aim = R"("wall_point_m": [0.6, -0.02, 1.0], "wall_normal": [0, -1, 0])";
  const std::string condition = R"({"renderer": "train", "t_collision_s": 0.1, "frequency_hz": )"
                                R"(250, "scene": ")" +
                                door + R"(", )" + aim + R"(, "joint_limit_renderer": )";
  std::ofstream(dir / "door.json")
      << R"({"format": "rigidtouch-study-protocol", "format_version": 1, "name": "door stop",)"
      << R"( "description": "the door's stop as penalty or train", "instructions": "push",)"
      << R"( "familiarization_taps": 1, "series": 4, "taps_per_series": 1,)"
      << R"( "randomization": {"series_order": "balanced", "test_order": "fixed"},)"
      << R"( "conditions": {"penalty stop": )" << condition << R"("penalty"}, "train stop": )"
      << condition << R"("train"}},)"
      << R"( "tests": [{"name": "stop", "conditions": ["penalty stop", "train stop"],)"
      << R"( "keys": ["p", "t"], "instructions": "which stop?"}]})";
  const CliResult r =
      RunCli("study simulate --protocol " + (dir / "door.json").string() +
             " --participants 1 --seed 5 --quiet --log-dir " + (dir / "logs").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto answers = Answers(dir / "logs");
  ASSERT_EQ(answers.size(), 1u);
  EXPECT_EQ(AnswerCount(answers), 4u);  // one test of 4 series
  // the log's protocol holds both joint-limit renderers and the aim
  const std::string log = ReadAll(fs::directory_iterator(dir / "logs")->path());
  EXPECT_NE(log.find(R"("joint_limit_renderer":"penalty")"), std::string::npos);
  EXPECT_NE(log.find(R"("joint_limit_renderer":"train")"), std::string::npos);
  EXPECT_NE(log.find(R"("wall_normal":[0.0,-1.0,0.0])"), std::string::npos);
  // a joint-limit renderer that cannot render a stop is refused, naming the field
  std::ofstream(dir / "bad.json") << std::regex_replace(
      ReadAll(dir / "door.json"), std::regex(R"("penalty"\})"), R"("event"})");
  const CliResult bad =
      RunCli("study simulate --protocol " + (dir / "bad.json").string() +
             " --participants 1 --seed 5 --quiet --log-dir " + (dir / "bad").string());
  EXPECT_EQ(bad.exit_code, 2) << bad.err;
  EXPECT_NE(bad.err.find("joint_limit_renderer"), std::string::npos) << bad.err;
  fs::remove_all(dir);
}

}  // namespace
}  // namespace rigidtouch::test
