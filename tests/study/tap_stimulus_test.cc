// The study's engine binding: percepts of simulated taps from the real tap experiment.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "study/analysis.h"
#include "study/protocol.h"
#include "study/simulate.h"
#include "study/statistics.h"
#include "study/stimulus.h"

namespace rigidtouch::study {
namespace {

using nlohmann::json;

Condition Wall(const json& c) {
  const json d = {{"name", "one"},
                  {"conditions", {{"a", c}, {"b", c}}},
                  {"tests", {{{"name", "t"}, {"conditions", {"a", "b"}}}}}};
  return ParseProtocol(d, "test").conditions[0];
}

const json kWall0 = {{"renderer", "impulse"}, {"restitution", 0}};
const json kWall1 = {{"renderer", "train"}, {"t_collision_s", 0.1}, {"frequency_hz", 250}};
const json kWall2 = {{"renderer", "train"}, {"t_collision_s", 0.1}, {"frequency_hz", 50}};

TEST(TapStimulusTest, PerceptsAreDeterministicAndTellTheWallsApart) {
  const auto source = MakeTapStimulusSource({});
  const TapPercept a = source->RenderTap(Wall(kWall1), 42);
  const TapPercept b = source->RenderTap(Wall(kWall1), 42);
  EXPECT_EQ(a.peak_force_N, b.peak_force_N);  // same seed, same tap, bit for bit
  EXPECT_EQ(a.vibration_rms_N, b.vibration_rms_N);
  EXPECT_GT(a.peak_force_N, 0.0);
  EXPECT_GT(a.vibration_rms_N, 0.0);
  double fractions = 0.0;
  for (double f : a.band_energy_fraction) fractions += f;
  EXPECT_NEAR(fractions, 1.0, 1e-9);
  // another seed draws another hand speed (10% spread)
  const TapPercept c = source->RenderTap(Wall(kWall1), 43);
  EXPECT_NE(a.approach_speed_mps, c.approach_speed_mps);
  // the 250 Hz train puts more of its force into the 100-400 Hz band, and more vibration, than
  // the 50 Hz train
  const TapPercept w2 = source->RenderTap(Wall(kWall2), 42);
  EXPECT_GT(a.band_energy_fraction[2], w2.band_energy_fraction[2]);
  EXPECT_GT(a.vibration_rms_N, w2.vibration_rms_N);
}

// two identical walls through the real tap source: a cohort of 200 simulated participants stays
// within the exact binomial 95% interval of 50% (1 tap per series keeps the run to seconds)
TEST(TapStimulusTest, IdenticalWallsThroughTheEngineGiveChance) {
  const json d = {{"name", "identical"},
                  {"series", 20},
                  {"conditions", {{"a", kWall1}, {"b", kWall1}}},
                  {"tests",
                   {{{"name", "same"},
                     {"conditions", {"a", "b"}},
                     {"familiarization_taps", 1},
                     {"taps_per_series", 1}}}}};
  const Protocol protocol = ParseProtocol(d, "identical");
  const auto source = MakeTapStimulusSource({});
  CohortConfig config;
  config.participants = 200;
  config.seed = 2026;
  const auto runs = SimulateCohort(protocol, *source, config);
  std::vector<LogInput> logs;
  for (const auto& run : runs) logs.push_back({run.id, run.records});
  const StudyReport report = AnalyzeLogs(logs);
  ASSERT_EQ(report.tests.size(), 1u);
  const TestResult& t = report.tests[0];
  ASSERT_EQ(t.pooled_answers, 4000);
  const double lo = 100.0 * BinomialQuantile(4000, 0.5, 0.025) / 4000.0;
  const double hi = 100.0 * BinomialQuantile(4000, 0.5, 0.975) / 4000.0;
  EXPECT_GE(t.percent_correct.mean, lo);
  EXPECT_LE(t.percent_correct.mean, hi);
}

// the method's study through the engine (the documented prediction, docs/study.md): the second
// test (wall 1 vs wall 2) is predicted harder than the first (wall 0 vs wall 1), by the nominal
// observer and by simulated cohorts of 9, with fewer participants at >= 90% and more at <= 50%
TEST(TapStimulusTest, WallsProtocolPredictsTheSecondTestHarder) {
  const Protocol protocol =
      LoadProtocol(std::string(RIGIDTOUCH_SOURCE_DIR) + "/studies/walls.json");
  const auto source = MakeTapStimulusSource({});
  PredictionConfig config;
  config.cohorts = 300;
  const auto p = PredictProtocol(protocol, *source, ObserverParams{}, config);
  ASSERT_EQ(p.size(), 2u);
  EXPECT_LT(p[1].distance_jnd, p[0].distance_jnd);
  EXPECT_LT(p[1].percent_correct, p[0].percent_correct);
  EXPECT_GT(p[1].label_interference, p[0].label_interference);  // wall 2 feels like wall 0
  EXPECT_LT(p[1].cohort_percent_correct.expected, p[0].cohort_percent_correct.expected);
  EXPECT_LT(p[1].at_least_90.expected, p[0].at_least_90.expected);
  EXPECT_GT(p[1].at_most_50.expected, p[0].at_most_50.expected);
  EXPECT_GT(p[1].cohorts_below_previous, 0.5);
  for (const TestPrediction& t : p) {
    for (const CohortShare& share : {t.at_least_90, t.at_most_50}) {
      EXPECT_LE(0.0, share.low);
      EXPECT_LE(share.low, share.expected);
      EXPECT_LE(share.expected, share.high);
      EXPECT_LE(share.high, 1.0);
    }
  }
}

}  // namespace
}  // namespace rigidtouch::study
