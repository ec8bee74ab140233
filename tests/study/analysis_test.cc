#include "study/analysis.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "rigidtouch/types.h"
#include "study/log.h"
#include "study/plan.h"
#include "study/protocol.h"

namespace rigidtouch::study {
namespace {

using nlohmann::json;

Protocol TwoTests(const char* name = "analysis") {
  json d = json::parse(R"({
    "series": 10,
    "conditions": {"a": {"renderer": "impulse"},
                   "b": {"renderer": "train", "frequency_hz": 250},
                   "c": {"renderer": "train", "frequency_hz": 50}},
    "tests": [{"name": "t1", "conditions": ["a", "b"]},
              {"name": "t2", "conditions": ["b", "c"]}]
  })");
  d["name"] = name;
  return ParseProtocol(d, "analysis.json");
}

constexpr std::uint64_t kLogSeed = 7;

// a log's session_start record, seed kLogSeed
LogInput StartLog(const Protocol& p, const std::string& id, const char* mode) {
  LogInput log;
  log.source = id + ".jsonl";
  log.records.push_back({{"type", "session_start"},
                         {"format", kLogFormat},
                         {"format_version", kLogFormatVersion},
                         {"protocol", p.ToJson()},
                         {"protocol_hash", ProtocolHash(p)},
                         {"participant", id},
                         {"mode", mode},
                         {"seed", kLogSeed}});
  return log;
}

json Familiarization(const Step& step) {
  return {{"type", "familiarization"},
          {"step", step.index},
          {"test", step.test},
          {"condition", step.condition}};
}

// a valid log (study/log.h, ValidateLog) of a session with seed 7: per test, its series in plan
// order take the given (condition, answer) pairs in turn, answered correctly when the pair is
// (the plan decides which condition each series renders); the log stops at the first series left
// without a pair
LogInput MakeLog(const Protocol& p, const std::string& id,
                 const std::vector<std::vector<std::pair<int, int>>>& per_test,
                 const char* mode = "person") {
  LogInput log = StartLog(p, id, mode);
  std::vector<std::size_t> next(p.tests.size(), 0);
  for (const Step& step : MakePlan(p, kLogSeed)) {
    if (step.kind == StepKind::kFamiliarization) {
      log.records.push_back(Familiarization(step));
      continue;
    }
    const std::size_t t = static_cast<std::size_t>(step.test);
    if (t >= per_test.size() || next[t] >= per_test[t].size()) break;
    const auto [condition, answer] = per_test[t][next[t]++];
    log.records.push_back({{"type", "answer"},
                           {"step", step.index},
                           {"test", step.test},
                           {"series", step.series},
                           {"condition", step.condition},
                           {"answer", answer == condition ? step.condition : 1 - step.condition}});
  }
  return log;
}

// n series alternating conditions 0, 1, ..., the first `correct` answered correctly
std::vector<std::pair<int, int>> Series(int n, int correct) {
  std::vector<std::pair<int, int>> out;
  for (int i = 0; i < n; ++i) {
    const int c = i % 2;
    out.emplace_back(c, i < correct ? c : 1 - c);
  }
  return out;
}

// a log of seed 7 for a protocol of one test, every series answered by `answer_of(condition)`
template <typename F>
LogInput MakeMappedLog(const Protocol& p, const std::string& id, F answer_of) {
  LogInput log = StartLog(p, id, "person");
  for (const Step& step : MakePlan(p, kLogSeed)) {
    if (step.kind == StepKind::kFamiliarization) {
      log.records.push_back(Familiarization(step));
      continue;
    }
    log.records.push_back({{"type", "answer"},
                           {"step", step.index},
                           {"test", step.test},
                           {"series", step.series},
                           {"condition", step.condition},
                           {"answer", answer_of(step.condition)}});
  }
  return log;
}

TEST(AnalysisTest, ThreeConditionsAgainstAThirdWithAConfusionMatrix) {
  const Protocol p = ParseProtocol(json::parse(R"({
    "name": "three", "series": 30,
    "conditions": {"r": {"renderer": "event", "material": "rubber"},
                   "w": {"renderer": "event", "material": "wood"},
                   "a": {"renderer": "event", "material": "aluminium"}},
    "tests": [{"name": "t", "conditions": ["r", "w", "a"]}]
  })"),
                                   "three.json");
  // rubber and aluminium named right, wood always named aluminium: 20 of 30 correct
  const auto answer = [](int c) { return c == 1 ? 2 : c; };
  const StudyReport report = AnalyzeLogs({MakeMappedLog(p, "P1", answer)});
  const TestResult& t = report.tests.at(0);
  EXPECT_EQ(t.conditions, (std::vector<std::string>{"r", "w", "a"}));
  EXPECT_DOUBLE_EQ(t.chance, 1.0 / 3.0);
  // balanced: 10 series of each; rows presented, columns named
  const std::vector<std::vector<int>> expected = {{10, 0, 0}, {0, 0, 10}, {0, 0, 10}};
  EXPECT_EQ(t.confusion, expected);
  const ParticipantResult& r = t.participants.at(0);
  EXPECT_EQ(r.correct, 20);
  EXPECT_NEAR(r.percent_correct, 100.0 * 20 / 30, 1e-12);
  // the binomial test is against 1/3, not 1/2: 20 of 30 is far above a third, not above a half
  const BinomialTest third = ExactBinomialTest(20, 30, 1.0 / 3.0);
  EXPECT_EQ(r.binomial.p_greater, third.p_greater);
  EXPECT_LT(r.binomial.p_greater, 1e-3);
  EXPECT_GT(ExactBinomialTest(20, 30, 0.5).p_greater, 0.04);
  EXPECT_EQ(t.pooled.p_greater, third.p_greater);
  EXPECT_TRUE(std::isnan(r.d_prime.d_prime));  // d' is for two conditions
  const json j = ReportToJson(report);
  EXPECT_EQ(j["tests"][0]["chance"], 1.0 / 3.0);
  EXPECT_EQ(j["tests"][0]["confusion"], json(expected));
  EXPECT_TRUE(j["tests"][0]["participants"][0]["d_prime"].is_null());
  const std::string text = ReportToText(report);
  EXPECT_NE(text.find("t: r vs w vs a (chance 33.3%)"), std::string::npos) << text;
  EXPECT_NE(text.find("pooled answers (row: presented, column: named)"), std::string::npos) << text;
  EXPECT_NE(text.find("  w               0        0       10\n"), std::string::npos) << text;
}

