#include "analysis/spectrum.h"

#include <fftw3.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <mutex>
#include <numbers>

namespace rigidtouch::analysis {

namespace {

// fftw's planner is not thread-safe; only fftw_execute is
std::mutex& PlannerMutex() {
  static std::mutex mutex;
  return mutex;
}

int NextPowerOfTwo(int n) {
  int p = 1;
  while (p < n) p *= 2;
  return p;
}

}  // namespace

Spectrum PowerSpectrum(std::span<const double> signal, double sample_rate_hz,
                       const SpectrumOptions& options) {
  Spectrum spectrum;
  spectrum.sample_rate_hz = sample_rate_hz;
  const int n = static_cast<int>(signal.size());
  if (n < 2 || !(sample_rate_hz > 0.0)) return spectrum;

  const int fft_length = NextPowerOfTwo(std::max(n, options.min_fft_length));
  spectrum.fft_length = fft_length;
  spectrum.bin_hz = sample_rate_hz / fft_length;

  double mean = 0.0;
  if (options.remove_mean) {
    for (double x : signal) mean += x;
    mean /= n;
  }
  std::vector<double> input(static_cast<std::size_t>(fft_length), 0.0);
  for (int i = 0; i < n; ++i) {
    double window = 1.0;
    if (options.window == SpectrumOptions::Window::kHann) {
      window = 0.5 * (1.0 - std::cos(2.0 * std::numbers::pi * i / (n - 1)));
    } else {
      const double taper_start = 0.75 * (n - 1);
      if (i > taper_start) {
        window =
            0.5 * (1.0 + std::cos(std::numbers::pi * (i - taper_start) / (n - 1 - taper_start)));
      }
    }
    input[static_cast<std::size_t>(i)] = window * (signal[static_cast<std::size_t>(i)] - mean);
  }
  const int bins = fft_length / 2 + 1;
  std::vector<std::complex<double>> output(static_cast<std::size_t>(bins));

  fftw_plan plan;
  {
    const std::lock_guard<std::mutex> lock(PlannerMutex());
    // FFTW_ESTIMATE does not touch the arrays while planning
    plan = fftw_plan_dft_r2c_1d(fft_length, input.data(),
                                reinterpret_cast<fftw_complex*>(output.data()), FFTW_ESTIMATE);
  }
  fftw_execute(plan);
  {
    const std::lock_guard<std::mutex> lock(PlannerMutex());
    fftw_destroy_plan(plan);
  }

  spectrum.power.resize(static_cast<std::size_t>(bins));
  for (int k = 0; k < bins; ++k) {
    // one-sided: fold the negative frequencies onto the positive ones (not DC or Nyquist)
    const double scale = (k == 0 || 2 * k == fft_length) ? 1.0 : 2.0;
    spectrum.power[static_cast<std::size_t>(k)] =
        scale * std::norm(output[static_cast<std::size_t>(k)]);
  }
  return spectrum;
}

double DominantFrequencyHz(const Spectrum& spectrum) {
  std::size_t best = 0;
  double best_power = 0.0;
  for (std::size_t k = 1; k < spectrum.power.size(); ++k) {
    if (spectrum.power[k] > best_power) {
      best_power = spectrum.power[k];
      best = k;
    }
  }
  return static_cast<double>(best) * spectrum.bin_hz;
}

double DominantFrequencyHz(const Spectrum& spectrum, double min_hz) {
  std::size_t best = 0;
  double best_power = 0.0;
  for (std::size_t k = 1; k < spectrum.power.size(); ++k) {
    if (static_cast<double>(k) * spectrum.bin_hz < min_hz) continue;
    if (spectrum.power[k] > best_power) {
      best_power = spectrum.power[k];
      best = k;
    }
  }
  return best == 0 ? std::numeric_limits<double>::quiet_NaN()
                   : static_cast<double>(best) * spectrum.bin_hz;
}

double PeakToMeanPower(const Spectrum& spectrum, double min_hz) {
  double peak = 0.0, sum = 0.0;
  int bins = 0;
  for (std::size_t k = 1; k < spectrum.power.size(); ++k) {
    if (static_cast<double>(k) * spectrum.bin_hz < min_hz) continue;
    peak = std::max(peak, spectrum.power[k]);
    sum += spectrum.power[k];
    ++bins;
  }
  if (!(sum > 0.0)) return std::numeric_limits<double>::quiet_NaN();
  return peak / (sum / bins);
}

Repetition RepetitionOf(std::span<const double> x, double h_s, double min_hz, double peak_to_mean) {
  Repetition r;
  // a click's spectrum is flat (peak over mean about 1): no repetition
  if (!(peak_to_mean > kRepetitionPeakToMean) || !(h_s > 0.0) || !(min_hz > 0.0) || x.size() < 3) {
    return r;
  }
  double energy = 0.0;
  for (double v : x) energy += v * v;
  if (!(energy > 0.0)) return r;
  // lags bounded in double before the conversion (any h_s > 0 stays in range)
  const double hi_lag =
      std::min(static_cast<double>(x.size() - 1), std::floor(1.0 / (min_hz * h_s) + 1e-9));
  if (hi_lag < 2.0) return r;
  const auto hi = static_cast<std::size_t>(hi_lag);
  const auto correlation = [&x, energy](std::size_t lag) {
    double c = 0.0;
    for (std::size_t k = 0; k + lag < x.size(); ++k) c += x[k] * x[k + lag];
    return c / energy;
  };
  // a period is a peak of the autocorrelation: a smooth envelope (a ring slower than min_hz)
  // falls from lag 0 on and has none, where the highest value alone would be the shortest lag
  double before = correlation(1);
  double here = correlation(2);
  for (std::size_t lag = 2; lag <= hi; ++lag) {
    const double after = lag + 1 < x.size() ? correlation(lag + 1) : 0.0;
    if (here > before && here >= after && here > r.periodicity) {
      r.periodicity = std::min(here, 1.0);
      r.rate_hz = 1.0 / (static_cast<double>(lag) * h_s);
    }
    before = here;
    here = after;
  }
  return r;
}

double PowerAboveDc(const Spectrum& spectrum) {
  double sum = 0.0;
  for (std::size_t k = 1; k < spectrum.power.size(); ++k) sum += spectrum.power[k];
  return sum;
}

double ResolutionHz(int samples, double sample_rate_hz) {
  return samples > 0 && sample_rate_hz > 0.0 ? sample_rate_hz / samples : 0.0;
}

std::array<double, 4> BandEnergyFractions(const Spectrum& spectrum,
                                          const std::array<double, 3>& edges_hz) {
  std::array<double, 4> bands = {0.0, 0.0, 0.0, 0.0};
  double total = 0.0;
  for (std::size_t k = 1; k < spectrum.power.size(); ++k) {
    const double f_hz = static_cast<double>(k) * spectrum.bin_hz;
    std::size_t band = 0;
    while (band < 3 && f_hz >= edges_hz[band]) ++band;
    bands[band] += spectrum.power[k];
    total += spectrum.power[k];
  }
  if (total > 0.0) {
    for (double& b : bands) b /= total;
  }
  return bands;
}

}  // namespace rigidtouch::analysis
