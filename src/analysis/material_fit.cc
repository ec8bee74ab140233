#include "analysis/material_fit.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <numeric>

#include "analysis/spectrum.h"
#include "base/text.h"
#include "rigidtouch/types.h"

namespace rigidtouch::analysis {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;
constexpr int kMinPreContactSamples = 8;
constexpr double kMinPeriodsAfterOnset = 3.0;
constexpr double kOnsetPeakOverNoise = 8.0;  // a tap stands out of the noise by this much
constexpr double kOnsetEdgeOverNoise = 3.0;  // the onset: where the first lobe leaves the noise
constexpr int kMinSamplesAtExtreme = 3;      // clipped: this many samples at the extreme value
constexpr double kWindowDecays = 5.0;        // fit window: 5 / B after the onset (e^-5, 0.7 %)

struct TapContext {
  const io::TapRecording& recording;
  const io::RecordedTap& tap;
};

[[noreturn]] void TapFail(const TapContext& c, int line, const std::string& message) {
  throw Error(c.recording.path + ":" + std::to_string(line) + ": tap " + std::to_string(c.tap.tap) +
              ": " + message);
}

double FitMedian(std::vector<double> v) {
  const std::size_t mid = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(mid), v.end());
  return v[mid];
}

std::string FitNum(double v) {
  return text::FormatNumber(v);
}

// the sample rate from the median interval; refuses intervals that differ from it by over 10 %
double TapSampleRate(const TapContext& c) {
  const std::vector<double>& t = c.tap.time_s;
  std::vector<double> dt(t.size() - 1);
  for (std::size_t i = 1; i < t.size(); ++i) dt[i - 1] = t[i] - t[i - 1];
  const double h = FitMedian(dt);
  for (std::size_t i = 0; i < dt.size(); ++i) {
    if (std::abs(dt[i] - h) > 0.1 * h) {
      TapFail(c, c.tap.line[i + 1],
              "irregular sampling: interval " + FitNum(dt[i]) + " s differs from the median " +
                  FitNum(h) + " s by over 10 %; resample the recording uniformly");
    }
  }
  return 1.0 / h;
}

// a flat top: kMinSamplesAtExtreme or more samples exactly at the largest or the smallest value
// (a saturated sensor or a clipping converter repeats its rail value)
void CheckTapClipping(const TapContext& c) {
  const std::vector<double>& x = c.tap.signal;
  const auto [lo, hi] = std::minmax_element(x.begin(), x.end());
  for (const double rail : {*hi, *lo}) {
    std::vector<std::size_t> at;
    for (std::size_t i = 0; i < x.size(); ++i) {
      if (x[i] == rail) at.push_back(i);
    }
    if (static_cast<int>(at.size()) < kMinSamplesAtExtreme || *hi == *lo) continue;
    const double percent = 100.0 * static_cast<double>(at.size()) / static_cast<double>(x.size());
    TapFail(c, c.tap.line[at.front()],
            "clipped (saturated): " + std::to_string(at.size()) + " samples (" + FitNum(percent) +
                " %) sit at the extreme value " + FitNum(rail) + " " +
                std::string(io::TapQuantityUnit(c.recording.quantity)) + ", the first on line " +
                std::to_string(c.tap.line[at.front()]) + " and the last on line " +
                std::to_string(c.tap.line[at.back()]) +
                "; the peak is lost: record with a larger sensor range");
  }
}

struct TapOnset {
  std::size_t index = 0;  // the first sample of the first lobe
  double baseline = 0.0;  // the pre-contact median
  double noise = 0.0;     // the pre-contact noise (1.4826 MAD)
};

