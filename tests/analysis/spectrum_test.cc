#include "analysis/spectrum.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

namespace rigidtouch::analysis {
namespace {

std::vector<double> Sine(double f_hz, double rate_hz, double duration_s, double amplitude = 1.0,
                         double offset = 0.0) {
  const int n = static_cast<int>(std::lround(duration_s * rate_hz));
  std::vector<double> x(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    x[static_cast<std::size_t>(i)] =
        offset + amplitude * std::sin(2.0 * std::numbers::pi * f_hz * i / rate_hz + 0.3);
  }
  return x;
}

TEST(SpectrumTest, LengthIsZeroPaddedToAPowerOfTwo) {
  const Spectrum s = PowerSpectrum(Sine(250.0, 1000.0, 0.1), 1000.0);
  EXPECT_EQ(s.fft_length, 128);  // 100 samples -> 128
  EXPECT_EQ(s.power.size(), 65u);
  EXPECT_DOUBLE_EQ(s.bin_hz, 1000.0 / 128.0);
  SpectrumOptions longer;
  longer.min_fft_length = 1000;
  EXPECT_EQ(PowerSpectrum(Sine(250.0, 1000.0, 0.1), 1000.0, longer).fft_length, 1024);
}

TEST(SpectrumTest, Sine250HzAt1kHzOver100ms) {
  const Spectrum s = PowerSpectrum(Sine(250.0, 1000.0, 0.1), 1000.0);
  // within one bin (7.8 Hz) of 250 Hz
  EXPECT_NEAR(DominantFrequencyHz(s), 250.0, s.bin_hz);
  const auto bands = BandEnergyFractions(s);
  EXPECT_GT(bands[2], 0.9);  // 100-400 Hz
  EXPECT_NEAR(bands[0] + bands[1] + bands[2] + bands[3], 1.0, 1e-12);
}

TEST(SpectrumTest, Sine50HzFallsInThe40To100Band) {
  // 0.5 s gives 2 Hz resolution, so the Hann main lobe (+-4 Hz) stays inside 40-100 Hz
  const Spectrum s = PowerSpectrum(Sine(50.0, 1000.0, 0.5), 1000.0);
  EXPECT_NEAR(DominantFrequencyHz(s), 50.0, s.bin_hz);
  EXPECT_GT(BandEnergyFractions(s)[1], 0.9);
}

TEST(SpectrumTest, TwoEqualSinesSplitThePower) {
  // 20 Hz and 600 Hz of equal amplitude at 2 kHz over 0.2 s: half the power each, +-5%
  std::vector<double> x = Sine(20.0, 2000.0, 0.2);
  const std::vector<double> y = Sine(600.0, 2000.0, 0.2);
  for (std::size_t i = 0; i < x.size(); ++i) x[i] += y[i];
  const auto bands = BandEnergyFractions(PowerSpectrum(x, 2000.0));
  EXPECT_NEAR(bands[0], 0.5, 0.05);
  EXPECT_NEAR(bands[3], 0.5, 0.05);
  EXPECT_LT(bands[1] + bands[2], 0.01);
}

TEST(SpectrumTest, MeanRemovalKeepsAPressingForceOutOfTheSpectrum) {
  // a 2 N pressing force plus a 0.1 N 250 Hz ripple: with the mean removed the ripple dominates
  const std::vector<double> x = Sine(250.0, 1000.0, 0.1, 0.1, 2.0);
  const Spectrum with_mean_removed = PowerSpectrum(x, 1000.0);
  EXPECT_NEAR(DominantFrequencyHz(with_mean_removed), 250.0, with_mean_removed.bin_hz);
  EXPECT_GT(BandEnergyFractions(with_mean_removed)[2], 0.9);
  SpectrumOptions keep;
  keep.remove_mean = false;
  const Spectrum raw = PowerSpectrum(x, 1000.0, keep);
  // the window's leakage of the 2 N offset (Hann first side bin: half of DC) beats the ripple
  EXPECT_LT(DominantFrequencyHz(raw), 2.0 * raw.bin_hz + 1e-9);
  // DC bin: (sum of window * 2 N)^2, window sum (N - 1) / 2 = 49.5 for N = 100, +-1% for ripple
  EXPECT_NEAR(raw.power[0], std::pow(2.0 * 49.5, 2), 0.01 * std::pow(2.0 * 49.5, 2));
}

TEST(SpectrumTest, ConstantSignalHasNoPowerAboveDc) {
  const std::vector<double> x(64, 3.0);
  const Spectrum s = PowerSpectrum(x, 1000.0);
  EXPECT_EQ(DominantFrequencyHz(s), 0.0);
  const auto bands = BandEnergyFractions(s);
  for (double b : bands) EXPECT_EQ(b, 0.0);
}

TEST(SpectrumTest, BandEdgesAreLowerInclusive) {
  // hand-built spectrum: bins at 0, 40, 80, ... Hz, unit power each
  Spectrum s;
  s.bin_hz = 40.0;
  s.power.assign(12, 1.0);  // 0 .. 440 Hz
  const auto bands = BandEnergyFractions(s);
  // above DC: 40..440 = 11 bins; [0,40): none; [40,100): 40,80; [100,400): 120..360 (7); 400, 440
  EXPECT_DOUBLE_EQ(bands[0], 0.0);
  EXPECT_DOUBLE_EQ(bands[1], 2.0 / 11.0);
  EXPECT_DOUBLE_EQ(bands[2], 7.0 / 11.0);
  EXPECT_DOUBLE_EQ(bands[3], 2.0 / 11.0);
}

TEST(SpectrumTest, TooShortSignalGivesAnEmptySpectrum) {
  EXPECT_TRUE(PowerSpectrum(std::vector<double>{1.0}, 1000.0).power.empty());
  EXPECT_TRUE(PowerSpectrum(std::vector<double>{1.0, 2.0}, 0.0).power.empty());
}

}  // namespace
}  // namespace rigidtouch::analysis

