#include "study/simulate.h"

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <iostream>
#include <set>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "rigidtouch/types.h"
#include "study/analysis.h"
#include "study/log.h"
#include "study/random.h"
#include "study/statistics.h"
#include "study/test_files.h"
#include "study/toy_stimulus.h"

namespace rigidtouch::study {
namespace {

using nlohmann::json;
using testing::ReadFile;
using testing::ScratchDir;
using testing::ToyStimulusSource;

Protocol Cohort(json first, json second, int series = 20) {
  json d = {{"name", "cohort"},
            {"series", series},
            {"conditions", {{"first", first}, {"second", second}}},
            {"tests", {{{"name", "only"}, {"conditions", {"first", "second"}}}}}};
  return ParseProtocol(d, "cohort");
}

const json kTrain250 = {{"renderer", "train"}, {"frequency_hz", 250}};
const json kTrain100 = {{"renderer", "train"}, {"frequency_hz", 100}};
const json kPenalty1000 = {{"renderer", "penalty"}, {"stiffness_N_per_m", 1000}};
const json kPenalty1300 = {{"renderer", "penalty"}, {"stiffness_N_per_m", 1300}};

// per participant: (test, series, condition, answer) of every answer
std::vector<std::vector<std::vector<int>>> Answers(const std::vector<ParticipantRun>& runs) {
  std::vector<std::vector<std::vector<int>>> out;
  for (const ParticipantRun& run : runs) {
    std::vector<std::vector<int>> answers;
    for (const json& r : run.records) {
      if (r["type"] != "answer") continue;
      answers.push_back({r["test"].get<int>(), r["series"].get<int>(), r["condition"].get<int>(),
                         r["answer"].get<int>()});
    }
    out.push_back(answers);
  }
  return out;
}

TEST(SimulateTest, IdenticalWallsGiveChanceWithinTheBinomialInterval) {
  // two labels, one configuration: 200 participants x 20 series = 4000 answers
  const Protocol protocol = Cohort(kTrain250, kTrain250);
  ToyStimulusSource source;
  CohortConfig config;
  config.participants = 200;
  config.seed = 12345;
  const auto runs = SimulateCohort(protocol, source, config);
  std::vector<LogInput> logs;
  for (const auto& run : runs) logs.push_back({run.id, run.records});
  const StudyReport report = AnalyzeLogs(logs);
  ASSERT_EQ(report.tests.size(), 1u);
  const TestResult& t = report.tests[0];
  EXPECT_EQ(t.percent_correct.n, 200);
  EXPECT_EQ(t.pooled_answers, 4000);
  // exact central 95% interval of Binomial(4000, 0.5); with every session complete the cohort
  // mean of percent correct equals the pooled percentage
  const double lo = 100.0 * BinomialQuantile(4000, 0.5, 0.025) / 4000.0;
  const double hi = 100.0 * BinomialQuantile(4000, 0.5, 0.975) / 4000.0;
  EXPECT_GE(t.percent_correct.mean, lo);
  EXPECT_LE(t.percent_correct.mean, hi);
  EXPECT_NEAR(t.percent_correct.mean, 100.0 * t.pooled_correct / 4000.0, 1e-9);
}

Protocol ThreeWayOf(const json& a, const json& b, const json& c, int series = 30) {
  json d = {{"name", "three"},
            {"series", series},
            {"conditions", {{"a", a}, {"b", b}, {"c", c}}},
            {"tests", {{{"name", "only"}, {"conditions", {"a", "b", "c"}}}}}};
  return ParseProtocol(d, "three");
}

TestResult RunThreeWay(const Protocol& protocol, int participants, const ObserverParams& observer,
                       std::uint64_t seed) {
  ToyStimulusSource source;
  CohortConfig config;
  config.participants = participants;
  config.seed = seed;
  config.observer = observer;
  std::vector<LogInput> logs;
  for (const auto& run : SimulateCohort(protocol, source, config)) {
    logs.push_back({run.id, run.records});
  }
  return AnalyzeLogs(logs).tests.at(0);
}

// exact central 95% interval of Binomial(n, 1/3), in percent
std::pair<double, double> ThirdInterval(int n) {
  return {100.0 * BinomialQuantile(n, 1.0 / 3.0, 0.025) / n,
          100.0 * BinomialQuantile(n, 1.0 / 3.0, 0.975) / n};
}

TEST(SimulateTest, ThreeIdenticalWallsGiveChanceOfOneThird) {
  // three labels, one configuration: 100 participants x 30 series = 3000 answers
  const TestResult t = RunThreeWay(ThreeWayOf(kTrain250, kTrain250, kTrain250), 100, {}, 321);
  EXPECT_EQ(t.chance, 1.0 / 3.0);
  ASSERT_EQ(t.pooled_answers, 3000);
  const auto [lo, hi] = ThirdInterval(3000);  // 31.6% to 35.0%
  const double pooled = 100.0 * t.pooled_correct / 3000.0;
  EXPECT_GE(pooled, lo);
  EXPECT_LE(pooled, hi);
  // every label is named, and each about as often: a third of 3000 each, 5 binomial SD (25.8)
  for (int named = 0; named < 3; ++named) {
    int n = 0;
    for (int presented = 0; presented < 3; ++presented) n += t.confusion[presented][named];
    EXPECT_NEAR(n, 1000, 5 * 25.8) << named;
  }
}

TEST(SimulateTest, ThreeDifferentWallsAreIdentifiedAboveChance) {
  const TestResult t = RunThreeWay(ThreeWayOf(kTrain250, kTrain100, kPenalty1000), 20, {}, 5);
  ASSERT_EQ(t.pooled_answers, 600);
  EXPECT_GT(t.percent_correct.mean, 75.0);
  EXPECT_LT(t.pooled.p_greater, 1e-6);  // against 1/3
  // the confusion matrix counts every answer; its diagonal is the correct ones
  int total = 0, diagonal = 0;
  for (int a = 0; a < 3; ++a) {
    for (int b = 0; b < 3; ++b) total += t.confusion[a][b];
    diagonal += t.confusion[a][a];
  }
  EXPECT_EQ(total, 600);
  EXPECT_EQ(diagonal, t.pooled_correct);
}

// the label memory of three walls: an association lost before every series and re-derived from a
// coded memory far noisier than the walls' differences gives labels at random, so chance; the
// same with an exact coded memory gives the labels back
TEST(SimulateTest, ThreeWallsLabelsRederivedFromTheCodedMemory) {
  const Protocol protocol = ThreeWayOf(kTrain250, kTrain100, kPenalty1000);
  ObserverParams lost;
  lost.label_loss_per_series = 1.0;
  lost.label_code_sd_jnd = 1e4;
  const TestResult noisy = RunThreeWay(protocol, 100, lost, 9);
  const auto [lo, hi] = ThirdInterval(3000);
  const double pooled = 100.0 * noisy.pooled_correct / 3000.0;
  EXPECT_GE(pooled, lo);
  EXPECT_LE(pooled, hi);
  lost.label_code_sd_jnd = 0.0;
  EXPECT_GT(RunThreeWay(protocol, 20, lost, 9).percent_correct.mean, 75.0);
}

// a participant who always lapses guesses uniformly among the three
TEST(SimulateTest, LapsesGuessAmongAllThree) {
  ObserverParams guessing;
  guessing.lapse_rate = 1.0;
  const TestResult t =
      RunThreeWay(ThreeWayOf(kTrain250, kTrain100, kPenalty1000), 100, guessing, 4);
  for (int named = 0; named < 3; ++named) {
    int n = 0;
    for (int presented = 0; presented < 3; ++presented) n += t.confusion[presented][named];
    EXPECT_NEAR(n, 1000, 5 * 25.8) << named;  // Binomial(3000, 1/3): SD 25.8
  }
}

TEST(SimulateTest, DifferentWallsAreToldApartAndTheCohortIsDeterministic) {
  const Protocol protocol = Cohort(kTrain250, kTrain100);
  ToyStimulusSource source;
  CohortConfig config;
  config.participants = 20;
  config.seed = 7;
  const auto a = SimulateCohort(protocol, source, config);
  const auto b = SimulateCohort(protocol, source, config);
  EXPECT_EQ(Answers(a), Answers(b));
  ASSERT_EQ(a.size(), 20u);
  EXPECT_EQ(a[0].id, "sim-001");
  EXPECT_EQ(a[19].id, "sim-020");
  EXPECT_NE(a[0].seed, a[1].seed);
  config.seed = 8;
  EXPECT_NE(Answers(SimulateCohort(protocol, source, config)), Answers(a));

  std::vector<LogInput> logs;
  for (const auto& run : a) logs.push_back({run.id, run.records});
  const TestResult t = AnalyzeLogs(logs).tests[0];
  EXPECT_GT(t.percent_correct.mean, 75.0);
  EXPECT_GT(t.pooled.p_greater, 0.0);
  EXPECT_LT(t.pooled.p_greater, 1e-6);
  // simulated logs say what they are
  EXPECT_EQ(a[0].records[0]["mode"], "simulated");
  EXPECT_EQ(a[0].records[0]["stimulus_source"], "test-only toy stimulus source");
  EXPECT_EQ(a[0].records[0]["observer"], ObserverParams{}.ToJson());
}

TEST(SimulateTest, IdsAreZeroPaddedToTheCohortSize) {
  EXPECT_EQ(SimulatedParticipantId(0, 9), "sim-001");
  EXPECT_EQ(SimulatedParticipantId(41, 999), "sim-042");
  EXPECT_EQ(SimulatedParticipantId(41, 1000), "sim-0042");
  EXPECT_EQ(SimulatedParticipantId(12344, 20000), "sim-12345");
}

TEST(SimulateTest, SwappedLabelsAreFlaggedBelowChance) {
  const Protocol protocol = Cohort(kTrain250, kTrain100);
  ToyStimulusSource source;
  CohortConfig config;
  config.participants = 5;
  config.seed = 3;
  config.observer.label_swap_probability = 1.0;
  config.observer.lapse_rate = 0.0;
  config.observer.label_loss_per_series = 0.0;  // held swapped for the whole test
  std::vector<LogInput> logs;
  for (const auto& run : SimulateCohort(protocol, source, config)) {
    logs.push_back({run.id, run.records});
  }
  const TestResult t = AnalyzeLogs(logs).tests[0];
  for (const ParticipantResult& p : t.participants) {
    EXPECT_TRUE(p.label_swap_suspected) << p.id << " " << p.percent_correct;
    EXPECT_LT(p.d_prime.d_prime, 0.0);
  }
}

TEST(SimulateTest, LoggedCohortRefusesAnotherObserverOnResume) {
  ScratchDir dir;
  const Protocol protocol = Cohort(kPenalty1000, kPenalty1300, 4);
  ToyStimulusSource source;
  CohortConfig config;
  config.participants = 2;
  config.seed = 5;
  config.log_dir = dir.path();
  SimulateCohort(protocol, source, config);
  const std::string before = ReadFile(dir.File("sim-001.jsonl"));
  config.resume = true;
  config.observer.lapse_rate = 0.1;
  try {
    SimulateCohort(protocol, source, config);
    FAIL() << "expected a refusal";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("different observer"), std::string::npos) << e.what();
  }
  EXPECT_EQ(ReadFile(dir.File("sim-001.jsonl")), before);
  config.resume = false;
  config.observer = ObserverParams{};
  EXPECT_THROW(SimulateCohort(protocol, source, config), Error);  // logs exist, no --resume
}

// answers recorded so far in the cohort's logs (the logs may be being written)
int CountAnswers(const ScratchDir& dir, int participants) {
  int answers = 0;
  for (int i = 0; i < participants; ++i) {
    const std::string log = dir.File(SimulatedParticipantId(i, participants) + ".jsonl");
    for (const json& r : ReadLog(log).records) answers += r["type"] == "answer" ? 1 : 0;
  }
  return answers;
}

TEST(SimulateTest, KilledAndResumedCohortEqualsAnUninterruptedOne) {
  const Protocol protocol = Cohort(kPenalty1000, kPenalty1300, 12);
  ToyStimulusSource source;
  CohortConfig config;
  config.participants = 4;
  config.seed = 99;

  ScratchDir reference_dir;
  config.log_dir = reference_dir.path();
  const auto reference = SimulateCohort(protocol, source, config);
  const int total = 4 * 12;

  ScratchDir crash_dir;
  config.log_dir = crash_dir.path();
  config.resume = true;
  Rng rng(2718);
  std::set<int> answers_at_kill;  // where the kills landed
  // kill again and again until the cohort completes: each kill waits for 1 to 6 more answers and
  // a random delay, so the kills land at many points however fast the machine runs the cohort
  for (int attempt = 0; attempt < 60 && CountAnswers(crash_dir, 4) < total; ++attempt) {
    const int target = CountAnswers(crash_dir, 4) + 1 + static_cast<int>(rng.Below(6));
    std::fflush(nullptr);
    const pid_t child = fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
      // the child resumes the cohort until it is killed; no gtest code runs here
      try {
        SimulateCohort(protocol, source, config);
      } catch (...) {
        _exit(3);
      }
      _exit(0);
    }
    int status = 0;
    bool exited = false;
    while (CountAnswers(crash_dir, 4) < target) {
      if (waitpid(child, &status, WNOHANG) == child) {
        exited = true;
        break;
      }
      std::this_thread::sleep_for(std::chrono::microseconds(200));
    }
    if (!exited) {
      std::this_thread::sleep_for(std::chrono::microseconds(rng.Below(1000)));
      kill(child, SIGKILL);
      waitpid(child, &status, 0);
    }
    if (WIFSIGNALED(status)) {
      answers_at_kill.insert(CountAnswers(crash_dir, 4));
    } else {
      ASSERT_TRUE(WIFEXITED(status));
      ASSERT_EQ(WEXITSTATUS(status), 0) << "the child failed to resume";
    }
  }
  const auto resumed = SimulateCohort(protocol, source, config);
  EXPECT_EQ(Answers(resumed), Answers(reference));
  for (const auto& run : resumed) {
    const LogContents c = ReadLog(run.log_path);
    EXPECT_EQ(c.torn_tail_bytes, 0u);
    EXPECT_EQ(c.records.back()["type"], "session_end");
  }
  std::cout << "[ info ] " << answers_at_kill.size() << " kills landed, after";
  for (int a : answers_at_kill) std::cout << " " << a;
  std::cout << " of " << total << " answers\n";
  EXPECT_GE(answers_at_kill.size(), 3u) << "the kills should land at several points";
}