// the onset detector (docs/materials.md): on the signal through a 3-sample running median (which
// removes a one-sample spike and keeps a sinusoid sampled at 4 or more samples a period), the
// sample p of the largest deviation from the first sample; the baseline and the noise from the
// first half of the raw samples before p (median, 1.4826 x median absolute deviation); a tap when
// |y_p - baseline| >= 8 noise; the onset is the first sample of the run, ending at p, of samples on
// p's side of the baseline by more than 3 noise. Noise before the tap is not joined to that run,
// so it cannot move the onset.
TapOnset DetectTapOnset(const TapContext& c) {
  const std::vector<double>& x = c.tap.signal;
  std::vector<double> y = x;
  for (std::size_t i = 1; i + 1 < x.size(); ++i) {
    y[i] = std::max(std::min(x[i - 1], x[i]), std::min(std::max(x[i - 1], x[i]), x[i + 1]));
  }
  const double first = y.front();
  std::size_t p = 0;
  for (std::size_t i = 0; i < y.size(); ++i) {
    if (std::abs(y[i] - first) > std::abs(y[p] - first)) p = i;
  }
  const std::size_t quiet = p / 2;
  if (static_cast<int>(quiet) < kMinPreContactSamples) {
    TapFail(c, c.tap.line.front(),
            "too short before the contact: " + std::to_string(p) +
                " samples before the largest deviation; record at least " +
                std::to_string(2 * kMinPreContactSamples) + " before the tap");
  }
  TapOnset o;
  std::vector<double> pre(x.begin(), x.begin() + static_cast<std::ptrdiff_t>(quiet));
  o.baseline = FitMedian(pre);
  for (double& v : pre) v = std::abs(v - o.baseline);
  o.noise = 1.4826 * FitMedian(pre);
  // re-centre on the baseline: the largest deviation from it
  for (std::size_t i = quiet; i < y.size(); ++i) {
    if (std::abs(y[i] - o.baseline) > std::abs(y[p] - o.baseline)) p = i;
  }
  const double peak = std::abs(y[p] - o.baseline);
  const double floor = std::max(o.noise, 1e-12 * std::max(1.0, std::abs(o.baseline)));
  if (peak < kOnsetPeakOverNoise * floor) {
    TapFail(c, c.tap.line.front(),
            "no contact onset: the largest deviation from the pre-contact level, " + FitNum(peak) +
                " " + std::string(io::TapQuantityUnit(c.recording.quantity)) + ", is " +
                FitNum(peak / floor) + " times the pre-contact noise (a tap stands out by " +
                FitNum(kOnsetPeakOverNoise) + ")");
  }
  const double sign = y[p] > o.baseline ? 1.0 : -1.0;
  std::size_t i = p;
  while (i > quiet && sign * (y[i - 1] - o.baseline) > kOnsetEdgeOverNoise * floor) --i;
  o.index = i;
  o.noise = floor;
  return o;
}

// spectral first guess of f (the dominant bin of the signal from the onset, spectrum.h), B from
// the transient's energy (for a e^(-Bt) sin: integral of x^2 ~ a^2 / (4 B)) and a from the peak
struct SinusoidGuess {
  double frequency_hz = 0.0, decay_per_s = 0.0, amplitude = 0.0;
};

SinusoidGuess SinusoidFirstGuess(const std::vector<double>& x, std::size_t from, double baseline,
                                 double rate) {
  std::vector<double> y(x.begin() + static_cast<std::ptrdiff_t>(from), x.end());
  for (double& v : y) v -= baseline;
  SpectrumOptions so;
  so.window = SpectrumOptions::Window::kTaperedEnd;  // the transient starts at the first sample
  so.remove_mean = false;
  so.min_fft_length = 8192;
  SinusoidGuess g;
  g.frequency_hz = DominantFrequencyHz(PowerSpectrum(y, rate, so));
  double peak = 0.0, energy = 0.0;
  for (const double v : y) {
    if (std::abs(v) > std::abs(peak)) peak = v;
    energy += v * v / rate;
  }
  g.amplitude = peak;
  g.decay_per_s = energy > 0.0 ? peak * peak / (4.0 * energy) : 1.0;
  return g;
}

// the model a e^(-B tau) sin(2 pi f tau), tau = t - t0, zero before t0, and its Jacobian row
// with respect to p = (a, B, f, t0)
double SinusoidModel(const Eigen::Vector4d& p, double t, Eigen::RowVector4d* row) {
  const double tau = t - p[3];
  if (tau <= 0.0) {
    if (row) row->setZero();
    return 0.0;
  }
  const double w = kTwoPi * p[2];
  const double e = std::exp(-p[1] * tau), s = std::sin(w * tau), co = std::cos(w * tau);
  if (row) {
    *row << e * s, -p[0] * tau * e * s, p[0] * e * co * kTwoPi * tau,
        p[0] * e * (p[1] * s - w * co);
  }
  return p[0] * e * s;
}

