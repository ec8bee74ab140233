#include "study/session.h"

#include <gtest/gtest.h>

#include <sstream>
#include <string>
#include <vector>

#include "rigidtouch/types.h"
#include "study/analysis.h"
#include "study/test_files.h"

namespace rigidtouch::study {
namespace {

using nlohmann::json;
using testing::AppendFile;
using testing::ReadFile;
using testing::ScratchDir;
using testing::WriteFile;

Protocol SmallProtocol(const char* name = "small") {
  json d = json::parse(R"({
    "familiarization_taps": 2,
    "series": 6,
    "taps_per_series": 3,
    "instructions": "tap gently",
    "conditions": {
      "soft": {"renderer": "penalty", "stiffness_N_per_m": 500},
      "hard": {"renderer": "impulse"},
      "buzz": {"renderer": "train", "frequency_hz": 250}
    },
    "tests": [{"name": "first", "conditions": ["soft", "hard"], "keys": ["s", "h"]},
              {"name": "second", "conditions": ["hard", "buzz"]}]
  })");
  d["name"] = name;
  return ParseProtocol(d, "small.json");
}

class RecordingPresenter : public WallPresenter {
 public:
  void Present(const Condition& condition, int taps) override {
    shown.push_back(condition.label + "x" + std::to_string(taps));
  }
  std::string Describe() const override { return "recording presenter"; }
  bool dry_run() const override { return true; }
  std::vector<std::string> shown;
};

// answers series in order from a script; stops when the script ends
class ScriptedResponder : public Responder {
 public:
  explicit ScriptedResponder(std::vector<int> script) : script_(std::move(script)) {}
  void Show(std::string_view text) override { shown += std::string(text) + "\n"; }
  std::optional<int> Ask(const Protocol& /*protocol*/, const Step& /*step*/) override {
    if (next_ >= script_.size()) return std::nullopt;
    return script_[next_++];
  }
  std::string StopReason() const override { return "script ended"; }
  std::string shown;