TEST(SimulateTest, PredictProtocolUsesTheObserverModel) {
  const Protocol same = Cohort(kTrain250, kTrain250);
  const Protocol different = Cohort(kTrain250, kTrain100);
  ToyStimulusSource source;
  const ObserverParams observer;
  const auto p_same = PredictProtocol(same, source, observer, 1, 10);
  const auto p_diff = PredictProtocol(different, source, observer, 1, 10);
  ASSERT_EQ(p_same.size(), 1u);
  EXPECT_EQ(p_same[0].name, "only");
  EXPECT_EQ(p_same[0].distance_jnd, 0.0);
  EXPECT_DOUBLE_EQ(p_same[0].percent_correct, 50.0);
  EXPECT_GT(p_diff[0].distance_jnd, 0.0);
  EXPECT_GT(p_diff[0].percent_correct, 50.0);
  EXPECT_THROW(PredictProtocol(same, source, observer, 1, 0), Error);
}

TEST(SimulateTest, PredictedSharesOfGuessingCohortsAreBinomial) {
  // an observer who always guesses answers each of 20 series with a fair coin: a participant's
  // score is Binomial(20, 1/2), so P(<= 50%) = P(X <= 10) and P(>= 90%) = P(X >= 18); the count
  // of such participants in a cohort of 9 is Binomial(9, P)
  const Protocol protocol = Cohort(kTrain250, kTrain100);
  ToyStimulusSource source;
  ObserverParams observer;
  observer.lapse_rate = 1.0;
  PredictionConfig config;
  config.sample_taps = 5;
  config.participants = 9;
  config.cohorts = 1000;
  const auto predictions = PredictProtocol(protocol, source, observer, config);
  ASSERT_EQ(predictions.size(), 1u);
  const TestPrediction& p = predictions[0];
  double at_most_10 = 0.0;
  double at_least_18 = 0.0;
  for (int k = 0; k <= 20; ++k) {
    if (k <= 10) at_most_10 += BinomialPmf(k, 20, 0.5);
    if (k >= 18) at_least_18 += BinomialPmf(k, 20, 0.5);
  }
  // 9000 simulated participants: 4 binomial SE
  EXPECT_NEAR(p.at_most_50.expected, at_most_10, 4.0 * std::sqrt(at_most_10 * 0.5 / 9000.0));
  EXPECT_NEAR(p.at_least_90.expected, at_least_18, 0.001);
  EXPECT_NEAR(p.cohort_percent_correct.expected, 50.0, 4.0 * 100.0 * std::sqrt(0.25 / 180000.0));
  // the cohort interval: 5th and 95th percentiles of Binomial(9, P) / 9. The 5th is 3 of 9
  // (CDF 0.030 at 2, 0.113 at 3: both several SE of 1000 cohorts away from 0.05); the 95th is 8
  // of 9, but CDF(7) = 0.9385 is only 1.5 SE below 0.95, so 7 of 9 is allowed too
  EXPECT_EQ(BinomialQuantile(9, at_most_10, 0.05), 3);
  EXPECT_NEAR(p.at_most_50.low, 3.0 / 9.0, 1e-12);
  EXPECT_EQ(BinomialQuantile(9, at_most_10, 0.95), 8);
  EXPECT_TRUE(std::abs(p.at_most_50.high - 8.0 / 9.0) < 1e-12 ||
              std::abs(p.at_most_50.high - 7.0 / 9.0) < 1e-12)
      << p.at_most_50.high;
  EXPECT_LE(p.at_most_50.low, p.at_most_50.expected);
  EXPECT_GE(p.at_most_50.high, p.at_most_50.expected);
  EXPECT_EQ(p.at_least_90.low, 0.0);
}