struct LmResult {
  Eigen::Vector4d p;
  Eigen::Matrix4d covariance;
  double ssr = 0.0;
  int iterations = 0;
};

// Levenberg-Marquardt with Marquardt's scaling (lambda diag(J'J)); the covariance is
// s^2 (J'J)^-1 at the solution, s^2 = SSR / (n - 4)
LmResult LevenbergMarquardt(const std::vector<double>& t, const std::vector<double>& y,
                            Eigen::Vector4d p) {
  const std::size_t n = t.size();
  auto residuals = [&](const Eigen::Vector4d& q, Eigen::MatrixXd* jac) {
    Eigen::VectorXd r(static_cast<Eigen::Index>(n));
    Eigen::RowVector4d row;
    for (std::size_t i = 0; i < n; ++i) {
      const auto k = static_cast<Eigen::Index>(i);
      r[k] = y[i] - SinusoidModel(q, t[i], jac ? &row : nullptr);
      if (jac) jac->row(k) = row;
    }
    return r;
  };
  Eigen::MatrixXd jac(static_cast<Eigen::Index>(n), 4);
  Eigen::VectorXd r = residuals(p, &jac);
  double ssr = r.squaredNorm(), lambda = 1e-3;
  LmResult out;
  for (out.iterations = 0; out.iterations < 200; ++out.iterations) {
    const Eigen::Matrix4d jtj = jac.transpose() * jac;
    const Eigen::Vector4d g = jac.transpose() * r;
    bool improved = false;
    while (lambda < 1e12) {
      Eigen::Matrix4d a = jtj;
      a.diagonal() += lambda * jtj.diagonal().cwiseMax(1e-300);
      const Eigen::Vector4d step = a.ldlt().solve(g);
      const Eigen::Vector4d q = p + step;
      const double trial = residuals(q, nullptr).squaredNorm();
      if (std::isfinite(trial) && trial < ssr) {
        const double gain = (ssr - trial) / std::max(ssr, 1e-300);
        p = q;
        ssr = trial;
        lambda = std::max(lambda / 10.0, 1e-12);
        improved = gain > 1e-14;
        break;
      }
      lambda *= 10.0;
    }
    if (!improved) break;
    r = residuals(p, &jac);
  }
  r = residuals(p, &jac);
  out.p = p;
  out.ssr = r.squaredNorm();
  const double dof = std::max(1.0, static_cast<double>(n) - 4.0);
  const Eigen::Matrix4d jtj = jac.transpose() * jac;
  out.covariance = (out.ssr / dof) * jtj.inverse();
  return out;
}

// the tap's impact speed (docs/materials.md): the explicit column at the onset sample; else the
// median |velocity| over the last 5 ms (at least 3 samples) before t0; else the least-squares slope
// of position over the last 5 ms (at least 3 samples) before t0
double TapImpactSpeed(const TapContext& c, double t0, std::string& from) {
  const io::RecordedTap& tap = c.tap;
  std::size_t end = 0;  // samples before t0
  while (end < tap.time_s.size() && tap.time_s[end] < t0) ++end;
  auto window_start = [&](double span_s) {
    std::size_t s = end;
    while (s > 0 && (tap.time_s[s - 1] >= t0 - span_s || end - s < 3)) --s;
    return s;
  };
  double speed = 0.0;
  if (!tap.impact_speed_mps.empty()) {
    from = "impact_speed_mps";
    speed = std::abs(tap.impact_speed_mps[std::min(end, tap.time_s.size() - 1)]);
  } else if (!tap.velocity_mps.empty()) {
    // the median: a sample or two of the stop, when t0 is a little late, do not pull it down
    from = "velocity_mps";
    const std::size_t s = window_start(0.005);
    std::vector<double> v;
    for (std::size_t i = s; i < end; ++i) v.push_back(std::abs(tap.velocity_mps[i]));
    speed = v.empty() ? 0.0 : FitMedian(v);
  } else if (!tap.position_m.empty()) {
    from = "position_m";
    const std::size_t s = window_start(0.005);
    double mt = 0.0, mx = 0.0;
    const double n = static_cast<double>(end - s);
    for (std::size_t i = s; i < end; ++i) mt += tap.time_s[i] / n, mx += tap.position_m[i] / n;
    double stt = 0.0, stx = 0.0;
    for (std::size_t i = s; i < end; ++i) {
      stt += (tap.time_s[i] - mt) * (tap.time_s[i] - mt);
      stx += (tap.time_s[i] - mt) * (tap.position_m[i] - mx);
    }
    speed = stt > 0.0 ? std::abs(stx / stt) : 0.0;
  } else {
    TapFail(c, tap.line.front(),
            "no impact speed: give a velocity_mps, position_m or impact_speed_mps column");
  }
  if (!(speed > 0.0)) {
    TapFail(c, tap.line[std::min(end, tap.line.size() - 1)],
            "the impact speed from " + from + " is 0 m/s; a tap needs an approach speed");
  }
  return speed;
}

}  // namespace