 private:
  std::vector<int> script_;
  std::size_t next_ = 0;
};

SessionConfig Config(const char* participant = "P01", std::optional<std::uint64_t> seed = 99) {
  SessionConfig c;
  c.participant = participant;
  c.seed = seed;
  c.software_version = "test";
  return c;
}

std::vector<json> OfType(const std::vector<json>& records, const std::string& type) {
  std::vector<json> out;
  for (const json& r : records) {
    if (r.value("type", "") == type) out.push_back(r);
  }
  return out;
}

// the deterministic content of the answers: step, test, series, condition, answer
std::vector<std::vector<int>> AnswerKeysOf(const std::vector<json>& records) {
  std::vector<std::vector<int>> out;
  for (const json& a : OfType(records, "answer")) {
    out.push_back({a["step"].get<int>(), a["test"].get<int>(), a["series"].get<int>(),
                   a["condition"].get<int>(), a["answer"].get<int>()});
  }
  return out;
}

// a fixed answer script: 12 series in all
const std::vector<int> kScript = {0, 1, 1, 0, 1, 1, 0, 0, 1, 0, 1, 1};

TEST(SessionTest, NewSessionRecordsEveryEventInPlanOrder) {
  const Protocol p = SmallProtocol();
  MemorySink sink;
  RecordingPresenter presenter;
  ScriptedResponder responder(kScript);
  const SessionOutcome outcome = RunSession(p, Config(), {}, "mem", sink, presenter, responder);
  EXPECT_EQ(outcome.status, SessionStatus::kComplete);
  EXPECT_EQ(outcome.seed, 99u);
  EXPECT_EQ(outcome.answers_recorded, 12);
  EXPECT_EQ(outcome.answers_total, 12);

  const std::vector<Step> plan = MakePlan(p, 99);
  ASSERT_EQ(presenter.shown.size(), plan.size());
  for (const Step& s : plan) {
    const Condition& c = p.conditions[p.tests[s.test].conditions[s.condition]];
    EXPECT_EQ(presenter.shown[s.index], c.label + "x" + std::to_string(s.taps));
  }
  const auto& r = sink.records;
  ASSERT_FALSE(r.empty());
  EXPECT_EQ(r.front()["type"], "session_start");
  EXPECT_EQ(r.front()["protocol_hash"], ProtocolHash(p));
  EXPECT_EQ(r.front()["protocol"], p.ToJson());
  EXPECT_EQ(r.front()["seed"], 99);
  EXPECT_EQ(r.front()["participant"], "P01");
  EXPECT_EQ(r.front()["software_version"], "test");
  EXPECT_EQ(r.back()["type"], "session_end");
  EXPECT_EQ(OfType(r, "familiarization").size(), 4u);
  EXPECT_EQ(OfType(r, "series").size(), 12u);
  const auto answers = OfType(r, "answer");
  ASSERT_EQ(answers.size(), 12u);
  for (std::size_t i = 0; i < answers.size(); ++i) {
    const json& a = answers[i];
    EXPECT_EQ(a["answer"], kScript[i]);
    EXPECT_EQ(a["correct"], a["answer"] == a["condition"]);
    EXPECT_TRUE(a.contains("time_utc"));
    EXPECT_TRUE(a.contains("response_time_s"));
    const Step& s = plan[a["step"].get<int>()];
    EXPECT_EQ(s.kind, StepKind::kSeries);
    EXPECT_EQ(a["condition"], s.condition);
    EXPECT_EQ(a["series"], s.series);
  }
  // the series record states what was rendered, e.g. the penalty stiffness
  const auto series = OfType(r, "series");
  for (const json& s : series) {
    const Step& step = plan[s["step"].get<int>()];
    EXPECT_EQ(s["rendered"], p.conditions[p.tests[step.test].conditions[step.condition]].ToJson());
  }
  EXPECT_NE(responder.shown.find("tap gently"), std::string::npos);
  EXPECT_NE(responder.shown.find("Familiarization: tap soft (key s) 2 times."), std::string::npos);
}

TEST(SessionTest, StopThenResumeGivesTheUninterruptedAnswers) {
  const Protocol p = SmallProtocol();
  MemorySink reference;
  {
    RecordingPresenter presenter;
    ScriptedResponder responder(kScript);
    RunSession(p, Config(), {}, "mem", reference, presenter, responder);
  }
  for (std::size_t stop_after : {0u, 1u, 5u, 6u, 7u, 11u}) {
    MemorySink sink;
    RecordingPresenter presenter;
    ScriptedResponder first(std::vector<int>(kScript.begin(), kScript.begin() + stop_after));
    const SessionOutcome a = RunSession(p, Config(), {}, "mem", sink, presenter, first);
    EXPECT_EQ(a.status, SessionStatus::kStopped);
    EXPECT_EQ(OfType(sink.records, "stop").back()["reason"], "script ended");

    const std::vector<json> existing = sink.records;
    SessionConfig resume = Config("P01", std::nullopt);  // the seed comes from the log
    resume.resume = true;
    ScriptedResponder rest(std::vector<int>(kScript.begin() + stop_after, kScript.end()));
    const SessionOutcome b = RunSession(p, resume, existing, "mem", sink, presenter, rest);
    EXPECT_EQ(b.status, SessionStatus::kComplete);
    EXPECT_TRUE(b.resumed);
    EXPECT_EQ(b.answers_before, static_cast<int>(stop_after));
    EXPECT_EQ(b.answers_recorded, static_cast<int>(12 - stop_after));
    EXPECT_EQ(AnswerKeysOf(sink.records), AnswerKeysOf(reference.records)) << stop_after;
    // the series that was shown but not answered is shown again, marked as a repeat
    const auto series = OfType(sink.records, "series");
    EXPECT_EQ(series.size(), 13u);
    int repeats = 0;
    for (const json& s : series) repeats += s.value("repeated", false) ? 1 : 0;
    EXPECT_EQ(repeats, 1);
  }
}

TEST(SessionTest, ResumingACompleteSessionDoesNothing) {
  const Protocol p = SmallProtocol();
  MemorySink sink;
  RecordingPresenter presenter;
  ScriptedResponder responder(kScript);
  RunSession(p, Config(), {}, "mem", sink, presenter, responder);
  const std::vector<json> existing = sink.records;
  SessionConfig resume = Config();
  resume.resume = true;
  RecordingPresenter again;
  const SessionOutcome o = RunSession(p, resume, existing, "mem", sink, again, responder);
  EXPECT_EQ(o.status, SessionStatus::kAlreadyComplete);
  EXPECT_EQ(sink.records.size(), existing.size());
  EXPECT_TRUE(again.shown.empty());
}

std::string RefusalOf(const Protocol& p, const SessionConfig& config,
                      const std::vector<json>& existing) {
  MemorySink sink;
  RecordingPresenter presenter;
  ScriptedResponder responder(kScript);
  try {
    RunSession(p, config, existing, "log.jsonl", sink, presenter, responder);
  } catch (const Error& e) {
    EXPECT_TRUE(sink.records.empty()) << "a refused log must not be appended to";
    return e.what();
  }
  return "";
}

TEST(SessionTest, RefusesLogsOfAnotherSession) {
  const Protocol p = SmallProtocol();
  MemorySink sink;
  RecordingPresenter presenter;
  ScriptedResponder responder({0, 1, 1});
  RunSession(p, Config(), {}, "mem", sink, presenter, responder);
  const std::vector<json> log = sink.records;

  SessionConfig resume = Config();
  resume.resume = true;
  EXPECT_EQ(RefusalOf(p, resume, log), "") << "the right session resumes";

  const std::string other_protocol = RefusalOf(SmallProtocol("other"), resume, log);
  EXPECT_NE(other_protocol.find("written for protocol \"small\""), std::string::npos)
      << other_protocol;
  EXPECT_NE(other_protocol.find("not for \"other\""), std::string::npos) << other_protocol;

  SessionConfig other_participant = resume;
  other_participant.participant = "P02";
  const std::string e2 = RefusalOf(p, other_participant, log);
  EXPECT_NE(e2.find("belongs to participant \"P01\", not \"P02\""), std::string::npos) << e2;

  SessionConfig other_seed = resume;
  other_seed.seed = 100;
  EXPECT_NE(RefusalOf(p, other_seed, log).find("seed is 99, not 100"), std::string::npos);

  SessionConfig simulated = resume;
  simulated.mode = "simulated";
  EXPECT_NE(RefusalOf(p, simulated, log).find("person session"), std::string::npos);

  EXPECT_NE(RefusalOf(p, Config(), log).find("pass --resume"), std::string::npos);
}

TEST(SessionTest, RefusesLogsThatContradictThePlan) {
  const Protocol p = SmallProtocol();
  MemorySink sink;
  RecordingPresenter presenter;
  ScriptedResponder responder({0, 1, 1});
  RunSession(p, Config(), {}, "mem", sink, presenter, responder);
  SessionConfig resume = Config();
  resume.resume = true;

  std::vector<json> flipped = sink.records;
  for (json& r : flipped) {
    if (r["type"] == "answer") {
      r["condition"] = 1 - r["condition"].get<int>();
      break;
    }
  }
  EXPECT_NE(RefusalOf(p, resume, flipped).find("does not match step"), std::string::npos);

  std::vector<json> doubled = sink.records;
  doubled.push_back(OfType(sink.records, "answer").front());
  EXPECT_NE(RefusalOf(p, resume, doubled).find("two answers for step"), std::string::npos);

  std::vector<json> wrong_type = sink.records;
  wrong_type[0]["participant"] = 7;
  EXPECT_NE(RefusalOf(p, resume, wrong_type).find("malformed record"), std::string::npos);

  std::vector<json> gap = sink.records;
  std::erase_if(gap,
                [](const json& r) { return r["type"] == "familiarization" && r["step"] == 0; });
  EXPECT_NE(RefusalOf(p, resume, gap).find("out of order"), std::string::npos);
}

TEST(SessionTest, LoggedSessionDropsATornTailAndRecordsIt) {
  ScratchDir dir;
  const std::string path = dir.File("p01.jsonl");
  const Protocol p = SmallProtocol();
  {
    RecordingPresenter presenter;
    ScriptedResponder responder({0, 1, 1, 0});
    RunLoggedSession(p, Config(), path, presenter, responder);
  }
  const std::string clean = ReadFile(path);
  const std::string torn = R"({"answer":1,"condition":0,"cor)";
  AppendFile(path, torn);
  SessionConfig resume = Config();
  resume.resume = true;
  RecordingPresenter presenter;
  ScriptedResponder responder(std::vector<int>(kScript.begin() + 4, kScript.end()));
  const SessionOutcome o = RunLoggedSession(p, resume, path, presenter, responder);
  EXPECT_EQ(o.status, SessionStatus::kComplete);
  EXPECT_EQ(o.torn_tail_bytes, torn.size());
  const std::string after = ReadFile(path);
  EXPECT_EQ(after.substr(0, clean.size()), clean);  // nothing before the tear changed
  const LogContents c = ReadLog(path);
  EXPECT_EQ(c.torn_tail_bytes, 0u);
  EXPECT_EQ(OfType(c.records, "resume").front()["torn_tail_bytes_dropped"], torn.size());
  EXPECT_EQ(OfType(c.records, "answer").size(), 12u);
}