TEST(SimulateTest, PredictedSharesOfLapsingPerfectObserversAreBinomial) {
  // walls far apart, exact memory, no label loss: right on every series except the lapses, which
  // guess; so each answer is right with probability 1 - lapse / 2 = 0.8, independently, and a
  // participant's score is Binomial(20, 0.8): P(>= 90%) = P(X >= 18), P(<= 50%) = P(X <= 10)
  const Protocol protocol = Cohort(kPenalty1000, kTrain250);
  ToyStimulusSource source(/*speed_log_sd=*/0.0);
  ObserverParams observer;
  observer.individual_jnd_log_sd = 0.0;
  observer.individual_threshold_sd_dB = 0.0;
  observer.memory_encoding_sd_jnd = 0.0;
  observer.memory_drift_sd_jnd_per_series = 0.0;
  observer.label_loss_per_series = 0.0;
  observer.lapse_rate = 0.0;
  PredictionConfig config;
  config.sample_taps = 1;
  config.cohorts = 0;
  ASSERT_GT(PredictProtocol(protocol, source, observer, config)[0].percent_correct, 99.999);
  observer.lapse_rate = 0.4;
  config.cohorts = 1000;
  const TestPrediction p = PredictProtocol(protocol, source, observer, config)[0];
  double at_least_18 = 0.0;
  double at_most_10 = 0.0;
  for (int k = 0; k <= 20; ++k) {
    if (k >= 18) at_least_18 += BinomialPmf(k, 20, 0.8);
    if (k <= 10) at_most_10 += BinomialPmf(k, 20, 0.8);
  }
  // 9000 simulated participants: 4 binomial SE
  EXPECT_NEAR(p.at_least_90.expected, at_least_18,
              4.0 * std::sqrt(at_least_18 * (1.0 - at_least_18) / 9000.0));
  EXPECT_NEAR(p.at_most_50.expected, at_most_10,
              4.0 * std::sqrt(at_most_10 * (1.0 - at_most_10) / 9000.0) + 1e-4);
  EXPECT_NEAR(p.cohort_percent_correct.expected, 80.0, 4.0 * 100.0 * std::sqrt(0.16 / 180000.0));
}

