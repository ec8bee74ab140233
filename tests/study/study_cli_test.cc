// End-to-end tests of `rigidtouch study run`, `study analyze` and `study predict`: the real
// executable, answers on stdin, the text presenter, SIGKILL at random points, bad inputs.
// (`study simulate`'s resume path is tested in simulate_test.)
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iostream>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "study/log.h"
#include "study/random.h"
#include "study/test_files.h"

namespace rigidtouch::study {
namespace {

using nlohmann::json;
using testing::AppendFile;
using testing::kWalls;
using testing::ReadFile;
using testing::ScratchDir;
using testing::WriteFile;

const std::string kCli = RIGIDTOUCH_CLI;

// a running CLI process with a pipe to its stdin
struct Child {
  pid_t pid = -1;
  int stdin_fd = -1;
};

Child Spawn(const std::vector<std::string>& args, const std::string& out_path,
            const std::string& err_path) {
  signal(SIGPIPE, SIG_IGN);  // a child that exits early must not kill the test
  int fds[2];
  if (pipe(fds) != 0) throw std::runtime_error("pipe failed");
  std::fflush(nullptr);
  const pid_t pid = fork();
  if (pid < 0) throw std::runtime_error("fork failed");
  if (pid == 0) {
    dup2(fds[0], STDIN_FILENO);
    close(fds[0]);
    close(fds[1]);
    const int out = open(out_path.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
    const int err = open(err_path.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
    dup2(out, STDOUT_FILENO);
    dup2(err, STDERR_FILENO);
    std::vector<char*> argv;
    argv.push_back(const_cast<char*>(kCli.c_str()));
    for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    execv(kCli.c_str(), argv.data());
    _exit(127);
  }
  close(fds[0]);
  return {pid, fds[1]};
}

void Feed(const Child& child, const std::string& text) {
  std::size_t done = 0;
  while (done < text.size()) {
    const ssize_t n = write(child.stdin_fd, text.data() + done, text.size() - done);
    if (n <= 0) return;  // the child has gone
    done += static_cast<std::size_t>(n);
  }
}

struct Result {
  int exit_code = -1;
  std::string out;
  std::string err;
};

// runs the CLI to completion with `input` on stdin
Result RunCli(const ScratchDir& dir, const std::vector<std::string>& args,
              const std::string& input = "") {
  const std::string out = dir.File("cli.out");
  const std::string err = dir.File("cli.err");
  WriteFile(out, "");
  WriteFile(err, "");
  const Child child = Spawn(args, out, err);
  Feed(child, input);
  close(child.stdin_fd);
  int status = 0;
  waitpid(child.pid, &status, 0);
  Result r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = ReadFile(out);
  r.err = ReadFile(err);
  return r;
}

// a protocol with two tests of 6 series; test "first" answers with keys a/b, "second" 1/2
std::string WriteProtocol(const ScratchDir& dir, const std::string& name = "e2e") {
  const json protocol = {
      {"name", name},
      {"series", 6},
      {"instructions", "Scripted end-to-end session."},
      {"conditions",
       {{"soft", {{"renderer", "penalty"}, {"stiffness_N_per_m", 400}}},
        {"click", {{"renderer", "impulse"}, {"restitution", 0}}},
        {"buzz", {{"renderer", "train"}, {"t_collision_s", 0.1}, {"frequency_hz", 250}}}}},
      {"tests",
       {{{"name", "first"}, {"conditions", {"soft", "click"}}, {"keys", {"a", "b"}}},
        {{"name", "second"}, {"conditions", {"click", "buzz"}}}}}};
  const std::string path = dir.File(name + ".json");
  WriteFile(path, protocol.dump(2));
  return path;
}

// 12 answers: keys and labels mixed, in any case
const std::vector<std::string> kAnswers = {"a",    "b", "B", "soft", "a", "click",
                                           "buzz", "1", "2", "2",    "1", "CLICK"};

std::string LogLines(std::size_t from, std::size_t to) {
  std::string s;
  for (std::size_t i = from; i < to && i < kAnswers.size(); ++i) s += kAnswers[i] + "\n";
  return s;
}

std::vector<json> Records(const std::string& log, const std::string& type) {
  std::vector<json> out;
  for (const json& r : ReadLog(log).records) {
    if (r["type"] == type) out.push_back(r);
  }
  return out;
}

// step, test, series, condition, answer of every answer in a log
std::vector<std::vector<int>> LoggedAnswerKeys(const std::string& log) {
  std::vector<std::vector<int>> out;
  for (const json& a : Records(log, "answer")) {
    out.push_back({a["step"].get<int>(), a["test"].get<int>(), a["series"].get<int>(),
                   a["condition"].get<int>(), a["answer"].get<int>()});
  }
  return out;
}

std::vector<std::string> RunArgs(const std::string& protocol, const std::string& log,
                                 const std::string& participant = "P01") {
  return {"study", "run", "--protocol", protocol, "--participant", participant,
          "--log", log,   "--seed",     "42",     "--presenter",   "text"};
}

TEST(StudyCliTest, ScriptedSessionRecordsEveryAnswer) {
  ScratchDir dir;
  const std::string protocol = WriteProtocol(dir);
  const std::string log = dir.File("p01.jsonl");
  const Result r = RunCli(dir, RunArgs(protocol, log), LogLines(0, 12));
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("rendering soft (penalty) for 3 taps"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("Session complete"), std::string::npos) << r.out;
  const auto answers = Records(log, "answer");
  ASSERT_EQ(answers.size(), 12u);
  for (std::size_t i = 0; i < answers.size(); ++i) {
    EXPECT_EQ(answers[i]["series"], static_cast<int>(i % 6));
    // labels and keys map to the right condition
    const std::string given = kAnswers[i];
    const std::string named = answers[i]["answer_label"];
    if (given.size() > 1) {
      std::string lower = given;
      for (char& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
      EXPECT_EQ(named, lower);
    }
  }
  EXPECT_EQ(ReadLog(log).records.back()["type"], "session_end");
  EXPECT_EQ(ReadLog(log).records.front()["seed"], 42);
}

// a person's session needs a real device: without --device (or with a preset name, as it used to
// take) nothing starts and no log is written; --device sim is a dry run, recorded as one, as is
// the text presenter
TEST(StudyCliTest, APersonsSessionNeedsADeviceAndADryRunIsLoggedAsOne) {
  ScratchDir dir;
  const std::string protocol = WriteProtocol(dir);
  const std::string log = dir.File("p01.jsonl");
  std::vector<std::string> device_run = {"study",         "run", "--protocol",  protocol,
                                         "--participant", "P01", "--log",       log,
                                         "--seed",        "42",  "--presenter", "device"};
  for (const std::vector<std::string>& extra :
       {std::vector<std::string>{}, std::vector<std::string>{"--device", "omega3"}}) {
    std::vector<std::string> args = device_run;
    args.insert(args.end(), extra.begin(), extra.end());
    const Result r = RunCli(dir, args, LogLines(0, 12));
    EXPECT_EQ(r.exit_code, 2) << r.err;
    EXPECT_NE(r.err.find("a participant's session needs a device"), std::string::npos) << r.err;
    EXPECT_FALSE(std::filesystem::exists(log));
  }
  std::vector<std::string> sim = device_run;
  sim.insert(sim.end(), {"--device", "sim", "--preset", "omega3"});
  const Result r = RunCli(dir, sim, LogLines(0, 12));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json start = ReadLog(log).records.at(0);
  EXPECT_EQ(start["dry_run"], true);
  EXPECT_NE(start["presenter"].get<std::string>().find("dry run"), std::string::npos);
  EXPECT_NE(start["presenter"].get<std::string>().find("omega3"), std::string::npos);
  EXPECT_EQ(Records(log, "answer").size(), 12u);

  const std::string text_log = dir.File("p02.jsonl");
  ASSERT_EQ(RunCli(dir, RunArgs(protocol, text_log, "P02"), LogLines(0, 12)).exit_code, 0);
  EXPECT_EQ(ReadLog(text_log).records.at(0)["dry_run"], true);
}

TEST(StudyCliTest, KilledAtRandomPointsThenResumedEqualsAnUninterruptedRun) {
  ScratchDir dir;
  const std::string protocol = WriteProtocol(dir);
  const std::string reference = dir.File("reference.jsonl");
  ASSERT_EQ(RunCli(dir, RunArgs(protocol, reference), LogLines(0, 12)).exit_code, 0);
  const auto expected = LoggedAnswerKeys(reference);
  ASSERT_EQ(expected.size(), 12u);

  const std::string log = dir.File("crashy.jsonl");
  std::vector<std::string> args = RunArgs(protocol, log);
  args.push_back("--resume");  // also starts a new session when the log does not exist yet
  Rng rng(31337);
  std::set<std::size_t> kill_points;
  bool torn_written = false;
  for (int attempt = 0; attempt < 40 && LoggedAnswerKeys(log).size() < 12; ++attempt) {
    const std::size_t recorded = std::filesystem::exists(log) ? LoggedAnswerKeys(log).size() : 0;
    if (!torn_written && recorded > 0) {
      // a crash in the middle of a write leaves a torn last line
      AppendFile(log, R"({"answer":1,"condition":0,"correct":fal)");
      torn_written = true;
    }
    const Child child = Spawn(args, dir.File("crashy.out"), dir.File("crashy.err"));
    // feed a few of the remaining answers, wait for some of them, then kill at a random moment
    const std::size_t fed = std::min<std::size_t>(12, recorded + rng.Below(4));
    Feed(child, LogLines(recorded, fed));
    const std::size_t wait_for = recorded + rng.Below(fed - recorded + 1);
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
    int status = 0;
    bool exited = false;
    // the log appears once the child has started; then its answers are counted
    while ((!std::filesystem::exists(log) || LoggedAnswerKeys(log).size() < wait_for) &&
           std::chrono::steady_clock::now() < deadline) {
      if (waitpid(child.pid, &status, WNOHANG) == child.pid) {
        exited = true;
        break;
      }
      std::this_thread::sleep_for(std::chrono::microseconds(300));
    }
    if (!exited) {
      std::this_thread::sleep_for(std::chrono::microseconds(rng.Below(3000)));
      kill(child.pid, SIGKILL);
      waitpid(child.pid, &status, 0);
    }
    close(child.stdin_fd);
    ASSERT_TRUE(WIFSIGNALED(status) || (WIFEXITED(status) && WEXITSTATUS(status) == 0))
        << ReadFile(dir.File("crashy.err"));
    if (std::filesystem::exists(log)) kill_points.insert(LoggedAnswerKeys(log).size());
  }
  // finish: the remaining answers, then end of input
  const std::size_t recorded = LoggedAnswerKeys(log).size();
  const Result last = RunCli(dir, args, LogLines(recorded, 12));
  EXPECT_EQ(last.exit_code, 0) << last.err;

  EXPECT_EQ(LoggedAnswerKeys(log), expected) << "answers lost, duplicated or reordered";
  const LogContents contents = ReadLog(log);
  EXPECT_EQ(contents.torn_tail_bytes, 0u);
  EXPECT_EQ(contents.records.back()["type"], "session_end");
  // the torn line was removed on resume (ReadLog would refuse a log with a broken middle line);
  // the resume record notes the dropped bytes unless the kill fell between the two
  EXPECT_TRUE(torn_written);
  std::cout << "[ info ] kills landed after " << kill_points.size() << " different answer counts:";
  for (std::size_t k : kill_points) std::cout << " " << k;
  std::cout << "\n";
  EXPECT_GE(kill_points.size(), 3u);
}

TEST(StudyCliTest, EndOfInputStopsCleanlyAndResumeFinishes) {
  ScratchDir dir;
  const std::string protocol = WriteProtocol(dir);
  const std::string log = dir.File("p01.jsonl");
  const Result first = RunCli(dir, RunArgs(protocol, log), LogLines(0, 5));
  EXPECT_EQ(first.exit_code, 0) << first.err;
  EXPECT_NE(first.out.find("Session stopped after 5 of 12 answers"), std::string::npos)
      << first.out;
  EXPECT_EQ(Records(log, "stop").size(), 1u);
  EXPECT_EQ(Records(log, "stop")[0]["reason"], "end of input");

  std::vector<std::string> resume = RunArgs(protocol, log);
  resume.push_back("--resume");
  resume.push_back("--json");
  const Result second = RunCli(dir, resume, LogLines(5, 12));
  EXPECT_EQ(second.exit_code, 0) << second.err;
  const json summary = json::parse(second.out);  // --json: exactly one object on stdout
  EXPECT_EQ(summary["status"], "complete");
  EXPECT_EQ(summary["answers_before"], 5);
  EXPECT_EQ(summary["answers_recorded"], 7);
  EXPECT_EQ(Records(log, "answer").size(), 12u);

  const Result third = RunCli(dir, resume, "");
  EXPECT_EQ(json::parse(third.out)["status"], "already_complete");
}

TEST(StudyCliTest, TypoAsksAgain) {
  ScratchDir dir;
  const std::string protocol = WriteProtocol(dir);
  const std::string log = dir.File("p01.jsonl");
  const Result r = RunCli(dir, RunArgs(protocol, log), "zz\n\nwall 9\n" + LogLines(0, 12));
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("\"zz\" is not an answer: type a or b"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("\"wall 9\" is not an answer"), std::string::npos) << r.out;
  EXPECT_EQ(Records(log, "answer").size(), 12u);
  EXPECT_EQ(Records(log, "answer")[0]["answer_label"], "soft");  // "a" after the typos
}

TEST(StudyCliTest, MalformedProtocolNamesTheField) {
  ScratchDir dir;
  const std::string bad = dir.File("bad.json");
  WriteFile(bad, R"({"name": "bad", "conditions": {"w": {"renderer": "train", "frequency_hz": 5}},
                    "tests": [{"name": "t", "conditions": ["w", "w"]}]})");
  Result r = RunCli(dir, RunArgs(bad, dir.File("l.jsonl")));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("bad.json: conditions[\"w\"].frequency_hz: 5 Hz is out of range"),
            std::string::npos)
      << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir.File("l.jsonl")));