TEST(SessionTest, LoggedSessionLeavesRefusedLogsByteIdentical) {
  ScratchDir dir;
  const Protocol p = SmallProtocol();
  const std::string log = dir.File("p01.jsonl");
  {
    RecordingPresenter presenter;
    ScriptedResponder responder({0, 1});
    RunLoggedSession(p, Config(), log, presenter, responder);
  }
  AppendFile(log, R"({"type":"ans)");  // a torn tail must survive a refusal too
  const std::string bytes = ReadFile(log);
  SessionConfig other = Config("P02");
  other.resume = true;
  RecordingPresenter presenter;
  ScriptedResponder responder(kScript);
  EXPECT_THROW(RunLoggedSession(p, other, log, presenter, responder), Error);
  EXPECT_EQ(ReadFile(log), bytes);
  SessionConfig same = Config();
  same.resume = true;
  EXPECT_THROW(RunLoggedSession(SmallProtocol("other"), same, log, presenter, responder), Error);
  EXPECT_EQ(ReadFile(log), bytes);

  const std::string csv = dir.File("data.csv");
  WriteFile(csv, "time_s,force_N\n0,1\n0.001,2");
  EXPECT_THROW(RunLoggedSession(p, same, csv, presenter, responder), Error);
  EXPECT_EQ(ReadFile(csv), "time_s,force_N\n0,1\n0.001,2");
  EXPECT_TRUE(presenter.shown.empty());
}

