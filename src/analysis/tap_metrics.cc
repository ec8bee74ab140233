#include "analysis/tap_metrics.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace rigidtouch::analysis {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// requested force: what the renderer asked for before the device limit
Vec3 RequestedForceN(const TraceSample& s) {
  return s.penalty_force_N + s.impulsive_force_N;
}

// displayed force along the contact normal n, and the tool's speed towards the wall
double NormalForceN(const TraceSample& s, const Vec3& n) {
  return s.device_force_N.dot(n);
}
double ApproachSpeedMps(const TraceSample& s, const Vec3& n) {
  return -s.tool_velocity_mps.dot(n);
}
// relative to a moving wall's point when the options give its velocities (sample k of the tap)
double ApproachSpeedMps(std::span<const TraceSample> s, std::size_t k, const Vec3& n,
                        const TapMetricsOptions& options) {
  if (options.surface_velocity_mps.size() != s.size()) return ApproachSpeedMps(s[k], n);
  return -(s[k].tool_velocity_mps - options.surface_velocity_mps[k]).dot(n);
}

void SetSpectraNaN(TapMetrics& m) {
  m.band_energy_fraction = {kNaN, kNaN, kNaN, kNaN};
  m.spectrum_window_s = kNaN;
  m.spectrum_resolution_hz = kNaN;
  m.transient_repetition_hz = kNaN;
  m.transient_periodicity = kNaN;
  m.transient_peak_to_mean = kNaN;
  m.transient_band_energy_fraction = {kNaN, kNaN, kNaN, kNaN};
  m.transient_power_ratio = kNaN;
}

// a tap that never touches: no contact metrics, forces and impulses along each sample's normal
void NoContactMetrics(std::span<const TraceSample> s, TapMetrics& m) {
  m.contact_onset_time_s = kNaN;
  m.approach_speed_mps = kNaN;
  m.rate_hardness_N_per_m = kNaN;
  m.extended_rate_hardness_N_per_m = kNaN;
  m.time_to_stop_s = kNaN;
  SetSpectraNaN(m);
  for (const TraceSample& sample : s) {
    m.peak_force_N = std::max(m.peak_force_N, sample.device_force_N.dot(sample.wall_normal));
    m.peak_requested_force_N =
        std::max(m.peak_requested_force_N, RequestedForceN(sample).dot(sample.wall_normal));
    if (sample.impulses > 0) {
      m.impulses.push_back({sample.time_s, sample.impulsive_force_N.dot(sample.wall_normal),
                            sample.kinetic_energy_before_J, sample.kinetic_energy_after_J});
    }
  }
}

// rate hardness (Lawrence et al. 2000) at the first tick of contact, and its extended form
void RateHardness(std::span<const TraceSample> s, std::size_t onset, std::size_t before,
                  const Vec3& n, const TapMetricsOptions& options, TapMetrics& m) {
  if (onset > 0 && s[onset].time_s > s[before].time_s) {
    const double rate_N_per_s = (NormalForceN(s[onset], n) - NormalForceN(s[before], n)) /
                                (s[onset].time_s - s[before].time_s);
    m.rate_hardness_N_per_m = rate_N_per_s / m.approach_speed_mps;
  } else {
    m.rate_hardness_N_per_m = kNaN;
  }
  // extended: largest rate within the window after onset
  double max_rate_N_per_s = -std::numeric_limits<double>::infinity();
  for (std::size_t k = std::max<std::size_t>(onset, 1); k < s.size(); ++k) {
    // the tolerance as for the collision window: tick onset + 10 is in, wherever the tap starts
    if (s[k].time_s - s[onset].time_s > options.extended_rate_hardness_window_s + 1e-9) break;
    const double dt_s = s[k].time_s - s[k - 1].time_s;
    if (dt_s <= 0.0) continue;
    max_rate_N_per_s =
        std::max(max_rate_N_per_s, (NormalForceN(s[k], n) - NormalForceN(s[k - 1], n)) / dt_s);
  }
  m.extended_rate_hardness_N_per_m =
      std::isfinite(max_rate_N_per_s) ? max_rate_N_per_s / m.approach_speed_mps : kNaN;
}

