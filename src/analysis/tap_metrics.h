// Per-tap metrics over a trace: peak force, rate hardness, penetration, time to stop, bounces,
// energy delivered to the user, impulses and the force spectrum over the collision window.
// Offline analysis: allocates, never runs inside the haptic loop.
//
// Conventions used throughout:
// - "Normal force" is device_force_N . n with n the wall_normal of the contact-onset sample
//   (positive pushes the tool out of the wall).
// - Contact: a sample is in contact when tool_contacts > 0.
// - Sample k's device force is held from sample k to sample k + 1 (zero-order hold), and
//   tool_position_m of sample k is the position at the start of that hold.
#pragma once

#include <array>
#include <span>
#include <vector>

#include "analysis/spectrum.h"
#include "rigidtouch/trace.h"

namespace rigidtouch::analysis {

/// Options of ComputeTapMetrics.
struct TapMetricsOptions {
  /// Window after contact onset over which the extended rate hardness looks for the largest
  /// dF/dt [s].
  double extended_rate_hardness_window_s = 0.010;
  /// Window after contact onset analysed by the force spectrum [s]; 0.1 s is the longest
  /// collision-rendering window the method allows (docs/method.md).
  double collision_window_s = 0.100;
  /// The tool has stopped once its approach speed (-n . velocity) is at most this [m/s].
  double stop_speed_mps = 1e-3;
  /// Edges of the four spectrum bands [Hz].
  std::array<double, 3> band_edges_hz = kDefaultBandEdgesHz;
  /// Spectrum settings.
  SpectrumOptions spectrum;
  /// A moving wall (a link of an articulated tree): per sample of the tap, the velocity of the
  /// wall's point under the tool [m/s]. When given (one per sample), the approach speed at onset
  /// and the time to stop are of the tool relative to that point, -n . (v_tool - v_wall); empty
  /// for a static wall (the tool's own velocity).
  std::span<const Vec3> surface_velocity_mps;
};

/// One collision impulse seen in the trace (a sample with impulses > 0).
struct ImpulseEvent {
  double time_s = 0.0;
  /// Eq. 9 force requested for it along the onset normal [N] (before the device limit); 0 when
  /// the impulse came out zero (the contact was already receding).
  double requested_force_N = 0.0;
  double kinetic_energy_before_J = 0.0;
  double kinetic_energy_after_J = 0.0;
};

/// Metrics of one tap. Quantities that need a contact are NaN when the tap never touched.
struct TapMetrics {
  int tap = -1;                       // TraceSample::tap of the samples
  bool contact = false;               // some sample had tool_contacts > 0
  double contact_onset_time_s = 0.0;  // time of the first contact sample (NaN without contact)
  /// Approach speed at onset: -n . tool_velocity at the last sample before onset [m/s]; relative
  /// to the wall's point under the tool for a moving wall (TapMetricsOptions).
  double approach_speed_mps = 0.0;
  /// Largest normal force the device displayed over the tap (after its limit) [N].
  double peak_force_N = 0.0;
  /// Largest normal force the renderer requested over the tap (penalty + Eq. 9, before the
  /// device limit) [N].
  double peak_requested_force_N = 0.0;
  /// Lawrence et al. 2000: (F_n[onset] - F_n[onset - 1]) / (t[onset] - t[onset - 1]) divided by
  /// the approach speed, i.e. over the first tick of contact [N/m].
  double rate_hardness_N_per_m = 0.0;
  /// Largest (F_n[k] - F_n[k - 1]) / (t[k] - t[k - 1]) for onset <= k with t[k] - t[onset] within
  /// the extended window, divided by the approach speed [N/m].
  double extended_rate_hardness_N_per_m = 0.0;
  /// Largest penetration_m over the tap [m].
  double max_penetration_m = 0.0;
  /// Time from onset to the first sample whose approach speed is <= stop_speed_mps [s]
  /// (NaN if the tool never stops within the tap).
  double time_to_stop_s = 0.0;
  /// Separations followed by a new contact within the tap: number of contact intervals - 1.
  int bounces = 0;
  /// Energy the device delivered to the user over the tap [J]:
  /// sum over consecutive samples k, k + 1 of the tap of device_force[k] . (x[k + 1] - x[k]),
  /// x = tool_position_m (the trace has no separate device position; with direct coupling the
  /// tool is the device end effector). Positive = into the user; passive rendering gives <= 0.
  double energy_to_user_J = 0.0;
  /// Every impulse in the tap, in time order.
  std::vector<ImpulseEvent> impulses;
  /// Fraction of the displayed normal force's power over the collision window below 40 Hz,
  /// 40-100, 100-400 and above 400 Hz (with the default edges).
  std::array<double, 4> band_energy_fraction = {0.0, 0.0, 0.0, 0.0};
  /// Duration of the analysed window from onset (TapMetricsOptions::collision_window_s, shorter
  /// when the tap ends first) [s]: every spectral figure below is over it.
  double spectrum_window_s = 0.0;
  /// Inverse of the analysed window's duration: spectra resolve nothing finer [Hz].
  double spectrum_resolution_hz = 0.0;
  /// The transient part: displayed normal force minus the penalty (or coupling) force, i.e. what
  /// the impulses add to what the device displays, after its limit; zero without impulses.
  /// Its repetition rate (RepetitionOf, lags from 2 samples up to 1 / 40 Hz: below 40 Hz the
  /// transient's envelope is felt as part of the press): a train's impulse rate, a vibration's
  /// frequency [Hz]; 0 when it does not repeat (one click), NaN when the transient is zero.
  double transient_repetition_hz = 0.0;
  /// The normalised autocorrelation at that period, in [0, 1] (RepetitionOf); NaN as above.
  double transient_periodicity = 0.0;
  /// Peak power over mean power of the transient's bins at or above 40 Hz: about 1 for a flat
  /// spectrum (one short pulse: no dominant frequency), large for a line (a periodic train).
  double transient_peak_to_mean = 0.0;
  /// Band fractions of the transient part's power (as band_energy_fraction).
  std::array<double, 4> transient_band_energy_fraction = {0.0, 0.0, 0.0, 0.0};
  /// Transient power above DC over the displayed force's power above DC (same window).
  double transient_power_ratio = 0.0;
  /// Some sample of the tap had its device force clipped by the device limit.
  bool force_clipped = false;
  /// Energy the passivity controller dissipated over the tap [J] (0 without it).
  double passivity_dissipated_J = 0.0;
};

/// Splits a trace into taps: maximal runs of consecutive samples with the same tap >= 0.
/// Samples with tap = -1 (between taps) are dropped.
std::vector<std::span<const TraceSample>> SplitTaps(std::span<const TraceSample> samples);

/// Metrics of one tap's samples (as returned by SplitTaps).
TapMetrics ComputeTapMetrics(std::span<const TraceSample> tap_samples,
                             const TapMetricsOptions& options = {});

/// Energy delivered to the user over `samples` [J], with the definition and sign of
/// TapMetrics::energy_to_user_J.
double EnergyToUserJ(std::span<const TraceSample> samples);

/// Running energy delivered to the user [J]: element k is the energy up to sample k (element 0
/// is 0), same definition and sign as TapMetrics::energy_to_user_J.
std::vector<double> CumulativeEnergyToUserJ(std::span<const TraceSample> samples);

}  // namespace rigidtouch::analysis
