// The material file and figure data of a fit, and synthetic tap recordings (material_fit.h).
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <numbers>

#include "analysis/material_fit.h"
#include "analysis/spectrum.h"
#include "io/normal_deviate.h"

namespace rigidtouch::analysis {
namespace {

nlohmann::json TapFitJson(const TapFit& t) {
  return {{"file", t.file},
          {"tap", t.tap},
          {"line", t.line},
          {"samples", t.samples},
          {"sample_rate_hz", t.sample_rate_hz},
          {"impact_speed_mps", t.impact_speed_mps},
          {"speed_from", t.speed_from},
          {"onset_s", t.onset_s},
          {"onset_sd_s", t.onset_sd_s},
          {"amplitude", t.amplitude},
          {"amplitude_sd", t.amplitude_sd},
          {"decay_per_s", t.decay_per_s},
          {"decay_sd_per_s", t.decay_sd_per_s},
          {"frequency_hz", t.frequency_hz},
          {"frequency_sd_hz", t.frequency_sd_hz},
          {"r2", t.r2},
          {"noise_rms", t.noise_rms},
          {"iterations", t.iterations}};
}

// a JSON number or null (JSON has no NaN)
nlohmann::json FitNumberOrNull(double v) {
  return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr);
}

// the one-sided amplitude spectrum of `x` at `rate` [unit / sqrt(Hz) up to a constant]: the
// project's PowerSpectrum with the tapered-end window (a transient from its first sample)
std::vector<double> TransientPower(const std::vector<double>& x, double rate, double& bin_hz) {
  SpectrumOptions o;
  o.window = SpectrumOptions::Window::kTaperedEnd;
  o.remove_mean = false;
  o.min_fft_length = 4096;
  const analysis::Spectrum s = PowerSpectrum(x, rate, o);
  bin_hz = s.bin_hz;
  return s.power;
}

}  // namespace

nlohmann::json MaterialFileJson(const MaterialFit& fit) {
  const bool acceleration = fit.quantity == io::TapQuantity::kAcceleration;
  const std::string unit = std::string(io::TapQuantityUnit(fit.quantity)) + " per m/s";
  nlohmann::json taps = nlohmann::json::array();
  for (const TapFit& t : fit.taps) taps.push_back(TapFitJson(t));
  const AmplitudeLine& l = fit.amplitude;
  nlohmann::json j = {
      {"name", fit.material.name},
      {"amplitude_Ns_per_m", fit.material.amplitude_Ns_per_m},
      {"decay_per_s", fit.material.decay_per_s},
      {"frequency_hz", fit.material.frequency_hz},
      {"amplitude_quantity", acceleration ? "acceleration" : "force"},
  };
  if (acceleration) {
    j["amplitude_mps2_per_mps"] = l.slope;
    j["effective_mass_kg"] = fit.effective_mass_kg;
  }
  j["fit"] = {
      {"method", "rigidtouch material fit (docs/materials.md)"},
      {"recordings", fit.recordings},
      {"device", fit.options.device},
      {"taps", fit.taps.size()},
      {"uncertainty",
       {{"amplitude_Ns_per_m", fit.amplitude_sd_Ns_per_m},
        {"decay_per_s", fit.decay_per_s.sd},
        {"frequency_hz", fit.frequency_hz.sd}}},
      {"spread",
       {{"decay_per_s", fit.decay_per_s.spread}, {"frequency_hz", fit.frequency_hz.spread}}},
      {"amplitude_line",
       {{"unit", unit},
        {"slope", l.slope},
        {"slope_sd", l.slope_sd},
        {"residual_rms", l.residual_rms},
        {"r2", FitNumberOrNull(l.r2)},
        {"affine_slope", l.affine_slope},
        {"affine_intercept", l.affine_intercept},
        {"affine_intercept_sd", l.affine_intercept_sd},
        {"affine_preferred", l.affine_preferred}}},
      {"per_tap", taps},
      {"warnings", fit.warnings},
  };
  return j;
}