TEST(SessionTest, ParticipantIdsAreChecked) {
  EXPECT_NO_THROW(CheckParticipantId("P-01_a.b"));
  EXPECT_THROW(CheckParticipantId(""), Error);
  EXPECT_THROW(CheckParticipantId("P 01"), Error);
  EXPECT_THROW(CheckParticipantId("../x"), Error);
  EXPECT_THROW(CheckParticipantId(std::string(65, 'a')), Error);
}

TEST(AnswerTest, KeysAndLabelsWithoutCaseOrSpaces) {
  const Protocol p = SmallProtocol();
  const StudyTest& first = p.tests[0];  // soft (key s) vs hard (key h)
  EXPECT_EQ(ParseAnswer(p, first, "s"), 0);
  EXPECT_EQ(ParseAnswer(p, first, " H \r"), 1);
  EXPECT_EQ(ParseAnswer(p, first, "Soft"), 0);
  EXPECT_EQ(ParseAnswer(p, first, "hard"), 1);
  EXPECT_EQ(ParseAnswer(p, first, "x"), std::nullopt);
  EXPECT_EQ(ParseAnswer(p, first, ""), std::nullopt);
  EXPECT_EQ(ParseAnswer(p, first, "1"), std::nullopt);
}

TEST(AnswerTest, TerminalAsksAgainAfterATypoAndStopsAtEndOfInput) {
  const Protocol p = SmallProtocol();
  Step step;
  step.kind = StepKind::kSeries;
  step.test = 1;  // hard (key 1) vs buzz (key 2)
  std::istringstream in("x\n\n  2 \nhard\n");
  std::ostringstream out;
  TerminalResponder terminal(in, out);
  EXPECT_EQ(terminal.Ask(p, step), 1);
  EXPECT_NE(out.str().find("\"x\" is not an answer"), std::string::npos) << out.str();
  EXPECT_EQ(terminal.Ask(p, step), 0);
  EXPECT_EQ(terminal.Ask(p, step), std::nullopt);
  EXPECT_EQ(terminal.StopReason(), "end of input");

  std::istringstream quit("QUIT\n1\n");
  TerminalResponder quitter(quit, out);
  EXPECT_EQ(quitter.Ask(p, step), std::nullopt);
  EXPECT_EQ(quitter.StopReason(), "quit");
}