TapFit FitTap(const io::TapRecording& recording, const io::RecordedTap& tap) {
  const TapContext c{recording, tap};
  TapFit fit;
  fit.file = recording.path;
  fit.tap = tap.tap;
  fit.line = tap.line.front();
  fit.sample_rate_hz = TapSampleRate(c);
  CheckTapClipping(c);
  const TapOnset onset = DetectTapOnset(c);
  const std::vector<double>& t = tap.time_s;
  fit.detected_onset_s = t[onset.index];
  fit.noise_rms = onset.noise;
  const SinusoidGuess g =
      SinusoidFirstGuess(tap.signal, onset.index, onset.baseline, fit.sample_rate_hz);
  fit.guess_frequency_hz = g.frequency_hz;
  if (fit.sample_rate_hz < 4.0 * g.frequency_hz) {
    TapFail(c, tap.line.front(),
            "sample rate " + FitNum(fit.sample_rate_hz) + " Hz is below 4 f = " +
                FitNum(4.0 * g.frequency_hz) + " Hz (f " + FitNum(g.frequency_hz) +
                " Hz, the spectrum's peak): record at least 4, better 20, samples per period");
  }
  const double after_s = t.back() - t[onset.index];
  if (!(g.frequency_hz > 0.0) || after_s * g.frequency_hz < kMinPeriodsAfterOnset) {
    TapFail(c, tap.line[onset.index],
            "too short after the onset: " + FitNum(after_s) + " s is under " +
                FitNum(kMinPeriodsAfterOnset) + " periods of the transient (first guess " +
                FitNum(g.frequency_hz) + " Hz)");
  }
  // the window: a quarter period (and 2 samples) before the detected onset, which lies after the
  // true one, to 5 / B after it
  const auto margin =
      static_cast<std::size_t>(std::ceil(0.25 * fit.sample_rate_hz / g.frequency_hz)) + 2;
  const std::size_t first = onset.index > margin ? onset.index - margin : 0;
  const double end_s = t[onset.index] + kWindowDecays / g.decay_per_s;
  std::vector<double> wt, wy;
  for (std::size_t i = first; i < t.size() && (t[i] <= end_s || wt.size() < 16); ++i) {
    wt.push_back(t[i]);
    wy.push_back(tap.signal[i] - onset.baseline);
  }
  const double t0_guess = t[onset.index > 0 ? onset.index - 1 : 0];
  const Eigen::Vector4d p0(g.amplitude, g.decay_per_s, g.frequency_hz, t0_guess);
  const LmResult lm = LevenbergMarquardt(wt, wy, p0);
  const Eigen::Vector4d sd = lm.covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
  fit.amplitude = std::abs(lm.p[0]);
  fit.amplitude_sd = sd[0];
  fit.decay_per_s = lm.p[1];
  fit.decay_sd_per_s = sd[1];
  fit.frequency_hz = lm.p[2];
  fit.frequency_sd_hz = sd[2];
  fit.onset_s = lm.p[3];
  fit.onset_sd_s = sd[3];
  fit.iterations = lm.iterations;
  fit.samples = static_cast<int>(wt.size());
  const double mean = std::accumulate(wy.begin(), wy.end(), 0.0) / static_cast<double>(wy.size());
  double sst = 0.0;
  for (const double v : wy) sst += (v - mean) * (v - mean);
  fit.r2 = sst > 0.0 ? 1.0 - lm.ssr / sst : 0.0;
  if (!(fit.frequency_hz > 0.0 && fit.decay_per_s > 0.0) || !std::isfinite(fit.r2)) {
    TapFail(c, tap.line[onset.index],
            "the decaying sinusoid does not fit (f " + FitNum(fit.frequency_hz) + " Hz, B " +
                FitNum(fit.decay_per_s) + " 1/s): is this a tap?");
  }
  if (fit.sample_rate_hz < 4.0 * fit.frequency_hz) {
    TapFail(c, tap.line.front(),
            "sample rate " + FitNum(fit.sample_rate_hz) + " Hz is below 4 f = " +
                FitNum(4.0 * fit.frequency_hz) + " Hz (f " + FitNum(fit.frequency_hz) +
                " Hz): record at least 4, better 20, samples per period");
  }
  fit.impact_speed_mps = TapImpactSpeed(c, fit.onset_s, fit.speed_from);
  fit.time_s = wt;
  fit.signal = wy;
  // shown with a positive first lobe (the amplitude's sign is the sensor's orientation)
  const double sign = lm.p[0] < 0.0 ? -1.0 : 1.0;
  fit.model.resize(wt.size());
  for (std::size_t i = 0; i < wt.size(); ++i) {
    fit.signal[i] *= sign;
    fit.model[i] = sign * SinusoidModel(lm.p, wt[i], nullptr);
  }
  return fit;
}

