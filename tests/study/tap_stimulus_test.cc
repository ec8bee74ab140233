// The study's engine binding: percepts of simulated taps from the real tap experiment.
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "analysis/spectrum.h"
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
}

// stdout of a command
std::string Output(const std::string& command) {
  std::string out;
  FILE* pipe = popen(command.c_str(), "r");
  if (pipe == nullptr) return out;
  char buffer[4096];
  std::size_t n = 0;
  while ((n = std::fread(buffer, 1, sizeof buffer, pipe)) > 0) out.append(buffer, n);
  pclose(pipe);
  return out;
}

// a condition with a material and passivity control is rendered as `rigidtouch tap --renderer R
// --material M [--passivity-control]` renders it: the same tap, to the last bit the JSON prints
TEST(TapStimulusTest, MaterialConditionsRenderAsTheTapCommand) {
  TapSourceOptions options;
  options.approach_speed_relative_sd = 0.0;  // as tap without --spread
  const auto source = MakeTapStimulusSource(options);
  struct Case {
    json condition;
    std::string flags;
  };
  const std::vector<Case> cases = {
      {{{"renderer", "event"}, {"material", "wood"}}, "--renderer event --material wood"},
      {{{"renderer", "train"}, {"material", "aluminium"}}, "--renderer train --material aluminium"},
      {{{"renderer", "event"}, {"material", "rubber"}, {"passivity_control", true}},
       "--renderer event --material rubber --passivity-control"},
  };
  std::vector<double> peaks;
  for (const Case& c : cases) {
    const TapPercept p = source->RenderTap(Wall(c.condition), 1);
    const json tap = json::parse(
        Output(std::string(RIGIDTOUCH_CLI) + " tap " + c.flags + " --taps 1 --json"))["taps"][0];
    EXPECT_DOUBLE_EQ(p.peak_force_N, tap["peak_force_N"].get<double>()) << c.flags;
    EXPECT_DOUBLE_EQ(p.rate_hardness_N_per_m, tap["rate_hardness_N_per_m"].get<double>())
        << c.flags;
    EXPECT_DOUBLE_EQ(p.transient_peak_to_mean, tap["transient_peak_to_mean"].get<double>())
        << c.flags;
    peaks.push_back(p.peak_force_N);
  }
  // and the material matters: rubber's transient is not wood's
  EXPECT_NE(peaks[0], peaks[2]);
}

// an acceleration material on a device of another mass: the study renders it as `tap --device`
// does (the force converted with the device's effective mass), also after the protocol's
// canonical form, which keeps the material's acceleration and mass
TEST(TapStimulusTest, AnAccelerationMaterialIsConvertedForTheDeviceAsTheTapCommandDoes) {
  const std::string stem = (std::filesystem::temp_directory_path() /
                            ("rigidtouch_study_accel_" + std::to_string(::getpid())))
                               .string();
  const std::string material = stem + "_wood.json", device = stem + "_heavy.json";
  // the preset wood's 15 N/(m/s) as fitted on the Touch (0.599 kg), and the Touch with its
  // apparent mass 0.645 kg instead of 0.045 kg (effective 1.199 kg)
  std::ofstream(material) << json{
      {"name", "accel_wood"},
      {"amplitude_Ns_per_m", 15.0},
      {"decay_per_s", 60},
      {"frequency_hz", 100},
      {"amplitude_quantity", "acceleration"},
      {"amplitude_mps2_per_mps", 15.0 / 0.599},
      {"effective_mass_kg",
       0.599}}.dump();
  std::ofstream(device) << json{{"name", "heavy"},
                                {"max_force_N", 0},
                                {"max_stiffness_N_per_m", 400},
                                {"max_damping_Ns_per_m", 4},
                                {"apparent_mass_kg", 0.645},
                                {"encoder_resolution_m", 0.055e-3},
                                {"velocity_filter_hz", 100},
                                {"delay_ticks", 0}}
                               .dump();
  TapSourceOptions options;
  options.approach_speed_relative_sd = 0.0;  // as tap without --spread
  options.device = device;
  const auto source = MakeTapStimulusSource(options);
  const Condition parsed = Wall({{"renderer", "event"}, {"material", material}});
  ASSERT_TRUE(parsed.material && parsed.material->acceleration());
  const Condition canonical = Wall(parsed.ToJson());
  ASSERT_TRUE(canonical.material && canonical.material->acceleration());
  const json cli =
      json::parse(Output(std::string(RIGIDTOUCH_CLI) + " tap --renderer event --material " +
                         material + " --device " + device + " --taps 1 --json 2>/dev/null"));
  EXPECT_NEAR(cli["material_amplitude_Ns_per_m"].get<double>(), 15.0 / 0.599 * 1.199, 1e-9);
  const json tap = cli["taps"][0];
  for (const Condition& c : {parsed, canonical}) {
    const TapPercept p = source->RenderTap(c, 1);
    EXPECT_DOUBLE_EQ(p.peak_force_N, tap["peak_force_N"].get<double>());
    EXPECT_DOUBLE_EQ(p.transient_peak_to_mean, tap["transient_peak_to_mean"].get<double>());
  }
  std::filesystem::remove(material);
  std::filesystem::remove(device);
}