nlohmann::json MaterialFigureJson(const MaterialFit& fit) {
  nlohmann::json taps = nlohmann::json::array();
  for (const TapFit& t : fit.taps) {
    std::vector<double> time_ms(t.time_s.size());
    for (std::size_t i = 0; i < t.time_s.size(); ++i) time_ms[i] = 1e3 * (t.time_s[i] - t.onset_s);
    double bin_hz = 0.0;
    const std::vector<double> data = TransientPower(t.signal, t.sample_rate_hz, bin_hz);
    const std::vector<double> model = TransientPower(t.model, t.sample_rate_hz, bin_hz);
    taps.push_back({{"label", t.file + " tap " + std::to_string(t.tap)},
                    {"impact_speed_mps", t.impact_speed_mps},
                    {"amplitude", t.amplitude},
                    {"amplitude_sd", t.amplitude_sd},
                    {"r2", t.r2},
                    {"time_ms", time_ms},
                    {"signal", t.signal},
                    {"model", t.model},
                    {"spectrum_bin_hz", bin_hz},
                    {"spectrum_data", data},
                    {"spectrum_model", model}});
  }
  return {{"name", fit.material.name},
          {"unit", std::string(io::TapQuantityUnit(fit.quantity))},
          {"frequency_hz", fit.material.frequency_hz},
          {"decay_per_s", fit.material.decay_per_s},
          {"slope", fit.amplitude.slope},
          {"slope_sd", fit.amplitude.slope_sd},
          {"residual_rms", fit.amplitude.residual_rms},
          {"taps", taps}};
}

std::string SyntheticTapsCsv(const SyntheticTapsOptions& o, const std::string& comment) {
  const double rate =
      o.sample_rate_hz > 0.0 ? o.sample_rate_hz : std::max(2000.0, 20.0 * o.frequency_hz);
  const double h = 1.0 / rate, w = 2.0 * std::numbers::pi * o.frequency_hz;
  std::uint64_t state = 0x9E3779B97F4A7C15ull * (o.seed + 1);
  auto uniform = [&state]() {  // SplitMix64, in (0, 1]
    std::uint64_t z = (state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    z ^= z >> 31;
    return (static_cast<double>(z >> 11) + 1.0) / 9007199254740992.0;
  };
  auto normal = [&]() {
    const double u1 = uniform();
    const double u2 = uniform() - 1e-17;
    return io::BoxMuller(u1, std::max(0.0, u2));
  };
  // RMS of e^(-B t) sin(w t) over its first ln 20 / B: the noise is this over 10^(snr / 20)
  const double window_s = std::log(20.0) / o.decay_per_s;
  double ms = 0.0;
  const int steps = 4000;
  for (int i = 0; i < steps; ++i) {
    const double t = (i + 0.5) * window_s / steps;
    const double v = std::exp(-o.decay_per_s * t) * std::sin(w * t);
    ms += v * v / steps;
  }
  const double rms_per_slope = std::sqrt(ms), noise_over = std::pow(10.0, -o.snr_db / 20.0);
  const double length_s =
      o.pre_contact_s + o.onset_jitter_s + std::max(5.0 / o.decay_per_s, 4.0 / o.frequency_hz);
  const auto samples = static_cast<int>(std::ceil(length_s * rate));
  std::string csv =
      comment + "time_s," + std::string(io::TapQuantityColumn(o.quantity)) + ",velocity_mps,tap\n";
  char row[160];
  double start_s = 0.0;
  int tap = 0;
  for (const double v : o.speeds_mps) {
    for (int k = 0; k < o.taps_per_speed; ++k, ++tap) {
      const double onset_s = o.pre_contact_s + o.onset_jitter_s * (2.0 * uniform() - 1.0);
      const double sigma = noise_over * rms_per_slope * o.slope * v;
      std::vector<double> x(static_cast<std::size_t>(samples)), vel(x.size());
      for (int i = 0; i < samples; ++i) {
        const double tau = i * h - onset_s;
        const double q =
            tau > 0.0 ? o.slope * v * std::exp(-o.decay_per_s * tau) * std::sin(w * tau) : 0.0;
        x[static_cast<std::size_t>(i)] = q + sigma * normal();
        vel[static_cast<std::size_t>(i)] = (tau > 0.0 ? 0.0 : -v) + 0.01 * v * normal();
      }
      if (tap == 0 && o.clip_fraction > 0.0) {
        std::vector<double> sorted = x;
        std::sort(sorted.begin(), sorted.end());
        const double rail = sorted[static_cast<std::size_t>(
            std::floor((1.0 - o.clip_fraction) * static_cast<double>(sorted.size())))];
        for (double& s : x) s = std::min(s, rail);
      }
      for (int i = 0; i < samples; ++i) {
        std::snprintf(row, sizeof row, "%.6f,%.6g,%.5g,%d\n", start_s + i * h,
                      x[static_cast<std::size_t>(i)], vel[static_cast<std::size_t>(i)], tap);
        csv += row;
      }
      start_s += samples * h + 0.1;
    }
  }
  return csv;
}

}  // namespace rigidtouch::analysis