namespace {

Summary SummarizeTaps(const std::vector<TapFit>& taps, double TapFit::*value, double TapFit::*sd) {
  Summary s;
  const double n = static_cast<double>(taps.size());
  for (const TapFit& t : taps) s.mean += t.*value / n;
  if (taps.size() == 1) {
    s.sd = taps[0].*sd;
    return s;
  }
  double ss = 0.0;
  for (const TapFit& t : taps) ss += (t.*value - s.mean) * (t.*value - s.mean);
  s.spread = std::sqrt(ss / (n - 1.0));
  s.sd = s.spread / std::sqrt(n);
  return s;
}

// least squares through the origin, A = k v, and the affine A = k v + c (Draper and Smith's
// formulas); the affine form is preferred when its intercept is over 3 standard deviations from 0
AmplitudeLine FitAmplitudeLine(const std::vector<TapFit>& taps) {
  AmplitudeLine l;
  const auto n = static_cast<double>(taps.size());
  double svv = 0.0, sva = 0.0, mv = 0.0, ma = 0.0;
  for (const TapFit& t : taps) {
    svv += t.impact_speed_mps * t.impact_speed_mps;
    sva += t.impact_speed_mps * t.amplitude;
    mv += t.impact_speed_mps / n;
    ma += t.amplitude / n;
  }
  l.slope = sva / svv;
  double ssr = 0.0, sst = 0.0, cvv = 0.0, cva = 0.0;
  for (const TapFit& t : taps) {
    const double r = t.amplitude - l.slope * t.impact_speed_mps;
    ssr += r * r;
    sst += (t.amplitude - ma) * (t.amplitude - ma);
    cvv += (t.impact_speed_mps - mv) * (t.impact_speed_mps - mv);
    cva += (t.impact_speed_mps - mv) * (t.amplitude - ma);
  }
  l.residual_rms = std::sqrt(ssr / n);
  l.r2 = sst > 0.0 ? 1.0 - ssr / sst : std::numeric_limits<double>::quiet_NaN();
  l.slope_sd = taps.size() > 1 ? std::sqrt(ssr / (n - 1.0) / svv)
                               : taps[0].amplitude_sd / taps[0].impact_speed_mps;
  if (taps.size() < 3 || !(cvv > 1e-12 * svv)) return l;
  l.affine_slope = cva / cvv;
  l.affine_intercept = ma - l.affine_slope * mv;
  double ssa = 0.0;
  for (const TapFit& t : taps) {
    const double r = t.amplitude - l.affine_slope * t.impact_speed_mps - l.affine_intercept;
    ssa += r * r;
  }
  l.affine_residual_rms = std::sqrt(ssa / n);
  const double s2 = ssa / (n - 2.0);
  l.affine_intercept_sd = std::sqrt(s2 * (1.0 / n + mv * mv / cvv));
  l.affine_preferred = std::abs(l.affine_intercept) > 3.0 * l.affine_intercept_sd;
  return l;
}

void AddFitWarnings(MaterialFit& fit) {
  const MaterialFitOptions& o = fit.options;
  const double f = fit.material.frequency_hz;
  if (o.display_limit_hz > 0.0 && f >= o.display_limit_hz) {
    fit.warnings.push_back("the fitted frequency " + FitNum(f) + " Hz is at or above " +
                           FitNum(o.display_limit_hz) + " Hz, the Nyquist frequency of device " +
                           o.device + "'s haptic rate: it cannot display it (raise --rate)");
  }
  double v_max = 0.0;
  for (const TapFit& t : fit.taps) v_max = std::max(v_max, t.impact_speed_mps);
  const double peak_N = fit.material.amplitude_Ns_per_m * v_max;
  if (o.max_force_N > 0.0 && peak_N > o.max_force_N) {
    fit.warnings.push_back("at the fastest recorded tap (" + FitNum(v_max) +
                           " m/s) the transient's " + "amplitude is " + FitNum(peak_N) +
                           " N, above device " + o.device + "'s force limit " +
                           FitNum(o.max_force_N) + " N: it will be clipped");
  }
  if (fit.amplitude.affine_preferred) {
    fit.warnings.push_back(
        "the amplitudes prefer A = " + FitNum(fit.amplitude.affine_slope) + " v + " +
        FitNum(fit.amplitude.affine_intercept) + " (intercept " +
        FitNum(fit.amplitude.affine_intercept / fit.amplitude.affine_intercept_sd) +
        " sd from 0); the renderers take A = slope v, through the origin");
  }
  double v_min = v_max;
  for (const TapFit& t : fit.taps) v_min = std::min(v_min, t.impact_speed_mps);
  if (v_max - v_min < 0.2 * v_max) {
    fit.warnings.push_back("the impact speeds span only " + FitNum(v_min) + " to " + FitNum(v_max) +
                           " m/s: record several speeds to check that A is linear in v");
  }
}

}  // namespace