TEST(SimulateTest, PredictedCohortsSeparateEasyFromIdenticalWalls) {
  ToyStimulusSource source;
  const ObserverParams observer;
  PredictionConfig config;
  config.sample_taps = 10;
  config.cohorts = 200;
  const auto same = PredictProtocol(Cohort(kTrain250, kTrain250), source, observer, config)[0];
  const auto easy = PredictProtocol(Cohort(kTrain250, kTrain100), source, observer, config)[0];
  // identical walls: nobody is expected at >= 90% (P(X >= 18 of 20) = 2e-4 for a coin; answers
  // to identical walls are no better than coins), most at <= 50%
  EXPECT_LT(same.at_least_90.expected, 0.01);
  EXPECT_GT(same.at_most_50.expected, 0.4);
  EXPECT_NEAR(same.cohort_percent_correct.expected, 50.0, 2.0);
  EXPECT_GT(easy.at_least_90.expected, 0.5);
  EXPECT_LT(easy.at_most_50.expected, same.at_most_50.expected);
  EXPECT_GT(easy.cohort_percent_correct.expected, 80.0);
  config.participants = 0;
  EXPECT_THROW(PredictProtocol(Cohort(kTrain250, kTrain100), source, observer, config), Error);
}

}  // namespace
}  // namespace rigidtouch::study
