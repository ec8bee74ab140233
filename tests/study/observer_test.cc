#include "study/observer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <numbers>
#include <string>
#include <vector>

#include "rigidtouch/types.h"
#include "study/plan.h"
#include "study/random.h"
#include "study/statistics.h"
#include "study/test_files.h"
#include "study/toy_stimulus.h"

namespace rigidtouch::study {
namespace {

using nlohmann::json;
using testing::ToyStimulusSource;

Condition Penalty(double stiffness_N_per_m) {
  Condition c;
  c.label = "penalty";
  c.renderer = RendererKind::kPenalty;
  c.stiffness_N_per_m = stiffness_N_per_m;
  return c;
}

Condition Impulse(double restitution) {
  Condition c;
  c.label = "impulse";
  c.renderer = RendererKind::kImpulse;
  c.restitution = restitution;
  return c;
}

Condition Train(double frequency_hz) {
  Condition c;
  c.label = "train";
  c.renderer = RendererKind::kTrain;
  c.t_collision_s = 0.1;
  c.frequency_hz = frequency_hz;
  return c;
}

StudyTest MethodTest() {
  // 3 familiarization taps, 20 series of 3 taps
  StudyTest t;
  t.name.assign(1, 't');  // not = "t": GCC 12's -Wrestrict misfires on it (its bug 105329)
  t.conditions = {0, 1};
  t.keys = {"1", "2"};
  return t;
}

TEST(ObserverTest, ChannelSensitivityFollowsTheFourChannelShapes) {
  const ObserverParams p;
  // exact by construction: 12 dB per octave around 250 Hz, NP flat below 40 Hz at P(40 Hz)
  EXPECT_DOUBLE_EQ(PacinianGain_dB(p, 250.0), 0.0);
  EXPECT_NEAR(PacinianGain_dB(p, 125.0), -12.0, 1e-12);
  EXPECT_NEAR(PacinianGain_dB(p, 500.0), -12.0, 1e-12);
  const double p40 = -12.0 * std::log2(250.0 / 40.0);
  EXPECT_NEAR(NonPacinianGain_dB(p, 40.0), p40, 1e-12);
  EXPECT_NEAR(NonPacinianGain_dB(p, 20.0), p40, 1e-12);
  EXPECT_NEAR(NonPacinianGain_dB(p, 80.0), p40 - 12.0, 1e-12);
  // NP is the more sensitive channel below 40 Hz, P above
  EXPECT_GT(NonPacinianGain_dB(p, 20.0), PacinianGain_dB(p, 20.0));
  EXPECT_LT(NonPacinianGain_dB(p, 100.0), PacinianGain_dB(p, 100.0));
  const auto centres = PerceptBandCentres_hz();
  EXPECT_NEAR(centres[0], 20.0, 1e-12);
  EXPECT_NEAR(centres[2], 200.0, 1e-12);
}

TEST(ObserverTest, PerceptVectorClosedForm) {
  const ObserverParams p;
  TapPercept tap;
  tap.peak_force_N = 10.0;
  tap.vibration_rms_N = 10.0 * p.vibration_threshold_rms_N;  // 20 dB above threshold
  tap.band_energy_fraction = {0.0, 0.0, 1.0, 0.0};           // all at 200 Hz
  tap.dominant_frequency_hz = 200.0;
  const PerceptVector v = ToPerceptVector(p, tap);
  EXPECT_NEAR(v[0], 20.0 / 2.3, 1e-12);
  const double sl_p = 20.0 - 12.0 * std::log2(250.0 / 200.0);
  EXPECT_NEAR(v[1], sl_p / 2.3, 1e-12);
  // NP at 200 Hz is far below threshold here: 0 dB SL
  EXPECT_EQ(v[2], 0.0);
  // salient (SL >= 10 dB): full pitch cue, from the pitch axis's origin sqrt(40 * 400) Hz; no
  // periodicity given: a pitch without a periodicity cue
  EXPECT_NEAR(v[3], std::log(200.0 / std::sqrt(40.0 * 400.0)) / std::log(1.2), 1e-12);
  EXPECT_EQ(v[4], 0.0);

  TapPercept silent;
  silent.peak_force_N = 0.001;  // below the onset floor
  silent.dominant_frequency_hz = 100.0;
  const PerceptVector s = ToPerceptVector(p, silent);
  EXPECT_NEAR(s[0], 20.0 * std::log10(0.01) / 2.3, 1e-12);
  EXPECT_EQ(s[1], 0.0);
  EXPECT_EQ(s[2], 0.0);
  EXPECT_EQ(s[3], 0.0);  // an imperceptible vibration has no pitch
  EXPECT_EQ(s[4], 0.0);

  TapPercept bad = tap;
  bad.peak_force_N = std::nan("");
  EXPECT_THROW(ToPerceptVector(p, bad), Error);
}

// a click has no pitch: it is not encoded as 250 Hz (the old encoding put "no vibration" at the
// P channel's best frequency) nor as the press's frequency, and a periodic train is told from it
// by its periodicity
TEST(ObserverTest, ClickHasNoPitchAndATrainIsToldFromIt) {
  const ObserverParams p;
  TapPercept click;
  click.peak_force_N = 3.3;
  click.vibration_rms_N = 100.0 * p.vibration_threshold_rms_N;  // 40 dB: any pitch is salient
  click.band_energy_fraction = {0.08, 0.11, 0.61, 0.2};         // flat spectrum's shares
  TapPercept train = click;
  train.dominant_frequency_hz = 250.0;
  train.periodicity = 0.9;
  TapPercept low = train;
  low.dominant_frequency_hz = 50.0;
  const PerceptVector c = ToPerceptVector(p, click);
  const PerceptVector t = ToPerceptVector(p, train);
  const PerceptVector l = ToPerceptVector(p, low);
  // the click sits at the pitch origin with no periodicity
  EXPECT_EQ(c[3], 0.0);
  EXPECT_EQ(c[4], 0.0);
  // the trains: pitch in Weber steps from the origin, periodicity 0.9 x 10 dB / 2.3 dB
  const double origin = std::sqrt(40.0 * 400.0);
  EXPECT_NEAR(t[3], std::log(250.0 / origin) / std::log(1.2), 1e-12);
  EXPECT_NEAR(l[3], std::log(50.0 / origin) / std::log(1.2), 1e-12);
  EXPECT_NEAR(t[4], 0.9 * 10.0 / 2.3, 1e-12);
  EXPECT_NEAR(l[4], 0.9 * 10.0 / 2.3, 1e-12);
  // identical vibration but for the pitch: the click differs from the 250 Hz train (it did not
  // under the old encoding) and is nearer to the pitch range's centre than either train is to the
  // other, so a click is not a low or a high pitch
  const double click_250 = PerceptDistance(c, t);
  const double click_50 = PerceptDistance(c, l);
  EXPECT_GT(click_250, 3.0);
  EXPECT_LT(click_250, PerceptDistance(t, l));
  EXPECT_LT(click_50, PerceptDistance(t, l));
  // a percept with a periodicity outside [0, 1] is refused
  TapPercept bad = train;
  bad.periodicity = 1.5;
  EXPECT_THROW(ToPerceptVector(p, bad), Error);
}

TEST(ObserverTest, ProbabilityCorrectSpecialCases) {
  EXPECT_EQ(NearestTemplateProbabilityCorrect(0.0, 0.3, 0.7, 4), 0.5);
  // exact templates: Phi(d / (2 sigma))
  EXPECT_NEAR(NearestTemplateProbabilityCorrect(1.5, 0.25, 0.0, 4), NormalCdf(1.5 / 1.0), 1e-15);
  // one axis: closed form
  const double c = 1.0 / std::sqrt(4 * 0.5 + 2 * 0.5);
  const double t = 1.0 / std::sqrt(2 * 0.5);
  EXPECT_NEAR(NearestTemplateProbabilityCorrect(1.0, 0.5, 0.5, 1),
              NormalCdf(c) * NormalCdf(t) + NormalCdf(-c) * NormalCdf(-t), 1e-15);
  // quadrature is continuous with the exact-template limit (tolerance: 1e-3 for vm = 1e-6)
  EXPECT_NEAR(NearestTemplateProbabilityCorrect(1.5, 0.25, 1e-6, 4), NormalCdf(1.5), 1e-3);
}

// direct Monte Carlo of the nearest-template rule with `dims` axes
double MonteCarloProbabilityCorrect(double distance, double vs, double vm, int dims, int trials,
                                    std::uint64_t seed) {
  Rng rng(seed);
  int correct = 0;
  for (int i = 0; i < trials; ++i) {
    double da = 0.0;
    double db = 0.0;
    for (int k = 0; k < dims; ++k) {
      const double x = std::sqrt(vs) * rng.Normal();  // wall A at the origin was presented
      const double a = std::sqrt(vm) * rng.Normal();
      const double b = (k == 0 ? distance : 0.0) + std::sqrt(vm) * rng.Normal();
      da += (x - a) * (x - a);
      db += (x - b) * (x - b);
    }
    correct += da < db ? 1 : 0;
  }
  return static_cast<double>(correct) / trials;
}

TEST(ObserverTest, QuadratureMatchesMonteCarlo) {
  // 200000 trials: SE <= 0.0011; tolerance 4 SE = 0.0045
  struct Case {
    double distance, vs, vm;
    int dims;
  };
  for (const Case& c : {Case{1.0, 1.0 / 3.0, 0.6, 4}, Case{2.5, 1.0 / 3.0, 1.5, 4},
                        Case{0.7, 0.2, 0.3, 2}, Case{3.0, 1.0, 2.0, 3}}) {
    const double q = NearestTemplateProbabilityCorrect(c.distance, c.vs, c.vm, c.dims);
    const double mc = MonteCarloProbabilityCorrect(c.distance, c.vs, c.vm, c.dims, 200000, 17);
    EXPECT_NEAR(q, mc, 0.0045) << c.distance << " " << c.vm << " " << c.dims;
  }
}

TEST(ObserverTest, ProbabilityCorrectNeverFallsAsWallsMoveApart) {
  for (double vm : {0.0, 0.1, 0.6, 2.0}) {
    double previous = 0.5;
    for (double d = 0.0; d <= 10.0; d += 0.1) {
      const double pc = NearestTemplateProbabilityCorrect(d, 1.0 / 3.0, vm, kPerceptDimensions);
      EXPECT_GE(pc, previous - 1e-12) << "vm " << vm << " d " << d;  // round-off only
      EXPECT_LE(pc, 1.0);
      previous = pc;
    }
    EXPECT_GT(previous, 0.99);
  }
}

TEST(ObserverTest, PredictionBoundaries) {
  ObserverParams p;
  const StudyTest t = MethodTest();
  const PerceptVector a = {0.0, 0.0, 0.0, 0.0};
  const PerceptVector b = {2.0, 0.0, 0.0, 0.0};
  EXPECT_DOUBLE_EQ(PredictPercentCorrect(p, t, a, a), 50.0);
  EXPECT_DOUBLE_EQ(PredictPercentCorrect(p, t, a, a, /*interference=*/3.0), 50.0);
  p.lapse_rate = 0.0;
  p.label_loss_per_series = 0.0;  // an explicit swap held for the whole test
  const double straight = PredictPercentCorrect(p, t, a, b);
  EXPECT_GT(straight, 60.0);
  p.label_swap_probability = 1.0;
  EXPECT_NEAR(PredictPercentCorrect(p, t, a, b), 100.0 - straight, 1e-9);
  p.label_swap_probability = 0.0;
  p.lapse_rate = 1.0;
  EXPECT_DOUBLE_EQ(PredictPercentCorrect(p, t, a, b), 50.0);
}

// predicted percent correct of wall `base` against each member of a family
std::vector<double> FamilyPrediction(const Condition& base, const std::vector<Condition>& family,
                                     const ObserverParams& p = {}) {
  ToyStimulusSource source;
  const StudyTest t = MethodTest();
  // the same tap seeds for every wall: only the condition differs
  const PerceptVector a = MeanPerceptVector(p, source, base, 40, 5);
  std::vector<double> out;
  for (const Condition& c : family) {
    out.push_back(PredictPercentCorrect(p, t, a, MeanPerceptVector(p, source, c, 40, 5)));
  }
  return out;
}

void ExpectNonDecreasingFromChance(const std::vector<double>& pc, const std::string& family,
                                   double largest_above) {
  ASSERT_FALSE(pc.empty());
  EXPECT_DOUBLE_EQ(pc.front(), 50.0) << family << ": identical walls";
  for (std::size_t i = 1; i < pc.size(); ++i) {
    EXPECT_GE(pc[i], pc[i - 1] - 1e-9) << family << " member " << i;  // round-off only
  }
  EXPECT_GT(pc.back(), largest_above) << family << ": the largest difference is discriminable";
}

// each family with the default observer (label memory included) and with the label memory off
// (discrimination alone): monotone from chance in both; the largest member is discriminable
// (> 75%) and, with lost labels re-derived from a coarse memory, still well above chance (> 65%)
void ExpectFamily(const Condition& base, const std::vector<Condition>& family,
                  const std::string& name) {
  ExpectNonDecreasingFromChance(FamilyPrediction(base, family), name, 65.0);
  ObserverParams discrimination;
  discrimination.label_loss_per_series = 0.0;
  ExpectNonDecreasingFromChance(FamilyPrediction(base, family, discrimination),
                                name + " (label memory off)", 75.0);
}

TEST(ObserverTest, LargerPhysicalDifferenceNeverLowersPredictedPercentCorrect) {
  std::vector<Condition> stiffer;
  for (double k = 1000.0; k <= 3000.0; k += 50.0) stiffer.push_back(Penalty(k));
  ExpectFamily(Penalty(1000.0), stiffer, "stiffness");

  std::vector<Condition> bouncier;
  for (double e = 0.0; e <= 1.0; e += 0.05) bouncier.push_back(Impulse(e));
  ExpectFamily(Impulse(0.0), bouncier, "restitution");

  std::vector<Condition> lower;
  for (double f = 250.0; f >= 100.0; f -= 10.0) lower.push_back(Train(f));
  ExpectFamily(Train(250.0), lower, "lower train frequency");

  std::vector<Condition> higher;
  for (double f = 250.0; f <= 390.0; f += 10.0) higher.push_back(Train(f));
  ExpectFamily(Train(250.0), higher, "higher train frequency");
}

Protocol TwoWalls(const Condition& a, const Condition& b) {
  json d = {{"name", "pair"},
            {"conditions", {{"a", a.ToJson()}, {"b", b.ToJson()}}},
            {"tests", {{{"name", "t"}, {"conditions", {"a", "b"}}}}}};
  return ParseProtocol(d, "pair");
}

TEST(ObserverTest, SimulatedParticipantsAgreeWithThePrediction) {
  // stimulus without tap variability and no individual differences: the simulation and the
  // analytic prediction describe the same random experiment
  ObserverParams p;
  p.individual_jnd_log_sd = 0.0;
  p.individual_threshold_sd_dB = 0.0;
  ToyStimulusSource source(/*speed_log_sd=*/0.0);
  const Protocol protocol = TwoWalls(Penalty(1000.0), Penalty(1600.0));
  const PerceptVector a = MeanPerceptVector(p, source, protocol.conditions[0], 1, 0);
  const PerceptVector b = MeanPerceptVector(p, source, protocol.conditions[1], 1, 0);
  const double predicted = PredictPercentCorrect(p, protocol.tests[0], a, b);
  EXPECT_GT(predicted, 60.0);
  EXPECT_LT(predicted, 90.0);

  constexpr int kParticipants = 2000;
  int correct = 0;
  int answers = 0;
  for (int i = 0; i < kParticipants; ++i) {
    SimulatedParticipant participant(protocol, p, source,
                                     DeriveSeed(2024, {static_cast<std::uint64_t>(i)}));
    for (const Step& step : MakePlan(protocol, static_cast<std::uint64_t>(i))) {
      if (step.kind != StepKind::kSeries) continue;
      correct += participant.Decide(step) == step.condition ? 1 : 0;
      ++answers;
    }
  }
  const double simulated = 100.0 * correct / answers;
  // 40000 answers, but series of one participant share templates: allow 5 binomial SE (1.1%)
  // plus the quadrature's error (< 0.1%)
  const double se = 100.0 * std::sqrt(0.25 / answers);
  EXPECT_NEAR(simulated, predicted, 5.0 * se + 0.1);
}

TEST(ObserverTest, DecisionsArePureFunctionsOfSeedAndStep) {
  // a hard pair, so that answers depend on the participant's noise
  const Protocol protocol = TwoWalls(Penalty(1000.0), Penalty(1200.0));
  const ObserverParams p;
  ToyStimulusSource source;
  const std::vector<Step> plan = MakePlan(protocol, 3);
  SimulatedParticipant forward(protocol, p, source, 77);
  std::vector<int> in_order;
  for (const Step& s : plan) {
    if (s.kind == StepKind::kSeries) in_order.push_back(forward.Decide(s));
  }
  // a fresh participant asked from the middle (as after a resume) answers the same
  SimulatedParticipant backward(protocol, p, source, 77);
  std::vector<int> reversed;
  for (auto it = plan.rbegin(); it != plan.rend(); ++it) {
    if (it->kind == StepKind::kSeries) reversed.insert(reversed.begin(), backward.Decide(*it));
  }
  EXPECT_EQ(in_order, reversed);
  SimulatedParticipant other(protocol, p, source, 78);
  std::vector<int> other_answers;
  for (const Step& s : plan) {
    if (s.kind == StepKind::kSeries) other_answers.push_back(other.Decide(s));
  }
  EXPECT_NE(in_order, other_answers);
}

TEST(ObserverTest, IndividualDifferencesScaleTheJnd) {
  ObserverParams p;
  ToyStimulusSource source;
  const Protocol protocol = TwoWalls(Train(250.0), Train(100.0));
  std::vector<double> factors;
  for (std::uint64_t s = 0; s < 400; ++s) {
    factors.push_back(std::log(SimulatedParticipant(protocol, p, source, s).jnd_factor()));
  }
  const MeanSd m = ComputeMeanSd(factors);
  // ln(factor) ~ N(0, s^2), s = 0.35: mean SE s / 20, SD SE ~ s / sqrt(800); tolerances 5 SE
  const double s = p.individual_jnd_log_sd;
  EXPECT_EQ(s, 0.35);
  EXPECT_NEAR(m.mean, 0.0, 5.0 * s / 20.0);
  EXPECT_NEAR(m.sd, s, 5.0 * s / std::sqrt(800.0));
  p.individual_jnd_log_sd = 0.0;
  EXPECT_EQ(SimulatedParticipant(protocol, p, source, 9).jnd_factor(), 1.0);
}

TEST(ObserverTest, LabelMemoryClosedForms) {
  ObserverParams p;
  p.label_loss_per_series = 0.05;
  p.label_code_sd_jnd = 4.0;
  // no loss: the explicit swap alone, at every series
  ObserverParams kept = p;
  kept.label_loss_per_series = 0.0;
  kept.label_swap_probability = 0.3;
  EXPECT_DOUBLE_EQ(LabelSwapProbability(kept, 5.0, 0), 0.3);
  EXPECT_DOUBLE_EQ(LabelSwapProbability(kept, 5.0, 19), 0.3);
  // identical walls: a lost association is re-derived by a fair coin
  EXPECT_NEAR(LabelSwapProbability(p, 0.0, 19), 0.5 * (1.0 - std::pow(0.95, 20)), 1e-15);
  // walls sqrt(2) sigma apart: q = Phi(-1) after a loss, weighted by P(lost by series s)
  const double d = std::sqrt(2.0) * 4.0;
  EXPECT_NEAR(LabelSwapProbability(p, d, 0), 0.05 * NormalCdf(-1.0), 1e-15);
  EXPECT_NEAR(LabelSwapProbability(p, d, 9), (1.0 - std::pow(0.95, 10)) * NormalCdf(-1.0), 1e-15);
  p.label_swap_probability = 1.0;  // held swapped until the first loss
  EXPECT_NEAR(LabelSwapProbability(p, d, 9),
              std::pow(0.95, 10) + (1.0 - std::pow(0.95, 10)) * NormalCdf(-1.0), 1e-15);
  p.label_swap_probability = 0.0;
  // similarity of coded memories and the interference it adds to the loss rate
  EXPECT_EQ(LabelSimilarity(p, 0.0), 1.0);
  EXPECT_NEAR(LabelSimilarity(p, d), 2.0 * NormalCdf(-1.0), 1e-15);
  EXPECT_LT(LabelSimilarity(p, 60.0), 1e-12);
  EXPECT_NEAR(LabelLossProbability(p, 0.0), 0.05, 1e-15);
  EXPECT_NEAR(LabelLossProbability(p, 1.5), 1.0 - std::pow(0.95, 2.5), 1e-15);
  p.label_interference = 0.0;
  EXPECT_NEAR(LabelLossProbability(p, 1.5), 0.05, 1e-15);
  // a swap never exceeds chance for swap-free participants, and falls as the walls move apart
  for (double distance = 0.0; distance < 20.0; distance += 0.5) {
    EXPECT_LE(LabelSwapProbability(p, distance + 0.5, 19), LabelSwapProbability(p, distance, 19));
    EXPECT_LE(LabelSwapProbability(p, distance, 19), 0.5);
  }
}

// a protocol of two walls whose templates are nearly exact (100 familiarization taps, no tap
// variability, no encoding noise or drift, no individual differences)
ObserverParams ExactTemplates() {
  ObserverParams p;
  p.individual_jnd_log_sd = 0.0;
  p.individual_threshold_sd_dB = 0.0;
  p.memory_encoding_sd_jnd = 0.0;
  p.memory_drift_sd_jnd_per_series = 0.0;
  p.lapse_rate = 0.0;
  return p;
}

TEST(ObserverTest, SimulatedLabelSwapsFollowTheClosedForm) {
  ObserverParams p = ExactTemplates();
  p.label_loss_per_series = 0.1;
  ToyStimulusSource source(/*speed_log_sd=*/0.0);
  json d = {{"name", "pair"},
            {"familiarization_taps", 100},
            {"conditions", {{"a", Train(250.0).ToJson()}, {"b", Train(150.0).ToJson()}}},
            {"tests", {{{"name", "t"}, {"conditions", {"a", "b"}}}}}};
  const Protocol protocol = ParseProtocol(d, "pair");
  const double distance =
      PerceptDistance(MeanPerceptVector(p, source, protocol.conditions[0], 1, 0),
                      MeanPerceptVector(p, source, protocol.conditions[1], 1, 0));
  ASSERT_GT(distance, 2.0);  // a pair whose re-derived labels swap often enough to measure
  ASSERT_LT(distance, 8.0);
  constexpr int kParticipants = 4000;
  const std::vector<int> series_checked = {0, 4, 19};
  std::vector<int> swaps(series_checked.size(), 0);
  for (int i = 0; i < kParticipants; ++i) {
    SimulatedParticipant participant(protocol, p, source,
                                     DeriveSeed(99, {static_cast<std::uint64_t>(i)}));
    for (std::size_t k = 0; k < series_checked.size(); ++k) {
      swaps[k] += participant.labels_swapped(0, series_checked[k]) ? 1 : 0;
    }
  }
  for (std::size_t k = 0; k < series_checked.size(); ++k) {
    const int series = series_checked[k];
    const int swapped = swaps[k];
    const double expected = LabelSwapProbability(p, distance, series);
    // 4 binomial SE; the templates' own noise (variance 1/100 per axis) moves q by < 0.005
    const double se = std::sqrt(expected * (1.0 - expected) / kParticipants);
    EXPECT_NEAR(static_cast<double>(swapped) / kParticipants, expected, 4.0 * se + 0.005)
        << "series " << series;
  }
}

TEST(ObserverTest, TemplateMemoryDecaysAsTheClosedForm) {
  // template error per axis: familiarization mean (1 / F) + encoding + (s + 1) drift steps
  ObserverParams p = ExactTemplates();
  p.memory_encoding_sd_jnd = 0.5;
  p.memory_drift_sd_jnd_per_series = 0.25;
  ToyStimulusSource source(/*speed_log_sd=*/0.0);
  const Protocol protocol = TwoWalls(Train(250.0), Train(100.0));
  const PerceptVector truth = ToPerceptVector(p, source.RenderTap(protocol.conditions[0], 0));
  constexpr int kParticipants = 2000;
  for (int series : {0, 19}) {
    std::vector<double> errors;
    for (int i = 0; i < kParticipants; ++i) {
      SimulatedParticipant participant(protocol, p, source,
                                       DeriveSeed(7, {static_cast<std::uint64_t>(i)}));
      const PerceptVector m = participant.TemplateAt(0, series, 0);
      for (int k = 0; k < kPerceptDimensions; ++k) errors.push_back(m[k] - truth[k]);
    }
    const MeanSd e = ComputeMeanSd(errors);
    const double variance = 1.0 / 3.0 + 0.25 + (series + 1) * 0.0625;
    // 8000 errors: SE of the variance ~ variance sqrt(2 / 8000); tolerance 5 SE
    EXPECT_NEAR(e.sd * e.sd, variance, 5.0 * variance * std::sqrt(2.0 / 8000.0))
        << "series " << series;
    EXPECT_NEAR(e.mean, 0.0, 5.0 * std::sqrt(variance / 8000.0));
  }
}

TEST(ObserverTest, IndividualThresholdsShiftTheSensationLevel) {
  ObserverParams p = ExactTemplates();
  p.individual_threshold_sd_dB = 5.0;
  ToyStimulusSource source(/*speed_log_sd=*/0.0);
  json d = {{"name", "pair"},
            {"familiarization_taps", 100},
            {"conditions", {{"a", Train(250.0).ToJson()}, {"b", Train(100.0).ToJson()}}},
            {"tests", {{{"name", "t"}, {"conditions", {"a", "b"}}}}}};
  const Protocol protocol = ParseProtocol(d, "pair");
  const PerceptVector nominal = ToPerceptVector(p, source.RenderTap(protocol.conditions[0], 0));
  ASSERT_GT(nominal[1], 10.0);  // far above threshold: the P level moves dB for dB
  std::vector<double> offsets;
  for (std::uint64_t seed = 0; seed < 400; ++seed) {
    SimulatedParticipant participant(protocol, p, source, seed);
    offsets.push_back(participant.threshold_offset_dB());
    // a threshold raised by x dB lowers the P level by x / JND; the template's noise has SD 0.1
    const double p_level = participant.TemplateAt(0, 0, 0)[1];
    EXPECT_NEAR(p_level, nominal[1] - participant.threshold_offset_dB() / p.intensity_jnd_dB, 0.5);
  }
  const MeanSd m = ComputeMeanSd(offsets);
  // offsets ~ N(0, 5^2) dB: mean SE 0.25, SD SE ~0.18; tolerances 5 SE
  EXPECT_NEAR(m.mean, 0.0, 1.25);
  EXPECT_NEAR(m.sd, 5.0, 0.9);
}

TEST(ObserverTest, EarlierWallsThatFeelAlikeInterfereWithTheLabels) {
  // test 2 repeats test 1's first wall under another label: its coded memory competes
  ObserverParams p = ExactTemplates();
  ToyStimulusSource source(/*speed_log_sd=*/0.0);
  json d = {{"name", "two tests"},
            {"familiarization_taps", 100},
            {"conditions",
             {{"a", Train(250.0).ToJson()},
              {"b", Penalty(1000.0).ToJson()},
              {"c", Train(250.0).ToJson()},
              {"d", Train(100.0).ToJson()}}},
            {"tests",
             {{{"name", "first"}, {"conditions", {"a", "b"}}},
              {{"name", "second"}, {"conditions", {"c", "d"}}}}}};
  const Protocol protocol = ParseProtocol(d, "two tests");
  PerceptVector mean[4];
  for (int c = 0; c < 4; ++c) mean[c] = MeanPerceptVector(p, source, protocol.conditions[c], 1, 0);
  // walls a, b of the first test against c, d of the second; a and c are the same wall
  double expected = 0.0;
  for (int earlier : {0, 1}) {
    for (int now : {2, 3})
      expected += LabelSimilarity(p, PerceptDistance(mean[earlier], mean[now]));
  }
  EXPECT_GT(expected, 1.0);  // at least the identical pair
  for (std::uint64_t seed = 0; seed < 20; ++seed) {
    SimulatedParticipant participant(protocol, p, source, seed);
    EXPECT_EQ(participant.interference(0), 0.0);  // nothing came before the first test
    // the templates' noise (SD 0.1 per axis) moves each similarity by < 0.03
    EXPECT_NEAR(participant.interference(1), expected, 0.1);
  }
  // the prediction uses the same interference, so the second test is predicted lower than the
  // same pair without a history
  const double with_history =
      PredictPercentCorrect(p, protocol.tests[1], mean[2], mean[3], expected);
  const double alone = PredictPercentCorrect(p, protocol.tests[1], mean[2], mean[3]);
  EXPECT_LT(with_history, alone - 0.5);
}

TEST(ObserverTest, ParametersParseWithNamedErrors) {
  const ObserverParams defaults;
  const ObserverParams same = ParseObserverParams(defaults.ToJson(), "observer.json");
  EXPECT_EQ(same.ToJson(), defaults.ToJson());
  const ObserverParams changed =
      ParseObserverParams(json{{"lapse_rate", 0.1}, {"intensity_jnd_dB", 2.0}}, "o.json");
  EXPECT_EQ(changed.lapse_rate, 0.1);
  EXPECT_EQ(changed.intensity_jnd_dB, 2.0);
  EXPECT_EQ(changed.frequency_weber_fraction, defaults.frequency_weber_fraction);
  try {
    ParseObserverParams(json{{"lapse", 0.1}}, "o.json");
    FAIL();
  } catch (const Error& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("o.json: unknown field \"lapse\"; valid fields: "), std::string::npos) << m;
    EXPECT_NE(m.find("lapse_rate"), std::string::npos) << m;
  }
  try {
    ParseObserverParams(json{{"lapse_rate", 1.5}}, "o.json");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("lapse_rate: 1.5 is out of range; valid: >= 0 and <= 1"),
              std::string::npos)
        << e.what();
  }
  try {
    ParseObserverParams(json{{"lapse_rate", "high"}}, "o.json");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("o.json: lapse_rate: expected a number, got a string"),
              std::string::npos)
        << e.what();
  }
  EXPECT_THROW(ParseObserverParams(json{{"intensity_jnd_dB", 0}}, "o.json"), Error);
  EXPECT_THROW(ParseObserverParams(json{{"non_pacinian_corner_hz", 300}}, "o.json"), Error);
}

TEST(ObserverTest, ParameterFilesAreReadStrictly) {
  testing::ScratchDir dir;
  const std::string path = dir.File("observer.json");
  testing::WriteFile(path, R"({"lapse_rate": 0.1})");
  EXPECT_EQ(LoadObserverParams(path).lapse_rate, 0.1);
  testing::WriteFile(path, R"({"lapse_rate": 1e400})");
  try {
    LoadObserverParams(path);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("observer.json: lapse_rate: 1e400 is not a finite number"),
              std::string::npos)
        << e.what();
  }
  EXPECT_THROW(LoadObserverParams(dir.File("missing.json")), Error);
}

}  // namespace
}  // namespace rigidtouch::study