MaterialFit FitMaterial(std::span<const io::TapRecording> recordings,
                        const MaterialFitOptions& options) {
  if (recordings.empty()) throw Error("no recordings to fit");
  MaterialFit fit;
  fit.options = options;
  fit.quantity = recordings.front().quantity;
  for (const io::TapRecording& r : recordings) {
    if (r.quantity != fit.quantity) {
      throw Error(r.path + ":1: records " + std::string(io::TapQuantityColumn(r.quantity)) +
                  " but " + recordings.front().path + " records " +
                  std::string(io::TapQuantityColumn(fit.quantity)) +
                  "; fit one quantity per material");
    }
    fit.recordings.push_back(r.path);
    for (const io::RecordedTap& tap : r.taps) fit.taps.push_back(FitTap(r, tap));
  }
  fit.frequency_hz = SummarizeTaps(fit.taps, &TapFit::frequency_hz, &TapFit::frequency_sd_hz);
  fit.decay_per_s = SummarizeTaps(fit.taps, &TapFit::decay_per_s, &TapFit::decay_sd_per_s);
  fit.amplitude = FitAmplitudeLine(fit.taps);
  const bool acceleration = fit.quantity == io::TapQuantity::kAcceleration;
  const double scale = acceleration ? options.effective_mass_kg : 1.0;
  if (acceleration && !(scale > 0.0)) {
    throw Error("an acceleration recording needs the effective mass (device and hand) > 0 kg");
  }
  fit.effective_mass_kg = acceleration ? scale : 0.0;
  fit.material.name = options.name;
  fit.material.amplitude_Ns_per_m = scale * fit.amplitude.slope;
  fit.material.decay_per_s = fit.decay_per_s.mean;
  fit.material.frequency_hz = fit.frequency_hz.mean;
  if (acceleration) {
    fit.material.amplitude_mps2_per_mps = fit.amplitude.slope;
    fit.material.effective_mass_kg = scale;
  }
  fit.amplitude_sd_Ns_per_m = scale * fit.amplitude.slope_sd;
  AddFitWarnings(fit);
  return fit;
}

}  // namespace rigidtouch::analysis