namespace rigidtouch::analysis {
namespace {

// a transient at the first sample: the Hann window weighs it by zero (no energy above DC), the
// end-tapered window keeps it (a unit impulse has a flat spectrum: every band gets its share)
TEST(SpectrumTest, TaperedEndWindowKeepsAnImpulseAtTheFirstSample) {
  std::vector<double> x(100, 0.0);
  x[0] = 1.0;
  SpectrumOptions hann;
  hann.remove_mean = false;
  const Spectrum h = PowerSpectrum(x, 1000.0, hann);
  double hann_energy = 0.0;
  for (double p : h.power) hann_energy += p;
  EXPECT_EQ(hann_energy, 0.0);
  SpectrumOptions tapered = hann;
  tapered.window = SpectrumOptions::Window::kTaperedEnd;
  const Spectrum t = PowerSpectrum(x, 1000.0, tapered);
  const auto bands = BandEnergyFractions(t);
  // flat spectrum up to 500 Hz: band widths 40, 60, 300, 100 Hz of 500 (tolerance: one 7.8 Hz
  // bin of the 128-point transform at each edge, 0.02)
  EXPECT_NEAR(bands[0], 40.0 / 500.0, 0.02);
  EXPECT_NEAR(bands[1], 60.0 / 500.0, 0.02);
  EXPECT_NEAR(bands[2], 300.0 / 500.0, 0.02);
  EXPECT_NEAR(bands[3], 100.0 / 500.0, 0.02);
}

}  // namespace
}  // namespace rigidtouch::analysis