  WriteFile(bad, R"({"name": "bad", "conditions": {"w": {"renderer": "spring"}}, "tests": []})");
  r = RunCli(dir, RunArgs(bad, dir.File("l.jsonl")));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("unknown renderer \"spring\"; valid renderers: penalty, impulse, train"),
            std::string::npos)
      << r.err;

  WriteFile(bad, R"({"name": "bad", "conditions": {"w": {"renderer": "impulse", "e": 0}}})");
  r = RunCli(dir, RunArgs(bad, dir.File("l.jsonl")));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("unknown parameter \"e\"; valid parameters for renderer impulse:"),
            std::string::npos)
      << r.err;

  WriteFile(bad, R"({"name": "bad", )");
  r = RunCli(dir, RunArgs(bad, dir.File("l.jsonl")));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("bad.json: not valid JSON"), std::string::npos) << r.err;
}

TEST(StudyCliTest, RefusedLogsAreLeftByteIdentical) {
  ScratchDir dir;
  const std::string protocol = WriteProtocol(dir);
  const std::string log = dir.File("p01.jsonl");
  ASSERT_EQ(RunCli(dir, RunArgs(protocol, log), LogLines(0, 3)).exit_code, 0);
  const std::string bytes = ReadFile(log);

  std::vector<std::string> other = RunArgs(protocol, log, "P02");
  other.push_back("--resume");
  Result r = RunCli(dir, other, LogLines(3, 12));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("belongs to participant \"P01\", not \"P02\""), std::string::npos) << r.err;
  EXPECT_EQ(ReadFile(log), bytes);

  std::vector<std::string> changed = RunArgs(WriteProtocol(dir, "changed"), log);
  changed.push_back("--resume");
  r = RunCli(dir, changed, LogLines(3, 12));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("written for protocol \"e2e\""), std::string::npos) << r.err;
  EXPECT_EQ(ReadFile(log), bytes);

  r = RunCli(dir, RunArgs(protocol, log), LogLines(3, 12));  // no --resume
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("pass --resume"), std::string::npos) << r.err;
  EXPECT_EQ(ReadFile(log), bytes);

  const std::string notes = dir.File("notes.txt");
  const std::string text = "not json lines\n{\"torn";
  WriteFile(notes, text);
  std::vector<std::string> on_notes = RunArgs(protocol, notes);
  on_notes.push_back("--resume");
  r = RunCli(dir, on_notes, LogLines(0, 12));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("line 1 is not JSON"), std::string::npos) << r.err;
  EXPECT_EQ(ReadFile(notes), text);
}

