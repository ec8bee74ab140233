#include "study/observer.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <numeric>

#include "base/text.h"
#include "io/strict_json.h"
#include "rigidtouch/types.h"
#include "study/random.h"
#include "study/statistics.h"

namespace rigidtouch::study {

namespace {

using nlohmann::json;
using text::FormatNumber;

// stream tags: every random decision of a participant has its own derived seed
enum Stream : std::uint64_t {
  kFamiliarizationTaps = 11,
  kFamiliarizationNoise = 12,
  kEncoding = 13,
  kDrift = 14,
  kSeriesTaps = 15,
  kSeriesNoise = 16,
  kLapse = 17,
  kSwap = 18,
  kIndividual = 19,
  kThreshold = 20,
  kLabelLoss = 21,
  kLabelCode = 22,
};

struct ParamSpec {
  const char* name;
  double ObserverParams::*member;
  double lo;
  bool lo_open;  // lo excluded
  double hi;
};

constexpr double kInf = std::numeric_limits<double>::infinity();

PerceptVector Add(const PerceptVector& a, const PerceptVector& b) {
  PerceptVector sum{};
  for (int i = 0; i < kPerceptDimensions; ++i) sum[i] = a[i] + b[i];
  return sum;
}

// The labels re-derived after the association was lost: labels[c] is the template the label of
// condition c is attached to. The participant recalls a coded memory of each wall, its template
// plus noise sigma per axis (its own draw per wall), and attaches the labels so that the codes
// lie nearest their templates overall (the permutation of least summed squared distance; ties
// broken at random). Two conditions: the sign test (D + e) . D of the closed form
// (LabelSwapProbability), e the difference of the two codes' noises, which is that rule.
std::vector<int> RederiveLabels(const std::vector<PerceptVector>& templates, double sigma,
                                Rng& code) {
  const int k = static_cast<int>(templates.size());
  if (k == 2) {
    double along = 0.0;  // (D + e_1 - e_0) . D
    for (int i = 0; i < kPerceptDimensions; ++i) {
      const double d = templates[1][i] - templates[0][i];
      const double e = sigma * (code.Normal() - code.Normal());
      along += (d + e) * d;
    }
    // exactly on the boundary (identical templates): a fair coin
    const bool swapped = along < 0.0 || (along == 0.0 && code.Bernoulli(0.5));
    return swapped ? std::vector<int>{1, 0} : std::vector<int>{0, 1};
  }
  std::vector<PerceptVector> codes(k);
  for (int c = 0; c < k; ++c) {
    for (int i = 0; i < kPerceptDimensions; ++i)
      codes[c][i] = templates[c][i] + sigma * code.Normal();
  }
  std::vector<int> perm(k);
  std::iota(perm.begin(), perm.end(), 0);
  std::vector<std::vector<int>> best;
  double best_cost = kInf;
  do {  // k <= 8: at most 40320 assignments
    double cost = 0.0;
    for (int c = 0; c < k; ++c) {
      const double d = PerceptDistance(codes[c], templates[perm[c]]);
      cost += d * d;
    }
    if (cost < best_cost) best.clear();
    if (cost <= best_cost) {
      best_cost = cost;
      best.push_back(perm);
    }
  } while (std::next_permutation(perm.begin(), perm.end()));
  return best.size() == 1 ? best.front() : best[code.Below(best.size())];
}

const ParamSpec kParamSpecs[] = {
    {"intensity_jnd_dB", &ObserverParams::intensity_jnd_dB, 0.0, true, kInf},
    {"frequency_weber_fraction", &ObserverParams::frequency_weber_fraction, 0.0, true, kInf},
    {"pacinian_best_frequency_hz", &ObserverParams::pacinian_best_frequency_hz, 0.0, true, kInf},
    {"pacinian_low_slope_dB_per_octave", &ObserverParams::pacinian_low_slope_dB_per_octave, 0.0,
     false, kInf},
    {"pacinian_high_slope_dB_per_octave", &ObserverParams::pacinian_high_slope_dB_per_octave, 0.0,
     false, kInf},
    {"non_pacinian_corner_hz", &ObserverParams::non_pacinian_corner_hz, 0.0, true, kInf},
    {"non_pacinian_high_slope_dB_per_octave",
     &ObserverParams::non_pacinian_high_slope_dB_per_octave, 0.0, false, kInf},
    {"vibration_threshold_rms_N", &ObserverParams::vibration_threshold_rms_N, 0.0, true, kInf},
    {"pitch_salience_dB", &ObserverParams::pitch_salience_dB, 0.0, true, kInf},
    {"onset_floor_N", &ObserverParams::onset_floor_N, 0.0, true, kInf},
    {"memory_encoding_sd_jnd", &ObserverParams::memory_encoding_sd_jnd, 0.0, false, kInf},
    {"memory_drift_sd_jnd_per_series", &ObserverParams::memory_drift_sd_jnd_per_series, 0.0, false,
     kInf},
    {"label_swap_probability", &ObserverParams::label_swap_probability, 0.0, false, 1.0},
    {"lapse_rate", &ObserverParams::lapse_rate, 0.0, false, 1.0},
    {"individual_jnd_log_sd", &ObserverParams::individual_jnd_log_sd, 0.0, false, kInf},
    {"individual_threshold_sd_dB", &ObserverParams::individual_threshold_sd_dB, 0.0, false, kInf},
    {"label_loss_per_series", &ObserverParams::label_loss_per_series, 0.0, false, 1.0},
    {"label_code_sd_jnd", &ObserverParams::label_code_sd_jnd, 0.0, false, kInf},
    {"label_interference", &ObserverParams::label_interference, 0.0, false, kInf},
};

std::string RangeText(const ParamSpec& spec) {
  std::string text = spec.lo_open ? "> " : ">= ";
  text += text::FormatNumber(spec.lo);
  if (std::isfinite(spec.hi)) text += " and <= " + text::FormatNumber(spec.hi);
  return text;
}

void RequireParams(bool ok, const std::string& message) {
  if (!ok) throw Error(message);
}

// Simpson weights for n (even) intervals of width h
std::vector<double> SimpsonWeights(int n, double h) {
  std::vector<double> w(n + 1);
  for (int i = 0; i <= n; ++i) w[i] = (i == 0 || i == n) ? 1.0 : (i % 2 == 1 ? 4.0 : 2.0);
  for (double& x : w) x *= h / 3.0;
  return w;
}

}  // namespace

nlohmann::json ObserverParams::ToJson() const {
  json j = json::object();
  for (const ParamSpec& spec : kParamSpecs) j[spec.name] = this->*spec.member;
  return j;
}

ObserverParams ParseObserverParams(const nlohmann::json& document, std::string_view source) {
  const io::JsonSource src(source);
  std::vector<std::string> valid;
  for (const ParamSpec& spec : kParamSpecs) valid.emplace_back(spec.name);
  const io::StrictObject in(src, document, "", valid, "an object of observer parameters");
  ObserverParams params;
  for (const ParamSpec& spec : kParamSpecs) {
    const std::optional<double> v = in.Number(spec.name);  // finite
    if (!v) continue;
    if (!((spec.lo_open ? *v > spec.lo : *v >= spec.lo) && *v <= spec.hi)) {
      in.FailAt(spec.name, text::FormatNumber(*v) + " is out of range; valid: " + RangeText(spec));
    }
    params.*(spec.member) = *v;
  }
  if (params.non_pacinian_corner_hz >= params.pacinian_best_frequency_hz) {
    in.FailAt("non_pacinian_corner_hz", text::FormatNumber(params.non_pacinian_corner_hz) +
                                            " must be below pacinian_best_frequency_hz (" +
                                            text::FormatNumber(params.pacinian_best_frequency_hz) +
                                            ")");
  }
  return params;
}

ObserverParams LoadObserverParams(const std::string& path) {
  return ParseObserverParams(io::ReadJsonFile(path, "observer parameter file"), path);
}

double PacinianGain_dB(const ObserverParams& p, double frequency_hz) {
  const double octaves = std::log2(frequency_hz / p.pacinian_best_frequency_hz);
  return octaves < 0.0 ? p.pacinian_low_slope_dB_per_octave * octaves
                       : -p.pacinian_high_slope_dB_per_octave * octaves;
}

double NonPacinianGain_dB(const ObserverParams& p, double frequency_hz) {
  // flat below the corner, where it equals the P channel (the channels cross there)
  const double level_dB = PacinianGain_dB(p, p.non_pacinian_corner_hz);
  if (frequency_hz <= p.non_pacinian_corner_hz) return level_dB;
  return level_dB - p.non_pacinian_high_slope_dB_per_octave *
                        std::log2(frequency_hz / p.non_pacinian_corner_hz);
}

std::array<double, kPerceptBands> PerceptBandCentres_hz() {
  // band limits 10 Hz (bottom of NP I) and 800 Hz (top of the P channel's range)
  return {std::sqrt(10.0 * 40.0), std::sqrt(40.0 * 100.0), std::sqrt(100.0 * 400.0),
          std::sqrt(400.0 * 800.0)};
}

PerceptVector ToPerceptVector(const ObserverParams& p, const TapPercept& percept) {
  auto ok = [](double v) { return std::isfinite(v) && v >= 0.0; };
  RequireParams(
      ok(percept.peak_force_N) && ok(percept.vibration_rms_N) && ok(percept.dominant_frequency_hz),
      "stimulus source returned a tap percept with a negative or non-finite force or "
      "frequency");
  RequireParams(std::isfinite(percept.periodicity) && percept.periodicity >= 0.0 &&
                    percept.periodicity <= 1.0,
                "stimulus source returned a tap percept with a periodicity outside [0, 1]");
  double fraction_sum = 0.0;
  for (double f : percept.band_energy_fraction) {
    RequireParams(ok(f), "stimulus source returned a negative or non-finite band energy fraction");
    fraction_sum += f;
  }

  PerceptVector v{};
  const double onset_N = std::max(percept.peak_force_N, p.onset_floor_N);
  v[0] = 20.0 * std::log10(onset_N) / p.intensity_jnd_dB;

  double sl_p_dB = 0.0;
  double sl_np_dB = 0.0;
  if (percept.vibration_rms_N > 0.0 && fraction_sum > 0.0) {
    const auto centres = PerceptBandCentres_hz();
    double gain_p = 0.0;
    double gain_np = 0.0;
    for (int b = 0; b < kPerceptBands; ++b) {
      const double share = percept.band_energy_fraction[b] / fraction_sum;
      gain_p += share * std::pow(10.0, PacinianGain_dB(p, centres[b]) / 10.0);
      gain_np += share * std::pow(10.0, NonPacinianGain_dB(p, centres[b]) / 10.0);
    }
    const double level_dB =
        20.0 * std::log10(percept.vibration_rms_N / p.vibration_threshold_rms_N);
    // below threshold a channel reads 0 dB SL whatever the stimulus
    sl_p_dB = std::max(0.0, level_dB + 10.0 * std::log10(gain_p));
    sl_np_dB = std::max(0.0, level_dB + 10.0 * std::log10(gain_np));
  }
  v[1] = sl_p_dB / p.intensity_jnd_dB;
  v[2] = sl_np_dB / p.intensity_jnd_dB;

  // a pitch only where the transient is periodic; a click has none (its spectrum is flat) and
  // sits at the pitch axis's origin with no periodicity: not at 250 Hz, not at the press's
  // frequency
  if (percept.dominant_frequency_hz > 0.0) {
    const double salience = std::clamp(std::max(sl_p_dB, sl_np_dB) / p.pitch_salience_dB, 0.0, 1.0);
    v[3] = salience * std::log(percept.dominant_frequency_hz / kPitchAxisOrigin_hz) /
           std::log1p(p.frequency_weber_fraction);
    v[4] = salience * percept.periodicity * p.pitch_salience_dB / p.intensity_jnd_dB;
  }
  return v;
}

double PerceptDistance(const PerceptVector& a, const PerceptVector& b) {
  double s = 0.0;
  for (int i = 0; i < kPerceptDimensions; ++i) s += (a[i] - b[i]) * (a[i] - b[i]);
  return std::sqrt(s);
}

double NearestTemplateProbabilityCorrect(double distance, double series_variance,
                                         double template_variance, int dimensions) {
  if (!(distance > 0.0)) return 0.5;  // identical walls: symmetric, exactly chance
  const double beta = std::sqrt(4.0 * series_variance + 2.0 * template_variance);
  const double alpha = std::sqrt(2.0 * template_variance);
  const double c = beta > 0.0 ? distance / beta : kInf;
  if (alpha == 0.0) return NormalCdf(c);
  const double t = distance / alpha;
  if (dimensions <= 1) return NormalCdf(c) * NormalCdf(t) + NormalCdf(-c) * NormalCdf(-t);

  // u = P1 / alpha ~ N(t, 1) along the difference, r = |P_perp| / alpha ~ chi(k), k = dims - 1
  const int k = dimensions - 1;
  // 200 x 100 Simpson intervals: within 1e-7 of a 1200 x 600 grid over the range of use
  constexpr int kU = 200;
  constexpr int kR = 100;
  constexpr double kSpan = 9.0;
  const double hu = 2.0 * kSpan / kU;
  const double r_max = std::sqrt(static_cast<double>(k)) + kSpan;
  const double hr = r_max / kR;
  const std::vector<double> wu = SimpsonWeights(kU, hu);
  const std::vector<double> wr = SimpsonWeights(kR, hr);
  const double log_norm = (k / 2.0 - 1.0) * std::log(2.0) + std::lgamma(k / 2.0);
  std::vector<double> r_weight(kR + 1);
  std::vector<double> r_value(kR + 1);
  for (int j = 0; j <= kR; ++j) {
    const double r = j * hr;
    r_value[j] = r;
    const double density = r > 0.0 ? std::exp((k - 1) * std::log(r) - 0.5 * r * r - log_norm)
                                   : (k == 1 ? 1.0 / std::exp(log_norm) : 0.0);
    r_weight[j] = wr[j] * density;
  }
  double total = 0.0;
  double weight_sum = 0.0;
  for (int i = 0; i <= kU; ++i) {
    const double z = -kSpan + i * hu;
    const double u = t + z;
    const double wz = wu[i] * std::exp(-0.5 * z * z) / std::sqrt(2.0 * std::numbers::pi);
    double inner = 0.0;
    double inner_weight = 0.0;
    for (int j = 0; j <= kR; ++j) {
      const double norm = std::hypot(u, r_value[j]);
      const double cosine = norm > 0.0 ? u / norm : 0.0;
      inner += r_weight[j] * NormalCdf(c * cosine);
      inner_weight += r_weight[j];
    }
    total += wz * inner;
    weight_sum += wz * inner_weight;
  }
  // normalising by the quadrature's own mass keeps the result a true average of values in [0, 1]
  return total / weight_sum;
}

double LabelSimilarity(const ObserverParams& params, double distance) {
  const double sigma = params.label_code_sd_jnd;
  if (!(distance > 0.0)) return 1.0;
  return sigma > 0.0 ? 2.0 * NormalCdf(-distance / (std::sqrt(2.0) * sigma)) : 0.0;
}

double LabelLossProbability(const ObserverParams& params, double interference) {
  return 1.0 - std::pow(1.0 - params.label_loss_per_series,
                        1.0 + params.label_interference * interference);
}

double LabelSwapProbability(const ObserverParams& params, double distance, int series,
                            double interference) {
  // the coded memories of the two walls differ by D + e, e ~ N(0, 2 sigma^2 I); the labels come
  // out swapped when (D + e) . D < 0, i.e. when e's component along D is below -|D|
  const double sigma = params.label_code_sd_jnd;
  const double q = !(distance > 0.0) ? 0.5
                   : sigma > 0.0     ? NormalCdf(-distance / (std::sqrt(2.0) * sigma))
                                     : 0.0;
  const double kept = std::pow(1.0 - LabelLossProbability(params, interference), series + 1);
  return kept * params.label_swap_probability + (1.0 - kept) * q;
}

double PredictPercentCorrect(const ObserverParams& params, const StudyTest& test,
                             const PerceptVector& a, const PerceptVector& b, double interference) {
  const double distance = PerceptDistance(a, b);
  const double series_variance = 1.0 / test.taps_per_series;
  const double lapse = params.lapse_rate;
  double sum = 0.0;
  for (int s = 0; s < test.series; ++s) {
    const double template_variance =
        1.0 / test.familiarization_taps +
        params.memory_encoding_sd_jnd * params.memory_encoding_sd_jnd +
        (s + 1) * params.memory_drift_sd_jnd_per_series * params.memory_drift_sd_jnd_per_series;
    const double pc = NearestTemplateProbabilityCorrect(distance, series_variance,
                                                        template_variance, kPerceptDimensions);
    const double q = LabelSwapProbability(params, distance, s, interference);
    sum += 0.5 * lapse + (1.0 - lapse) * (q * (1.0 - pc) + (1.0 - q) * pc);
  }
  return 100.0 * sum / test.series;
}

PerceptVector MeanPerceptVector(const ObserverParams& params, StimulusSource& source,
                                const Condition& condition, int taps, std::uint64_t seed) {
  PerceptVector mean{};
  for (int j = 0; j < taps; ++j) {
    const PerceptVector v = ToPerceptVector(
        params, source.RenderTap(condition, DeriveSeed(seed, {static_cast<std::uint64_t>(j)})));
    for (int i = 0; i < kPerceptDimensions; ++i) mean[i] += v[i] / taps;
  }
  return mean;
}

SimulatedParticipant::SimulatedParticipant(const Protocol& protocol, const ObserverParams& params,
                                           StimulusSource& source, std::uint64_t seed)
    : protocol_(protocol), params_(params), source_(source), seed_(seed) {
  Rng rng(DeriveSeed(seed_, {kIndividual}));
  jnd_factor_ = std::exp(params_.individual_jnd_log_sd * rng.Normal());
  // a participant's detection threshold sits individual_threshold_sd_dB * z above the nominal one
  // (its own stream, so the JND factor of a seed does not depend on this parameter)
  Rng threshold(DeriveSeed(seed_, {kThreshold}));
  threshold_offset_dB_ = params_.individual_threshold_sd_dB * threshold.Normal();
  params_.vibration_threshold_rms_N *= std::pow(10.0, threshold_offset_dB_ / 20.0);
  for (const Step& step : MakePlan(protocol_, seed_)) {
    if (test_order_.empty() || test_order_.back() != step.test) test_order_.push_back(step.test);
  }
}

void SimulatedParticipant::Present(const Condition& /*condition*/, int /*taps*/) {
  // the simulated hand taps when the observer is asked (or builds its memory); nothing to render
}

std::string SimulatedParticipant::Describe() const {
  return "simulated participant: " + source_.Describe();
}

void SimulatedParticipant::Show(std::string_view /*text*/) {}

std::optional<int> SimulatedParticipant::Ask(const Protocol& /*protocol*/, const Step& step) {
  return Decide(step);
}

bool SimulatedParticipant::labels_swapped(int test) const {
  Rng rng(DeriveSeed(seed_, {kSwap, static_cast<std::uint64_t>(test)}));
  return rng.Bernoulli(params_.label_swap_probability);
}

std::vector<int> SimulatedParticipant::InitialLabels(int test) const {
  const int k = static_cast<int>(protocol_.tests[test].conditions.size());
  std::vector<int> labels(k);
  std::iota(labels.begin(), labels.end(), 0);
  Rng rng(DeriveSeed(seed_, {kSwap, static_cast<std::uint64_t>(test)}));
  if (!rng.Bernoulli(params_.label_swap_probability)) return labels;
  // a swapped pair: with two conditions the two labels, with more a pair drawn at random
  const auto a = static_cast<int>(k == 2 ? 0 : rng.Below(k));
  const auto b = static_cast<int>(k == 2 ? 1 : (a + 1 + rng.Below(k - 1)) % k);
  std::swap(labels[a], labels[b]);
  return labels;
}

PerceptVector SimulatedParticipant::FeltMean(const Condition& condition, int taps,
                                             std::uint64_t tap_stream, std::uint64_t noise_stream) {
  PerceptVector mean{};
  for (int j = 0; j < taps; ++j) {
    const auto jj = static_cast<std::uint64_t>(j);
    const TapPercept percept = source_.RenderTap(condition, DeriveSeed(tap_stream, {jj}));
    const PerceptVector v = ToPerceptVector(params_, percept);
    Rng noise(DeriveSeed(noise_stream, {jj}));
    // a participant with a larger JND has the same noise on a compressed scale
    for (int i = 0; i < kPerceptDimensions; ++i) {
      mean[i] += (v[i] / jnd_factor_ + noise.Normal()) / taps;
    }
  }
  return mean;
}

const SimulatedParticipant::Memory& SimulatedParticipant::MemoryOf(int test) {
  auto found = memories_.find(test);
  if (found != memories_.end()) return found->second;
  const StudyTest& t = protocol_.tests[test];
  const int k = static_cast<int>(t.conditions.size());
  const auto tt = static_cast<std::uint64_t>(test);
  Memory memory;
  memory.templates.resize(k);
  for (int c = 0; c < k; ++c) {
    const auto cc = static_cast<std::uint64_t>(c);
    const Condition& condition = protocol_.conditions[t.conditions[c]];
    memory.templates[c] = FeltMean(condition, t.familiarization_taps,
                                   DeriveSeed(seed_, {kFamiliarizationTaps, tt, cc}),
                                   DeriveSeed(seed_, {kFamiliarizationNoise, tt, cc}));
    Rng encoding(DeriveSeed(seed_, {kEncoding, tt, cc}));
    for (double& x : memory.templates[c]) x += params_.memory_encoding_sd_jnd * encoding.Normal();
  }
  memory.drift.assign(t.series, std::vector<PerceptVector>(k));
  for (int c = 0; c < k; ++c) {
    Rng drift(DeriveSeed(seed_, {kDrift, tt, static_cast<std::uint64_t>(c)}));
    PerceptVector walk{};
    for (int s = 0; s < t.series; ++s) {
      for (double& x : walk) x += params_.memory_drift_sd_jnd_per_series * drift.Normal();
      memory.drift[s][c] = walk;
    }
  }
  // walls of the tests before this one that are not in it compete for its labels
  for (int earlier : test_order_) {
    if (earlier == test) break;
    const StudyTest& e = protocol_.tests[earlier];
    for (std::size_t ec = 0; ec < e.conditions.size(); ++ec) {
      const int other_condition = e.conditions[ec];
      if (std::find(t.conditions.begin(), t.conditions.end(), other_condition) !=
          t.conditions.end()) {
        continue;
      }
      const PerceptVector other = MemoryOf(earlier).templates[ec];
      for (int c = 0; c < k; ++c) {
        memory.interference +=
            LabelSimilarity(params_, PerceptDistance(memory.templates[c], other));
      }
    }
  }
  // label memory: the association of labels and templates is lost with probability h before each
  // series; the participant then re-derives it from the coded memory of each wall
  // (RederiveLabels), and keeps the result until the next loss
  const double loss_probability = LabelLossProbability(params_, memory.interference);
  memory.labels.resize(t.series);
  std::vector<int> labels = InitialLabels(test);
  for (int s = 0; s < t.series; ++s) {
    const auto ss = static_cast<std::uint64_t>(s);
    Rng loss(DeriveSeed(seed_, {kLabelLoss, tt, ss}));
    if (loss.Bernoulli(loss_probability)) {
      Rng code(DeriveSeed(seed_, {kLabelCode, tt, ss}));
      std::vector<PerceptVector> now(k);
      for (int c = 0; c < k; ++c) now[c] = Add(memory.templates[c], memory.drift[s][c]);
      labels = RederiveLabels(now, params_.label_code_sd_jnd, code);
    }
    memory.labels[s] = labels;
  }
  return memories_.emplace(test, std::move(memory)).first->second;
}

int SimulatedParticipant::Decide(const Step& step) {
  const StudyTest& t = protocol_.tests[step.test];
  const int k = static_cast<int>(t.conditions.size());
  const auto tt = static_cast<std::uint64_t>(step.test);
  const auto ss = static_cast<std::uint64_t>(step.series);
  const Condition& condition = protocol_.conditions[t.conditions[step.condition]];
  const PerceptVector felt =
      FeltMean(condition, step.taps, DeriveSeed(seed_, {kSeriesTaps, tt, ss}),
               DeriveSeed(seed_, {kSeriesNoise, tt, ss}));
  Rng lapse(DeriveSeed(seed_, {kLapse, tt, ss}));
  if (lapse.Bernoulli(params_.lapse_rate)) return static_cast<int>(lapse.Below(k));

  // the nearest of the k remembered templates (the first on a tie), named by the label the
  // participant holds for it
  const Memory& memory = MemoryOf(step.test);
  int nearest = 0;
  double nearest_distance = kInf;
  for (int c = 0; c < k; ++c) {
    const double d = PerceptDistance(felt, Add(memory.templates[c], memory.drift[step.series][c]));
    if (d < nearest_distance) {
      nearest = c;
      nearest_distance = d;
    }
  }
  const std::vector<int>& labels = memory.labels[step.series];
  return static_cast<int>(std::find(labels.begin(), labels.end(), nearest) - labels.begin());
}

double SimulatedParticipant::interference(int test) {
  return MemoryOf(test).interference;
}

bool SimulatedParticipant::labels_swapped(int test, int series) {
  const std::vector<int>& labels = MemoryOf(test).labels.at(series);
  for (std::size_t c = 0; c < labels.size(); ++c) {
    if (labels[c] != static_cast<int>(c)) return true;
  }
  return false;
}

const std::vector<int>& SimulatedParticipant::LabelsAt(int test, int series) {
  return MemoryOf(test).labels.at(series);
}

PerceptVector SimulatedParticipant::TemplateAt(int test, int series, int condition) {
  const Memory& memory = MemoryOf(test);
  return Add(memory.templates.at(condition), memory.drift.at(series).at(condition));
}

}  // namespace rigidtouch::study