// a step number beyond int read as an int wraps onto a step of the plan (2^32 + k reads as k); the
// validator must refuse it, not count the answer for step k
TEST(AnalysisTest, ValidateLogRefusesAStepBeyondInt) {
  const LogInput log = MakeLog(TwoTests("p"), "p01", {{{0, 0}}});
  ASSERT_NO_THROW(ValidateLog(log.records, log.source));
  std::vector<json> records = log.records;
  json& answer = records.back();
  ASSERT_EQ(answer["type"], "answer");
  answer["step"] = answer["step"].get<std::int64_t>() + (std::int64_t{1} << 32);
  try {
    ValidateLog(records, log.source);
    ADD_FAILURE() << "a step of 2^32 + k was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("p01.jsonl: record"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("no integer \"step\""), std::string::npos) << e.what();
  }
}

TEST(AnalysisTest, PercentCorrectGroupStatisticsAndFlags) {
  const Protocol p = TwoTests();
  const std::vector<LogInput> logs = {
      MakeLog(p, "P01", {Series(10, 10), Series(10, 5)}),
      MakeLog(p, "P02", {Series(10, 9), Series(10, 1)}),
      MakeLog(p, "P03", {Series(10, 6), Series(4, 4)}),
  };
  const StudyReport r = AnalyzeLogs(logs);
  EXPECT_EQ(r.protocol_name, "analysis");
  EXPECT_EQ(r.protocol_hash, ProtocolHash(p));
  EXPECT_EQ(r.sessions, 3);
  ASSERT_EQ(r.tests.size(), 2u);

  const TestResult& t1 = r.tests[0];
  EXPECT_EQ(t1.name, "t1");
  EXPECT_EQ(t1.conditions[0], "a");
  ASSERT_EQ(t1.participants.size(), 3u);
  EXPECT_DOUBLE_EQ(t1.participants[0].percent_correct, 100.0);
  EXPECT_DOUBLE_EQ(t1.participants[1].percent_correct, 90.0);
  EXPECT_DOUBLE_EQ(t1.participants[2].percent_correct, 60.0);
  // mean of 100, 90, 60 and its sample SD (n - 1)
  EXPECT_NEAR(t1.percent_correct.mean, 250.0 / 3.0, 1e-12);
  const double mean = 250.0 / 3.0;
  EXPECT_NEAR(
      t1.percent_correct.sd,
      std::sqrt((std::pow(100.0 - mean, 2) + std::pow(90.0 - mean, 2) + std::pow(60.0 - mean, 2)) /
                2.0),
      1e-12);
  EXPECT_EQ(t1.reached_criterion, 2);  // 100% and 90% reach 90% or better
  EXPECT_EQ(t1.pooled_answers, 30);
  EXPECT_EQ(t1.pooled_correct, 25);
  // 10/10: one-sided p = 2^-10, two-sided 2^-9
  EXPECT_NEAR(t1.participants[0].binomial.p_greater, 1.0 / 1024.0, 1e-15);
  EXPECT_NEAR(t1.participants[0].binomial.p_two_sided, 2.0 / 1024.0, 1e-15);
  EXPECT_TRUE(t1.participants[0].complete);

  const TestResult& t2 = r.tests[1];
  // P02 named 1 of 10 correctly: far below chance, flagged (p_less = 11/1024)
  const ParticipantResult& p02 = t2.participants[1];
  EXPECT_EQ(p02.id, "P02");
  EXPECT_NEAR(p02.binomial.p_less, 11.0 / 1024.0, 1e-15);
  EXPECT_TRUE(p02.label_swap_suspected);
  EXPECT_LT(p02.d_prime.d_prime, 0.0);
  EXPECT_FALSE(t2.participants[0].label_swap_suspected);  // 5/10
  EXPECT_FALSE(t2.participants[2].complete);              // 4 of 10 series answered
  EXPECT_DOUBLE_EQ(t2.participants[2].percent_correct, 100.0);
}