// the percept's vibration is the transient part (what the impulses add) and its pitch the
// repetition rate of a periodic transient: on the Touch at 0.2 m/s wall 1's transient is a train
// of pulses every 4 ms, wall 2's three clipped pulses 20 ms apart (docs/study.md), wall 0's one
// clipped pulse a click with a flat spectrum, and a pure penalty wall has no transient at all
TEST(TapStimulusTest, PitchOnlyWhereTheTransientIsPeriodic) {
  const auto source = MakeTapStimulusSource({});
  for (std::uint64_t seed : {1u, 2u, 3u}) {
    const TapPercept w0 = source->RenderTap(Wall(kWall0), seed);
    const TapPercept w1 = source->RenderTap(Wall(kWall1), seed);
    const TapPercept w2 = source->RenderTap(Wall(kWall2), seed);
    const TapPercept penalty = source->RenderTap(Wall({{"renderer", "penalty"}}), seed);
    // a click: flat spectrum (peak over mean about 1), no pitch, but a vibration
    EXPECT_LT(w0.transient_peak_to_mean, 1.2);
    EXPECT_EQ(w0.dominant_frequency_hz, 0.0);
    EXPECT_EQ(w0.periodicity, 0.0);
    EXPECT_GT(w0.vibration_rms_N, 0.0);
    // the 250 Hz train: a line, its period 4 ticks at 1 kHz
    EXPECT_GT(w1.transient_peak_to_mean, analysis::kRepetitionPeakToMean);
    EXPECT_NEAR(w1.dominant_frequency_hz, 250.0, 1e-6);
    EXPECT_GT(w1.periodicity, 0.5);
    // the 50 Hz train: its largest spectral bin is any of its equal harmonics, its pitch the
    // 20 ms between pulses
    EXPECT_GT(w2.transient_peak_to_mean, analysis::kRepetitionPeakToMean);
    EXPECT_NEAR(w2.dominant_frequency_hz, 50.0, 1e-6);
    EXPECT_GT(w2.periodicity, 0.0);
    EXPECT_LT(w2.periodicity, w1.periodicity);
    // pure penalty: nothing added to the press
    EXPECT_EQ(penalty.vibration_rms_N, 0.0);
    EXPECT_EQ(penalty.dominant_frequency_hz, 0.0);
    for (double f : penalty.band_energy_fraction) EXPECT_EQ(f, 0.0);
  }
}

// two identical walls through the real tap source: a cohort of simulated participants stays
// within the exact binomial 95% interval of 50% (1 tap per series keeps each answer to one tap)
void ExpectIdenticalWallsGiveChance(int participants) {
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
  config.participants = participants;
  config.seed = 2026;
  const auto runs = SimulateCohort(protocol, *source, config);
  std::vector<LogInput> logs;
  for (const auto& run : runs) logs.push_back({run.id, run.records});
  const StudyReport report = AnalyzeLogs(logs);
  ASSERT_EQ(report.tests.size(), 1u);
  const TestResult& t = report.tests[0];
  const int answers = 20 * participants;
  ASSERT_EQ(t.pooled_answers, answers);
  const double lo = 100.0 * BinomialQuantile(answers, 0.5, 0.025) / answers;
  const double hi = 100.0 * BinomialQuantile(answers, 0.5, 0.975) / answers;
  EXPECT_GE(t.percent_correct.mean, lo);
  EXPECT_LE(t.percent_correct.mean, hi);
}

// 200 participants, 4000 answers (interval 48.45-51.55%): 13 s in the release build, minutes under
// the sanitizers, so the full gate's release pass runs it (docs/testing.md)
TEST(TapStimulusTest, SlowIdenticalWallsThroughTheEngineGiveChance) {
  ExpectIdenticalWallsGiveChance(200);
}

// its fast counterpart: 20 participants, 400 answers (interval 45-55%)
TEST(TapStimulusTest, IdenticalWallsThroughTheEngineGiveChanceInASmallCohort) {
  ExpectIdenticalWallsGiveChance(20);
}

// the method's study through the engine (the documented prediction, docs/study.md): on the
// simulated Touch wall 0 is a click and walls 1 and 2 are pitched trains (250 and 50 Hz), so the
// second test's walls differ in pitch by ln(5) / ln(1.2) = 8.8 Weber steps and the model predicts
// it NOT harder than the first, against what the method's participants reported; the
// interference of wall 0 (a click, like no other wall now) is what remains of the ordering
TEST(TapStimulusTest, WallsProtocolPredictionAsDocumented) {
  const Protocol protocol =
      LoadProtocol(std::string(RIGIDTOUCH_SOURCE_DIR) + "/studies/walls.json");
  const auto source = MakeTapStimulusSource({});
  PredictionConfig config;
  config.cohorts = 300;
  const auto p = PredictProtocol(protocol, *source, ObserverParams{}, config);
  ASSERT_EQ(p.size(), 2u);
  // the click has no pitch; the trains are a whole pitch range apart
  EXPECT_EQ(p[0].mean_percepts[0][3], 0.0);
  EXPECT_EQ(p[0].mean_percepts[0][4], 0.0);
  EXPECT_GT(p[1].mean_percepts[0][3] - p[1].mean_percepts[1][3],
            0.8 * std::log(5.0) / std::log(1.2));
  EXPECT_GT(p[1].distance_jnd, p[0].distance_jnd);
  EXPECT_GT(p[1].percent_correct, p[0].percent_correct);
  EXPECT_GT(p[1].label_interference, p[0].label_interference);
  EXPECT_LT(p[1].cohorts_below_previous, 0.5);
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
