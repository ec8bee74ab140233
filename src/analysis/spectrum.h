// Power spectrum of a sampled force signal (FFTW), its dominant frequency and band energy
// fractions, and the repetition rate of a transient. Offline analysis: allocates, never runs
// inside the haptic loop.
#pragma once

#include <array>
#include <span>
#include <vector>

namespace rigidtouch::analysis {

/// How a signal window is turned into a spectrum.
struct SpectrumOptions {
  /// Taper applied before the transform. kHann suits steady signals; kTaperedEnd (flat, then a
  /// half-cosine over the last quarter) suits a transient that starts at the first sample, such
  /// as a tap from contact onset, which a Hann window would weigh by zero.
  enum class Window { kHann, kTaperedEnd };
  Window window = Window::kHann;
  /// Subtract the window's mean before windowing, so the sustained (pressing) force does not
  /// leak into the lowest bins and the spectrum describes the force's fluctuation.
  bool remove_mean = true;
  /// Zero-pad to the next power of two that is at least this many samples (and at least the
  /// signal length). Padding interpolates the spectrum; it adds no resolution.
  int min_fft_length = 0;
};

/// One-sided power spectrum: power[k] at frequency k * bin_hz, k = 0 .. fft_length / 2.
struct Spectrum {
  double sample_rate_hz = 0.0;
  double bin_hz = 0.0;        // sample_rate_hz / fft_length
  int fft_length = 0;         // power of two >= the signal length
  std::vector<double> power;  // |X_k|^2, doubled for 0 < k < fft_length / 2  [N^2]
};

/// Power spectrum of `signal` sampled at `sample_rate_hz`: optional mean removal, a Hann window
/// w[n] = 0.5 (1 - cos(2 pi n / (N - 1))) over the N samples, zero padding to a power of two,
/// then a real-to-complex FFT (FFTW). Returns an empty spectrum for fewer than 2 samples.
Spectrum PowerSpectrum(std::span<const double> signal, double sample_rate_hz,
                       const SpectrumOptions& options = {});

/// Frequency of the largest power bin, excluding DC (bin 0) [Hz]; 0 when every bin above DC is 0.
double DominantFrequencyHz(const Spectrum& spectrum);

/// Frequency of the largest power bin at or above `min_hz` (and above DC) [Hz]; NaN when every
/// such bin is 0. Used for a transient's vibration, whose envelope below `min_hz` is felt as part
/// of the press rather than as vibration.
double DominantFrequencyHz(const Spectrum& spectrum, double min_hz);

/// Power of the largest bin at or above `min_hz` (and above DC) over the mean power of those
/// bins: about 1 for a flat (broadband) spectrum such as one short pulse, much larger for a line
/// such as a periodic train. NaN when every such bin is 0.
double PeakToMeanPower(const Spectrum& spectrum, double min_hz);

/// Sum of the power above DC [N^2].
double PowerAboveDc(const Spectrum& spectrum);

/// Frequency resolution of a spectrum of `samples` samples at `sample_rate_hz`: the inverse of
/// the signal's duration [Hz]. Zero padding interpolates between such bins; it adds none.
double ResolutionHz(int samples, double sample_rate_hz);

/// A transient whose spectral peak-to-mean power (PeakToMeanPower at or above 40 Hz) is at or
/// below this has no repetition rate: one pulse gives about 1 (a flat spectrum), two equal pulses
/// 2, N equal evenly spaced pulses about N. A rate needs the period repeated.
inline constexpr double kRepetitionPeakToMean = 2.0;

/// How a transient repeats: the fundamental of a train of pulses (its repetition rate), or of a
/// decaying vibration (its period), rather than its largest spectral bin (a comb of one-tick
/// pulses has harmonics of nearly equal power, any of which can be the largest).
struct Repetition {
  double rate_hz = 0.0;      ///< 1 / period [Hz]; 0: none
  double periodicity = 0.0;  ///< normalised autocorrelation at the period, in [0, 1]; 0: none
};

/// Repetition of the transient `x` sampled every `h_s` seconds, whose spectral peak-to-mean power
/// at or above `min_hz` is `peak_to_mean`: none unless peak_to_mean > kRepetitionPeakToMean;
/// otherwise the period is the lag L from 2 samples (the Nyquist rate) to 1 / min_hz where the
/// biased autocorrelation c(L) = sum_k x[k] x[k + L] / sum_k x[k]^2 has its highest peak
/// (c(L - 1) < c(L) >= c(L + 1); the shortest lag on ties), and none if no peak is positive: a
/// ring slower than min_hz, whose c falls from lag 0 on, has none. The period is a whole number of
/// samples: at 1 kHz a rate is 1000 / L Hz (250, 200, 166.7, ...), exact for trains, whose impulses
/// fall on ticks. The biased estimate favours the period over its multiples (N equal pulses: (N -
/// 1) / N at the period, (N - 2) / N at twice it).
Repetition RepetitionOf(std::span<const double> x, double h_s, double min_hz, double peak_to_mean);

/// Edges between the four reported bands [Hz]: below 40, 40-100, 100-400, above 400.
inline constexpr std::array<double, 3> kDefaultBandEdgesHz = {40.0, 100.0, 400.0};

/// Fraction of the spectrum's power (DC bin excluded) in each band: bin frequency f in band i
/// when edges[i-1] <= f < edges[i] (edges[-1] = 0, edges[3] = infinity). All zeros when the
/// power above DC is 0.
std::array<double, 4> BandEnergyFractions(
    const Spectrum& spectrum, const std::array<double, 3>& edges_hz = kDefaultBandEdgesHz);

}  // namespace rigidtouch::analysis