// `study run --resume` and `study analyze` make the one check (ValidateLog): a log one accepts
// the other accepts, and a damaged log is refused by both with the same message
// a test of three conditions after one of two: 2 + 6 then 3 + 6 steps
Protocol ThreeWaySessionProtocol() {
  json d = json::parse(R"({
    "name": "three",
    "familiarization_taps": 2,
    "series": 6,
    "conditions": {
      "soft": {"renderer": "penalty", "stiffness_N_per_m": 500},
      "wood": {"renderer": "event", "material": "wood"},
      "tin": {"renderer": "train", "material": "aluminium", "passivity_control": true}
    },
    "tests": [{"name": "pair", "conditions": ["soft", "tin"]},
              {"name": "three", "conditions": ["soft", "wood", "tin"], "keys": ["s", "w", "t"]}]
  })");
  return ParseProtocol(d, "three.json");
}

TEST(SessionTest, ThreeConditionTestIsLoggedAndResumes) {
  const Protocol p = ThreeWaySessionProtocol();
  // answers of the second test use all three conditions
  const std::vector<int> script = {0, 1, 1, 0, 1, 0, 2, 0, 1, 2, 2, 1};
  MemorySink reference;
  RecordingPresenter reference_presenter;
  {
    ScriptedResponder responder(script);
    RunSession(p, Config(), {}, "mem", reference, reference_presenter, responder);
  }
  // each of the three is familiarized, with its key, and rendered as written
  EXPECT_EQ(OfType(reference.records, "familiarization").size(), 5u);
  for (const json& f : OfType(reference.records, "familiarization")) {
    if (f["test"] != 1) continue;
    const std::vector<std::string> keys = {"s", "w", "t"};
    EXPECT_EQ(f["key"], keys[f["condition"].get<int>()]);
  }
  const auto answers = OfType(reference.records, "answer");
  ASSERT_EQ(answers.size(), 12u);
  EXPECT_EQ(answers[8]["answer"], 1);
  EXPECT_EQ(answers[9]["answer"], 2);
  EXPECT_EQ(answers[9]["answer_label"], "tin");
  EXPECT_EQ(ValidateLog(reference.records, "mem").answers.size(), 12u);
  for (const json& s : OfType(reference.records, "series")) {
    if (s["test"] == 1 && s["label"] == "tin") {
      EXPECT_EQ(s["rendered"], json::parse(R"({"renderer": "train", "restitution": 0.0,
                                  "material": "aluminium", "passivity_control": true})"));
    }
  }
  for (std::size_t stop_after : {7u, 9u}) {  // inside the three-condition test
    MemorySink sink;
    RecordingPresenter presenter;
    ScriptedResponder first(std::vector<int>(script.begin(), script.begin() + stop_after));
    EXPECT_EQ(RunSession(p, Config(), {}, "mem", sink, presenter, first).status,
              SessionStatus::kStopped);
    SessionConfig resume = Config("P01", std::nullopt);
    resume.resume = true;
    ScriptedResponder rest(std::vector<int>(script.begin() + stop_after, script.end()));
    const std::vector<json> existing = sink.records;
    const SessionOutcome b = RunSession(p, resume, existing, "mem", sink, presenter, rest);
    EXPECT_EQ(b.status, SessionStatus::kComplete);
    EXPECT_EQ(b.answers_before, static_cast<int>(stop_after));
    EXPECT_EQ(AnswerKeysOf(sink.records), AnswerKeysOf(reference.records)) << stop_after;
  }
  // answer 2 is valid in the three-condition test only; 3 in neither
  std::vector<json> damaged = reference.records;
  std::size_t last = damaged.size();
  while (damaged[--last]["type"] != "answer") {
  }
  damaged[last]["answer"] = 3;
  EXPECT_THROW(ValidateLog(damaged, "mem"), Error);
  damaged = reference.records;
  std::size_t first = 0;
  while (damaged[first]["type"] != "answer") ++first;
  damaged[first]["answer"] = 2;
  try {
    ValidateLog(damaged, "mem");
    ADD_FAILURE() << "answer 2 in a two-condition test was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("valid answers: 0, 1"), std::string::npos) << e.what();
  }
}