TEST(AnalysisTest, DPrimeUsesTheLogLinearCorrection) {
  const Protocol p = TwoTests();
  // 10 series: 5 of each condition, all correct: H = 5.5/6, F = 0.5/6
  const StudyReport r = AnalyzeLogs({MakeLog(p, "P01", {Series(10, 10)})});
  const DPrime d = r.tests[0].participants[0].d_prime;
  EXPECT_NEAR(d.hit_rate, 5.5 / 6.0, 1e-15);
  EXPECT_NEAR(d.false_alarm_rate, 0.5 / 6.0, 1e-15);
  EXPECT_NEAR(d.d_prime, 2.0 * 1.3829941271006392, 1e-9);  // 2 z(11/12)
  // a test nobody answered has no participants and a NaN mean
  EXPECT_TRUE(r.tests[1].participants.empty());
  EXPECT_TRUE(std::isnan(r.tests[1].percent_correct.mean));
}

TEST(AnalysisTest, JsonHasTheAgreedFields) {
  const Protocol p = TwoTests();
  const json j = ReportToJson(AnalyzeLogs({MakeLog(p, "P01", {Series(10, 8), Series(10, 3)}),
                                           MakeLog(p, "P02", {Series(10, 7), Series(10, 6)})}));
  ASSERT_TRUE(j["tests"].is_array());
  ASSERT_EQ(j["tests"].size(), 2u);
  const json& t = j["tests"][0];
  EXPECT_EQ(t["name"], "t1");
  EXPECT_NEAR(t["mean_percent_correct"].get<double>(), 75.0, 1e-12);
  EXPECT_NEAR(t["sd"].get<double>(), std::sqrt(50.0), 1e-12);
  ASSERT_EQ(t["participants"].size(), 2u);
  EXPECT_EQ(t["participants"][0]["id"], "P01");
  EXPECT_EQ(t["participants"][0]["percent_correct"], 80.0);
  EXPECT_TRUE(t["participants"][0].contains("d_prime"));
  EXPECT_TRUE(t["participants"][0].contains("p_two_sided"));
  EXPECT_TRUE(t["pooled"].contains("p_greater"));
  EXPECT_TRUE(j["methods"].contains("d_prime"));
  // one participant gives no SD: written as null, not NaN
  const json single = ReportToJson(AnalyzeLogs({MakeLog(p, "P01", {Series(10, 8)})}));
  EXPECT_TRUE(single["tests"][0]["sd"].is_null());
  EXPECT_TRUE(json::accept(single.dump()));
  EXPECT_NE(ReportToText(AnalyzeLogs({MakeLog(p, "P01", {Series(10, 8)})})).find("t1: a vs b"),
            std::string::npos);
}

TEST(AnalysisTest, RefusesMixedProtocolsAndDuplicateParticipants) {
  const Protocol p = TwoTests();
  try {
    AnalyzeLogs({MakeLog(p, "P01", {}), MakeLog(TwoTests("other"), "P02", {})});
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("one protocol at a time"), std::string::npos);
  }
  try {
    AnalyzeLogs({MakeLog(p, "P01", {}), MakeLog(p, "P01", {})});
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("appears in two logs"), std::string::npos);
  }
  LogInput tampered = MakeLog(p, "P01", {Series(2, 2)});
  tampered.records[0]["protocol"]["tests"][0]["series"] = 11;
  EXPECT_THROW(AnalyzeLogs({tampered}), Error);
  LogInput doubled = MakeLog(p, "P01", {Series(2, 2)});
  doubled.records.push_back(doubled.records.back());  // an answer, twice
  EXPECT_THROW(AnalyzeLogs({doubled}), Error);
  LogInput wrong_type = MakeLog(p, "P01", {Series(2, 2)});
  wrong_type.records[1]["test"] = "first";
  EXPECT_THROW(AnalyzeLogs({wrong_type}), Error);
  wrong_type.records[0]["protocol_hash"] = 5;
  EXPECT_THROW(AnalyzeLogs({wrong_type}), Error);
  EXPECT_THROW(AnalyzeLogs({}), Error);
}

}  // namespace
}  // namespace rigidtouch::study
