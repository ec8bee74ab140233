// Materials from measurements (docs/materials.md): fits the decaying sinusoid
// Q(t) = a e^(-B (t - t0)) sin(2 pi f (t - t0)) to each recorded tap, then the amplitude per
// impact speed, and makes a material the event and train renderers accept. Offline analysis:
// allocates and throws, never runs inside the haptic loop.
#pragma once

#include <span>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "io/tap_recording.h"
#include "rigidtouch/model.h"

namespace rigidtouch::analysis {

/// What the fit needs besides the recordings.
struct MaterialFitOptions {
  std::string name = "fitted";  // the material's name
  /// For acceleration recordings: amplitude_Ns_per_m = effective_mass_kg * (acceleration per
  /// impact speed), the mass the device's force moves at the handle (its apparent mass plus the
  /// hand's, docs/materials.md). Unused for force recordings.
  double effective_mass_kg = 0.0;
  std::string device;  // the device whose mass and rate were used ("touch", a file), for the record
  /// Warn when f is at or above this (the haptic rate's Nyquist frequency) [Hz]; 0: no check.
  double display_limit_hz = 0.0;
  /// Warn when A v exceeds this at the fastest recorded tap [N]; 0: no check.
  double max_force_N = 0.0;
};

/// One tap's fit. The amplitude is in the recording's unit (m/s^2 or N) at the onset t0.
struct TapFit {
  std::string file;
  int tap = 0;
  int line = 0;     // the tap's first sample's line
  int samples = 0;  // in the fit window
  double sample_rate_hz = 0.0;
  double detected_onset_s = 0.0;  // the onset detector's sample
  double guess_frequency_hz = 0.0;
  double impact_speed_mps = 0.0;
  std::string speed_from;  // "impact_speed_mps", "velocity_mps" or "position_m"
  double amplitude = 0.0, amplitude_sd = 0.0;
  double decay_per_s = 0.0, decay_sd_per_s = 0.0;
  double frequency_hz = 0.0, frequency_sd_hz = 0.0;
  double onset_s = 0.0, onset_sd_s = 0.0;
  double r2 = 0.0;
  double noise_rms = 0.0;  // of the pre-contact samples (robust estimate)
  int iterations = 0;
  /// The fit window and the model on it (for the figure).
  std::vector<double> time_s, signal, model;
};

/// The amplitude per impact speed, A(v) = slope v (the renderer's form), and the affine
/// alternative A(v) = slope v + intercept, with which the data prefer.
struct AmplitudeLine {
  double slope = 0.0, slope_sd = 0.0;  // unit per (m/s)
  double residual_rms = 0.0;           // of A - slope v
  double r2 = 0.0;                     // 1 - SSR / sum (A - mean A)^2 (NaN with one tap)
  double affine_slope = 0.0, affine_intercept = 0.0, affine_intercept_sd = 0.0;
  double affine_residual_rms = 0.0;
  bool affine_preferred = false;  // the intercept differs from 0 by more than 3 sd (>= 3 speeds)
};

/// Mean, spread (sample standard deviation across taps) and uncertainty (the mean's standard
/// error; with one tap, that tap's Jacobian standard deviation).
struct Summary {
  double mean = 0.0, spread = 0.0, sd = 0.0;
};

struct MaterialFit {
  io::TapQuantity quantity = io::TapQuantity::kAcceleration;
  std::vector<std::string> recordings;
  std::vector<TapFit> taps;
  Summary frequency_hz, decay_per_s;
  AmplitudeLine amplitude;
  double effective_mass_kg = 0.0;  // acceleration only
  Material material;               // what the renderers take
  double amplitude_sd_Ns_per_m = 0.0;
  std::vector<std::string> warnings;
  MaterialFitOptions options;
};

/// Fits one tap; throws Error "FILE:LINE: tap T: ..." when it cannot support a fit: too short
/// (fewer than 8 pre-contact samples or 3 periods after the onset), clipped or saturated (3 or
/// more samples at the recording's extreme value), no onset (the largest deviation is below 8
/// times the pre-contact noise), irregular sampling, a sample rate below 4 f, no impact speed.
TapFit FitTap(const io::TapRecording& recording, const io::RecordedTap& tap);

/// Fits every tap of every recording (all of one quantity), then the amplitude line; the
/// material's f and B are the taps' means, its amplitude the line's slope (converted to force
/// with options.effective_mass_kg for acceleration). Throws Error for the first bad tap.
MaterialFit FitMaterial(std::span<const io::TapRecording> recordings,
                        const MaterialFitOptions& options);

/// The material file: name, amplitude_Ns_per_m, decay_per_s, frequency_hz, amplitude_quantity
/// (and for acceleration amplitude_mps2_per_mps and effective_mass_kg), and `fit` (provenance,
/// uncertainties, spread, the amplitude line, every tap). io::ReadMaterial reads it back.
nlohmann::json MaterialFileJson(const MaterialFit& fit);

/// What `--plot` draws, as JSON for python/plot_material.py: every tap's window, signal and
/// model, the amplitude line, and the spectra of data and model.
nlohmann::json MaterialFigureJson(const MaterialFit& fit);

/// How synthetic recordings are made (docs/materials.md, "Shipped data"): a stylus moving at
/// constant speed onto the sample, then the sample's transient at the contact onset,
/// Q(t) = k v e^(-B t) sin(2 pi f t), white sensor noise at `snr_db` (the transient's RMS over
/// its first ln 20 / B over the noise's), the onset at a random time, not on a sample.
struct SyntheticTapsOptions {
  io::TapQuantity quantity = io::TapQuantity::kAcceleration;
  double slope = 0.0;  // k: amplitude per impact speed [unit / (m/s)]
  double decay_per_s = 0.0;
  double frequency_hz = 0.0;
  std::vector<double> speeds_mps = {0.05, 0.1, 0.2, 0.3, 0.4};
  int taps_per_speed = 1;
  double sample_rate_hz = 0.0;    // 0: 20 f, at least 2 kHz
  double pre_contact_s = 0.02;    // the onset's mean time in its tap
  double onset_jitter_s = 0.002;  // uniform +- this
  double snr_db = 20.0;
  /// Clip the first tap's signal at the level that 1 % (this fraction) of its samples exceed.
  double clip_fraction = 0.0;
  unsigned seed = 1;
};

/// A synthetic recording's CSV text (columns time_s, the signal, velocity_mps, tap), with a
/// comment header saying it is synthetic and how it was made.
std::string SyntheticTapsCsv(const SyntheticTapsOptions& options, const std::string& comment);

}  // namespace rigidtouch::analysis