namespace rigidtouch::analysis {
namespace {

// Closed forms for the peak measures: a unit pulse at the first sample has |X(f)| = 1 at every
// frequency (flat: peak over mean power 1), a comb of period 4 samples at 1 kHz has lines at 0,
// 250 and 500 Hz only (the one-sided 250 Hz line twice the 500 Hz one)
TEST(SpectrumTest, PeakAboveAFrequencyAndItsProminence) {
  SpectrumOptions tapered;
  tapered.remove_mean = false;
  tapered.window = SpectrumOptions::Window::kTaperedEnd;
  std::vector<double> pulse(100, 0.0);
  pulse[0] = 1.0;
  const Spectrum flat = PowerSpectrum(pulse, 1000.0, tapered);
  // every bin exactly 1 (2 one-sided) but DC and Nyquist: the ratio is 1 to rounding
  EXPECT_NEAR(PeakToMeanPower(flat, 40.0), 1.0, 0.01);

  std::vector<double> comb(128, 0.0);
  for (std::size_t k = 0; k < comb.size(); k += 4) comb[k] = 1.0;
  SpectrumOptions plain;
  plain.remove_mean = false;
  plain.window = SpectrumOptions::Window::kTaperedEnd;
  plain.min_fft_length = 128;
  // no taper would leave exact lines; the taper spreads each line over a few 7.8 Hz bins
  const Spectrum lines = PowerSpectrum(comb, 1000.0, plain);
  EXPECT_EQ(DominantFrequencyHz(lines, 40.0), 250.0);
  EXPECT_GT(PeakToMeanPower(lines, 40.0), 10.0);
  // nothing above 600 Hz in a 1 kHz spectrum: NaN, not 0
  EXPECT_TRUE(std::isnan(DominantFrequencyHz(lines, 600.0)));
  EXPECT_TRUE(
      std::isnan(PeakToMeanPower(PowerSpectrum(std::vector<double>(100, 0.0), 1000.0), 40.0)));
  EXPECT_DOUBLE_EQ(ResolutionHz(100, 1000.0), 10.0);
}

// pulses of 1 N every `period` ticks of 1 ms, `count` of them, in a 100 ms window
std::vector<double> Pulses(int count, int period) {
  std::vector<double> x(100, 0.0);
  for (int i = 0; i < count; ++i) x[static_cast<std::size_t>(i * period)] = 1.0;
  return x;
}

// closed forms: N equal pulses have autocorrelation (N - 1) / N at their period; the rate is the
// pulses' (not a harmonic); nothing at or below the peak-to-mean threshold (a click's flat
// spectrum), nothing without a peak of the autocorrelation (a smooth envelope)
TEST(SpectrumTest, RepetitionOfPulseTrainsClosedForms) {
  const double h = 1e-3;
  const double min_hz = 40.0;
  // one pulse: flat spectrum (peak over mean 1), and no repetition even if the gate let it in
  EXPECT_EQ(RepetitionOf(Pulses(1, 4), h, min_hz, 1.0).rate_hz, 0.0);
  EXPECT_EQ(RepetitionOf(Pulses(1, 4), h, min_hz, 3.0).rate_hz, 0.0);
  EXPECT_EQ(RepetitionOf(Pulses(1, 4), h, min_hz, 3.0).periodicity, 0.0);
  // two pulses 4 ms apart: peak over mean 2, at the threshold: none; above it: 250 Hz, 1/2
  EXPECT_EQ(RepetitionOf(Pulses(2, 4), h, min_hz, kRepetitionPeakToMean).rate_hz, 0.0);
  EXPECT_EQ(RepetitionOf(Pulses(2, 4), h, min_hz, kRepetitionPeakToMean).periodicity, 0.0);
  const Repetition two = RepetitionOf(Pulses(2, 4), h, min_hz, 2.5);
  EXPECT_NEAR(two.rate_hz, 250.0, 1e-9);
  EXPECT_NEAR(two.periodicity, 0.5, 1e-12);
  // three pulses 20 ms apart: 50 Hz (not the 250 Hz harmonic a largest bin can give), 2/3
  const Repetition three = RepetitionOf(Pulses(3, 20), h, min_hz, 3.0);
  EXPECT_NEAR(three.rate_hz, 50.0, 1e-9);
  EXPECT_NEAR(three.periodicity, 2.0 / 3.0, 1e-12);
  // a 250 Hz train over the whole window: 25 pulses, 24/25 at 4 ms (8 ms gives 23/25)
  const Repetition train = RepetitionOf(Pulses(25, 4), h, min_hz, 20.0);
  EXPECT_NEAR(train.rate_hz, 250.0, 1e-9);
  EXPECT_NEAR(train.periodicity, 24.0 / 25.0, 1e-12);
  // the Nyquist rate: a pulse every other tick is 500 Hz, 49/50
  const Repetition nyquist = RepetitionOf(Pulses(50, 2), h, min_hz, 20.0);
  EXPECT_NEAR(nyquist.rate_hz, 500.0, 1e-9);
  EXPECT_NEAR(nyquist.periodicity, 49.0 / 50.0, 1e-12);
  // pulses 40 ms apart (25 Hz) lie below min_hz: no lag in 2-25 ms correlates
  EXPECT_EQ(RepetitionOf(Pulses(3, 40), h, min_hz, 3.0).rate_hz, 0.0);
  // nothing to analyse
  EXPECT_EQ(RepetitionOf(std::vector<double>(100, 0.0), h, min_hz, 3.0).rate_hz, 0.0);
  EXPECT_EQ(RepetitionOf(Pulses(3, 20), 0.0, min_hz, 3.0).rate_hz, 0.0);
  // a constant, or a ring at 20 Hz (below min_hz), correlates less at every longer lag: no peak,
  // no rate (the highest value alone would give the shortest lag, 500 Hz)
  EXPECT_EQ(RepetitionOf(std::vector<double>(100, 1.0), h, min_hz, 3.0).rate_hz, 0.0);
  std::vector<double> ring(100);
  for (std::size_t k = 0; k < ring.size(); ++k) {
    ring[k] = std::exp(-20.0 * k * h) * std::sin(2.0 * std::numbers::pi * 20.0 * k * h);
  }
  EXPECT_EQ(RepetitionOf(ring, h, min_hz, 3.0).rate_hz, 0.0);
  // a decaying 125 Hz vibration: its period, 8 ticks
  for (std::size_t k = 0; k < ring.size(); ++k) {
    ring[k] = std::exp(-30.0 * k * h) * std::sin(2.0 * std::numbers::pi * 125.0 * k * h);
  }
  EXPECT_NEAR(RepetitionOf(ring, h, min_hz, 3.0).rate_hz, 125.0, 1e-9);
}

}  // namespace
}  // namespace rigidtouch::analysis