TEST(StudyCliTest, AnalyzeWallsSessions) {
  ScratchDir dir;
  // two people on the shipped protocol, answering with the walls' names
  std::vector<std::string> logs;
  for (const char* id : {"P01", "P02"}) {
    const std::string log = dir.File(std::string(id) + ".jsonl");
    std::string answers;
    for (int i = 0; i < 20; ++i) answers += i % 2 == 0 ? "wall 0\n" : "1\n";
    for (int i = 0; i < 20; ++i) answers += i % 3 == 0 ? "wall 2\n" : "wall 1\n";
    std::vector<std::string> args = RunArgs(kWalls, log, id);
    const Result r = RunCli(dir, args, answers);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    logs.push_back(log);
  }
  std::vector<std::string> args = {"study", "analyze", logs[0], logs[1], "--json"};
  const Result r = RunCli(dir, args);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json report = json::parse(r.out);
  ASSERT_EQ(report["tests"].size(), 2u);
  EXPECT_EQ(report["tests"][0]["name"], "test 1");
  EXPECT_EQ(report["tests"][1]["name"], "test 2");
  for (const json& t : report["tests"]) {
    EXPECT_TRUE(t["mean_percent_correct"].is_number());
    EXPECT_TRUE(t["sd"].is_number());
    ASSERT_EQ(t["participants"].size(), 2u);
    EXPECT_EQ(t["participants"][0]["id"], "P01");
    EXPECT_TRUE(t["participants"][0]["percent_correct"].is_number());
  }
  const Result text = RunCli(dir, {"study", "analyze", logs[0]});
  EXPECT_EQ(text.exit_code, 0);
  EXPECT_NE(text.out.find("test 2: wall 1 vs wall 2"), std::string::npos) << text.out;

  const std::string junk = dir.File("junk.jsonl");
  WriteFile(junk, "hello\n");
  const Result refused = RunCli(dir, {"study", "analyze", junk});
  EXPECT_EQ(refused.exit_code, 2);
  EXPECT_EQ(ReadFile(junk), "hello\n");
}