TEST(AnswerTest, ThreeKeysAndLabels) {
  const Protocol p = ThreeWaySessionProtocol();
  const StudyTest& t = p.tests[1];
  EXPECT_EQ(ParseAnswer(p, t, "w"), 1);
  EXPECT_EQ(ParseAnswer(p, t, " TIN "), 2);
  EXPECT_EQ(ParseAnswer(p, t, "s"), 0);
  EXPECT_EQ(ParseAnswer(p, t, "x"), std::nullopt);
  std::istringstream in("x\nt\n");
  std::ostringstream out;
  TerminalResponder terminal(in, out);
  Step step;
  step.test = 1;
  EXPECT_EQ(terminal.Ask(p, step), 2);
  EXPECT_NE(out.str().find("Type s for soft, w for wood or t for tin: "), std::string::npos)
      << out.str();
  EXPECT_NE(out.str().find("type s, w or t (or the wall's name)"), std::string::npos) << out.str();
}

TEST(SessionTest, ResumeAndAnalyzeAgreeOnWhichLogsAreValid) {
  const Protocol p = SmallProtocol();
  MemorySink sink;
  RecordingPresenter presenter;
  ScriptedResponder responder({0, 1, 1, 0});
  RunSession(p, Config(), {}, "mem", sink, presenter, responder);
  SessionConfig resume = Config();
  resume.resume = true;
  const auto resume_error = [&](const std::vector<json>& records) -> std::string {
    try {
      InspectSession(p, resume, records, "log.jsonl");
    } catch (const Error& e) {
      return e.what();
    }
    return "";
  };
  const auto analyze_error = [&](const std::vector<json>& records) -> std::string {
    try {
      AnalyzeLogs({{"log.jsonl", records}});
    } catch (const Error& e) {
      return e.what();
    }
    return "";
  };
  const std::vector<json> good = sink.records;
  EXPECT_EQ(resume_error(good), "");
  EXPECT_EQ(analyze_error(good), "");

  std::size_t first_answer = 0;
  while (good[first_answer]["type"] != "answer") ++first_answer;
  std::vector<std::vector<json>> damaged;
  damaged.push_back(good);
  damaged.back()[first_answer]["answer"] = 7;  // answers are 0 or 1
  damaged.push_back(good);
  damaged.back()[first_answer]["condition"] = 1 - good[first_answer]["condition"].get<int>();
  damaged.push_back(good);
  damaged.back().push_back(good[first_answer]);  // a second answer for one step
  damaged.push_back(good);
  damaged.back()[0]["protocol"]["name"] =
      "edited";  // the embedded protocol no longer matches its hash
  damaged.push_back(good);
  damaged.back()[0].erase("seed");
  damaged.push_back(good);
  damaged.back()[0]["participant"] = "../P01";
  damaged.push_back(good);
  damaged.back()[first_answer]["step"] = "one";
  damaged.push_back(good);
  damaged.back().erase(damaged.back().begin() + static_cast<long>(first_answer));  // out of order
  damaged.push_back(good);
  damaged.back().push_back(good[0]);  // a second session
  for (std::size_t i = 0; i < damaged.size(); ++i) {
    const std::string by_resume = resume_error(damaged[i]);
    EXPECT_NE(by_resume, "") << "damage " << i;
    EXPECT_EQ(by_resume, analyze_error(damaged[i])) << "damage " << i;
  }
}

}  // namespace
}  // namespace rigidtouch::study