// spectra over the collision window from onset: the displayed normal force, and its transient
// part (displayed minus penalty: what the impulses add after the device limit)
void Spectra(std::span<const TraceSample> s, std::size_t onset, const Vec3& n,
             const TapMetricsOptions& options, TapMetrics& m) {
  std::vector<double> force_N, transient_N;
  for (std::size_t k = onset; k < s.size(); ++k) {
    // the tolerance keeps trace times' rounding from adding a sample: 100 ms is 100 ticks
    if (s[k].time_s - s[onset].time_s >= options.collision_window_s - 1e-9) break;
    force_N.push_back(NormalForceN(s[k], n));
    transient_N.push_back(NormalForceN(s[k], n) - s[k].penalty_force_N.dot(n));
  }
  double sample_rate_hz = 0.0;
  const std::size_t last = onset + force_N.size() - 1;
  if (force_N.size() >= 2 && s[last].time_s > s[onset].time_s) {
    sample_rate_hz = static_cast<double>(force_N.size() - 1) / (s[last].time_s - s[onset].time_s);
  }
  // the tap is a transient from onset: a Hann window would weigh the onset impulse by zero
  SpectrumOptions spectrum_options = options.spectrum;
  spectrum_options.window = SpectrumOptions::Window::kTaperedEnd;
  const Spectrum spectrum = PowerSpectrum(force_N, sample_rate_hz, spectrum_options);
  const Spectrum transient = PowerSpectrum(transient_N, sample_rate_hz, spectrum_options);
  if (spectrum.power.empty()) {
    SetSpectraNaN(m);
    return;
  }
  m.band_energy_fraction = BandEnergyFractions(spectrum, options.band_edges_hz);
  m.spectrum_window_s = static_cast<double>(force_N.size()) / sample_rate_hz;
  m.spectrum_resolution_hz = ResolutionHz(static_cast<int>(force_N.size()), sample_rate_hz);
  const double vibration_hz = options.band_edges_hz[0];
  m.transient_peak_to_mean = PeakToMeanPower(transient, vibration_hz);
  const double transient_power = PowerAboveDc(transient);
  if (transient_power > 0.0) {
    m.transient_band_energy_fraction = BandEnergyFractions(transient, options.band_edges_hz);
    const Repetition r =
        RepetitionOf(transient_N, 1.0 / sample_rate_hz, vibration_hz, m.transient_peak_to_mean);
    m.transient_repetition_hz = r.rate_hz;
    m.transient_periodicity = r.periodicity;
  } else {
    m.transient_band_energy_fraction = {kNaN, kNaN, kNaN, kNaN};
    m.transient_repetition_hz = kNaN;
    m.transient_periodicity = kNaN;
  }
  const double displayed_power = PowerAboveDc(spectrum);
  m.transient_power_ratio = displayed_power > 0.0 ? transient_power / displayed_power : kNaN;
}

}  // namespace

std::vector<std::span<const TraceSample>> SplitTaps(std::span<const TraceSample> samples) {
  std::vector<std::span<const TraceSample>> taps;
  std::size_t i = 0;
  while (i < samples.size()) {
    if (samples[i].tap < 0) {
      ++i;
      continue;
    }
    std::size_t j = i + 1;
    while (j < samples.size() && samples[j].tap == samples[i].tap) ++j;
    taps.push_back(samples.subspan(i, j - i));
    i = j;
  }
  return taps;
}

double EnergyToUserJ(std::span<const TraceSample> samples) {
  double energy_J = 0.0;
  for (std::size_t k = 0; k + 1 < samples.size(); ++k) {
    energy_J +=
        samples[k].device_force_N.dot(samples[k + 1].tool_position_m - samples[k].tool_position_m);
  }
  return energy_J;
}

std::vector<double> CumulativeEnergyToUserJ(std::span<const TraceSample> samples) {
  std::vector<double> energy_J(samples.size(), 0.0);
  for (std::size_t k = 0; k + 1 < samples.size(); ++k) {
    energy_J[k + 1] = energy_J[k] + samples[k].device_force_N.dot(samples[k + 1].tool_position_m -
                                                                  samples[k].tool_position_m);
  }
  return energy_J;
}

TapMetrics ComputeTapMetrics(std::span<const TraceSample> s, const TapMetricsOptions& options) {
  TapMetrics m;
  if (s.empty()) return m;
  m.tap = s.front().tap;
  m.energy_to_user_J = EnergyToUserJ(s);
  for (const TraceSample& sample : s) {
    m.max_penetration_m = std::max(m.max_penetration_m, sample.penetration_m);
    m.force_clipped = m.force_clipped || sample.clipped;
    m.passivity_dissipated_J += sample.passivity_dissipated_J;
  }

  std::size_t onset = 0;
  while (onset < s.size() && s[onset].tool_contacts <= 0) ++onset;
  if (onset == s.size()) {
    NoContactMetrics(s, m);
    return m;
  }
  m.contact = true;
  m.contact_onset_time_s = s[onset].time_s;
  const Vec3 n = s[onset].wall_normal;

  const std::size_t before = onset > 0 ? onset - 1 : onset;
  m.approach_speed_mps = ApproachSpeedMps(s, before, n, options);

  for (std::size_t k = 0; k < s.size(); ++k) {
    m.peak_force_N = std::max(m.peak_force_N, NormalForceN(s[k], n));
    m.peak_requested_force_N = std::max(m.peak_requested_force_N, RequestedForceN(s[k]).dot(n));
    if (s[k].impulses > 0) {
      m.impulses.push_back({s[k].time_s, s[k].impulsive_force_N.dot(n),
                            s[k].kinetic_energy_before_J, s[k].kinetic_energy_after_J});
    }
  }

  RateHardness(s, onset, before, n, options, m);

  m.time_to_stop_s = kNaN;
  for (std::size_t k = onset; k < s.size(); ++k) {
    if (ApproachSpeedMps(s, k, n, options) <= options.stop_speed_mps) {
      m.time_to_stop_s = s[k].time_s - s[onset].time_s;
      break;
    }
  }

  int intervals = 0;
  for (std::size_t k = 0; k < s.size(); ++k) {
    const bool in_contact = s[k].tool_contacts > 0;
    const bool was_in_contact = k > 0 && s[k - 1].tool_contacts > 0;
    if (in_contact && !was_in_contact) ++intervals;
  }
  m.bounces = std::max(0, intervals - 1);

  Spectra(s, onset, n, options, m);
  return m;
}

}  // namespace rigidtouch::analysis