// the shipped materials study at the terminal: three walls per test, answered by key and by
// label; the analysis is against a third, with the confusion matrix
TEST(StudyCliTest, MaterialsStudyIdentifiesAmongThree) {
  ScratchDir dir;
  const std::string protocol = std::string(RIGIDTOUCH_SOURCE_DIR) + "/studies/materials.json";
  const std::string log = dir.File("P01.jsonl");
  std::string answers;
  for (int i = 0; i < 30; ++i) answers += i % 3 == 0 ? "r\n" : (i % 3 == 1 ? "W\n" : "a\n");
  for (int i = 0; i < 30; ++i) answers += i % 2 == 0 ? "train:wood\n" : "a\n";
  const Result r = RunCli(dir, RunArgs(protocol, log, "P01"), answers);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("Type r for event:rubber, w for event:wood or a for event:aluminium: "),
            std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("rendering event:wood (event) for 3 taps"), std::string::npos) << r.out;
  const auto recorded = Records(log, "answer");
  ASSERT_EQ(recorded.size(), 60u);
  EXPECT_EQ(recorded[1]["answer"], 1);
  EXPECT_EQ(recorded[2]["answer_label"], "event:aluminium");
  EXPECT_EQ(recorded[30]["answer_label"], "train:wood");
  const Result text = RunCli(dir, {"study", "analyze", log});
  ASSERT_EQ(text.exit_code, 0) << text.err;
  EXPECT_NE(text.out.find("event: event:rubber vs event:wood vs event:aluminium (chance 33.3%)"),
            std::string::npos)
      << text.out;
  EXPECT_NE(text.out.find("pooled answers (row: presented, column: named)"), std::string::npos)
      << text.out;
  const Result j = RunCli(dir, {"study", "analyze", log, "--json"});
  ASSERT_EQ(j.exit_code, 0) << j.err;
  const json report = json::parse(j.out);
  for (const json& t : report["tests"]) {
    EXPECT_EQ(t["chance"], 1.0 / 3.0);
    int total = 0;
    for (const json& row : t["confusion"]) {
      for (const json& n : row) total += n.get<int>();
    }
    EXPECT_EQ(total, 30);
  }
  // the second test was answered wood or aluminium only: no "rubber" column entries
  for (const json& row : report["tests"][1]["confusion"]) EXPECT_EQ(row[0], 0);
}

TEST(StudyCliTest, PredictPrintsTheCohortSharesWithIntervals) {
  ScratchDir dir;
  Result r = RunCli(dir, {"study", "predict", "--protocol", kWalls, "--taps", "5", "--cohorts",
                          "100", "--participants", "9", "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json j = json::parse(r.out);
  EXPECT_EQ(j["participants"], 9);
  EXPECT_EQ(j["cohorts"], 100);
  ASSERT_EQ(j["tests"].size(), 2u);
  for (const json& t : j["tests"]) {
    for (const char* key : {"share_at_least_90", "share_at_most_50"}) {
      const double expected = t[key]["expected"].get<double>();
      const double low = t[key]["interval_90"][0].get<double>();
      const double high = t[key]["interval_90"][1].get<double>();
      EXPECT_LE(0.0, low) << key;
      EXPECT_LE(low, expected) << key;
      EXPECT_LE(expected, high) << key;
      EXPECT_LE(high, 1.0) << key;
      // a share of a cohort of 9 is a multiple of 1/9
      EXPECT_NEAR(high * 9.0, std::round(high * 9.0), 1e-9) << key;
    }
    EXPECT_GT(t["predicted_percent_correct"].get<double>(), 50.0);
  }
  EXPECT_TRUE(j["tests"][0]["cohorts_below_previous_test"].is_null());
  EXPECT_TRUE(j["tests"][1]["cohorts_below_previous_test"].is_number());

  r = RunCli(dir, {"study", "predict", "--protocol", kWalls, "--taps", "5", "--cohorts", "20"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("participants at >= 90%: "), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("at <= 50%: "), std::string::npos) << r.out;

  r = RunCli(dir, {"study", "predict", "--protocol", kWalls, "--participants", "0"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--participants"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace rigidtouch::study
