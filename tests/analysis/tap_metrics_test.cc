#include "analysis/tap_metrics.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "device/presets.h"
#include "device/simulated_device.h"

namespace rigidtouch::analysis {
namespace {

constexpr double kTick = 0.001;  // 1 kHz trace
constexpr int kOnset = 10;       // first contact sample
constexpr double kSpeed = 0.1;   // approach speed [m/s]

// a tap along -z onto a wall at z = 0: the tool moves down at kSpeed and touches at kOnset
std::vector<TraceSample> SyntheticTap(int n) {
  std::vector<TraceSample> s(static_cast<std::size_t>(n));
  for (int k = 0; k < n; ++k) {
    TraceSample& x = s[static_cast<std::size_t>(k)];
    x.step = 1000 + k;
    x.tap = 0;
    x.time_s = 1.0 + k * kTick;
    x.tool_position_m = Vec3(0.0, 0.0, 0.001 - 0.0001 * k);
    x.tool_velocity_mps = Vec3(0.0, 0.0, -kSpeed);
    x.wall_normal = Vec3::UnitZ();
    x.tool_contacts = k >= kOnset ? 1 : 0;
    x.penetration_m = std::max(0.0, -x.tool_position_m.z());
  }
  return s;
}

TEST(TapMetricsTest, ForceRampGivesTheKnownRateHardness) {
  // F = g (t - t[onset - 1]) from onset: dF/dt = g = 2000 N/s, so rate hardness = g / v
  // = 20000 N/m on the first tick and over the first 10 ms (1e-9 relative: time rounding)
  const double g_N_per_s = 2000.0;
  std::vector<TraceSample> s = SyntheticTap(60);
  for (int k = kOnset; k < 60; ++k) {
    s[k].device_force_N.z() = g_N_per_s * (s[k].time_s - s[kOnset - 1].time_s);
  }
  TapMetrics m = ComputeTapMetrics(s);
  ASSERT_TRUE(m.contact);
  EXPECT_DOUBLE_EQ(m.contact_onset_time_s, s[kOnset].time_s);
  EXPECT_NEAR(m.approach_speed_mps, kSpeed, 1e-15);
  EXPECT_NEAR(m.rate_hardness_N_per_m, 20000.0, 20000.0 * 1e-9);
  EXPECT_NEAR(m.extended_rate_hardness_N_per_m, 20000.0, 20000.0 * 1e-9);
  EXPECT_NEAR(m.peak_force_N, g_N_per_s * 50 * kTick, 1e-9);

  // a 5 N jump 4 ms after onset: the extended window (10 ms) sees 2000 + 5000 N/s
  std::vector<TraceSample> jump = s;
  for (int k = kOnset + 4; k < 60; ++k) jump[k].device_force_N.z() += 5.0;
  m = ComputeTapMetrics(jump);
  EXPECT_NEAR(m.rate_hardness_N_per_m, 20000.0, 20000.0 * 1e-9);
  EXPECT_NEAR(m.extended_rate_hardness_N_per_m, 70000.0, 70000.0 * 1e-9);

  // the same jump 15 ms after onset is outside the window
  std::vector<TraceSample> late = s;
  for (int k = kOnset + 15; k < 60; ++k) late[k].device_force_N.z() += 5.0;
  m = ComputeTapMetrics(late);
  EXPECT_NEAR(m.extended_rate_hardness_N_per_m, 20000.0, 20000.0 * 1e-9);

  // an impulse-like first tick: 3 N at onset gives 3 N / 1 ms / 0.1 m/s = 30000 N/m
  std::vector<TraceSample> step = SyntheticTap(30);
  for (int k = kOnset; k < 30; ++k) step[k].device_force_N.z() = 3.0;
  EXPECT_NEAR(ComputeTapMetrics(step).rate_hardness_N_per_m, 30000.0, 30000.0 * 1e-9);
}

TEST(TapMetricsTest, ForceAlongTheOnsetNormal) {
  // a tilted wall: normal (0, 0.6, 0.8), approach along -normal at 0.1 m/s
  const Vec3 n(0.0, 0.6, 0.8);
  std::vector<TraceSample> s = SyntheticTap(40);
  for (int k = 0; k < 40; ++k) {
    s[k].wall_normal = n;
    s[k].tool_velocity_mps = -kSpeed * n + Vec3(0.05, 0.0, 0.0);  // tangential part ignored
    if (k >= kOnset) s[k].device_force_N = 2.0 * n + Vec3(1.0, 0.0, 0.0);
  }
  const TapMetrics m = ComputeTapMetrics(s);
  EXPECT_NEAR(m.approach_speed_mps, kSpeed, 1e-15);
  EXPECT_NEAR(m.peak_force_N, 2.0, 1e-15);
  EXPECT_NEAR(m.rate_hardness_N_per_m, 2.0 / kTick / kSpeed, 1e-6);
}

TEST(TapMetricsTest, PenetrationAndTimeToStop) {
  // speed falls by 0.01 m/s per tick from onset: 0 at onset + 10 ticks = 10 ms
  std::vector<TraceSample> s = SyntheticTap(40);
  double z = s[kOnset].tool_position_m.z();
  for (int k = kOnset; k < 40; ++k) {
    const double v = std::max(0.0, kSpeed - 0.01 * (k - kOnset));
    s[k].tool_velocity_mps.z() = -v;
    s[k].tool_position_m.z() = z;
    s[k].penetration_m = std::max(0.0, -z);
    z -= v * kTick;
  }
  const TapMetrics m = ComputeTapMetrics(s);
  EXPECT_NEAR(m.time_to_stop_s, 10 * kTick, 1e-12);
  // deepest point: sum of the speeds times the tick after z = 0 (onset z = 0)
  double expected_m = 0.0;
  for (int k = 0; k < 10; ++k) expected_m += (kSpeed - 0.01 * k) * kTick;
  EXPECT_NEAR(m.max_penetration_m, expected_m, 1e-15);
  EXPECT_EQ(m.bounces, 0);
}

TEST(TapMetricsTest, TwoSeparationsInsideATapAreTwoBounces) {
  std::vector<TraceSample> s = SyntheticTap(40);
  // contact intervals [10, 14), [17, 20), [25, 35); the final release at 35 is no bounce
  for (int k = 0; k < 40; ++k) {
    const bool c = (k >= 10 && k < 14) || (k >= 17 && k < 20) || (k >= 25 && k < 35);
    s[k].tool_contacts = c ? 1 : 0;
  }
  EXPECT_EQ(ComputeTapMetrics(s).bounces, 2);
  // a single interval: none
  for (int k = 0; k < 40; ++k) s[k].tool_contacts = (k >= 10 && k < 35) ? 2 : 0;
  EXPECT_EQ(ComputeTapMetrics(s).bounces, 0);
}

TEST(TapMetricsTest, EnergyIsHeldForceTimesDisplacement) {
  // F = (0.5, 0, 2) N held, steps dx = (0.2, 0, -0.1) mm per tick:
  // each step delivers 0.5 * 2e-4 - 2 * 1e-4 = -1e-4 J (the user pushes against the force)
  const int n = 30;
  std::vector<TraceSample> s = SyntheticTap(n);
  for (int k = 0; k < n; ++k) {
    s[k].device_force_N = Vec3(0.5, 0.0, 2.0);
    s[k].tool_position_m = Vec3(0.0002 * k, 0.0, 0.001 - 0.0001 * k);
  }
  const double expected_J = -(n - 1) * 1e-4;
  EXPECT_NEAR(ComputeTapMetrics(s).energy_to_user_J, expected_J, 1e-15 * n);
  EXPECT_NEAR(EnergyToUserJ(s), expected_J, 1e-15 * n);
  const std::vector<double> cumulative = CumulativeEnergyToUserJ(s);
  ASSERT_EQ(cumulative.size(), static_cast<std::size_t>(n));
  EXPECT_EQ(cumulative.front(), 0.0);
  EXPECT_NEAR(cumulative[10], -10 * 1e-4, 1e-15 * n);
  EXPECT_NEAR(cumulative.back(), expected_J, 1e-15 * n);
}

TEST(TapMetricsTest, ImpulsesClippingAndSpectrum) {
  // 2 N pressing force with a 0.5 N 250 Hz ripple over 150 ms after onset
  const int n = kOnset + 150;
  std::vector<TraceSample> s = SyntheticTap(n);
  for (int k = kOnset; k < n; ++k) {
    const double t = s[k].time_s - s[kOnset].time_s;
    s[k].device_force_N.z() = 2.0 + 0.5 * std::sin(2.0 * std::numbers::pi * 250.0 * t);
  }
  s[kOnset].impulses = 1;
  s[kOnset].kinetic_energy_before_J = 0.003;
  s[kOnset].kinetic_energy_after_J = 0.0015;
  s[kOnset + 4].impulses = 1;
  s[kOnset + 4].kinetic_energy_before_J = 0.0016;
  s[kOnset + 4].kinetic_energy_after_J = 0.0;
  s[kOnset + 2].clipped = true;
  const TapMetrics m = ComputeTapMetrics(s);
  ASSERT_EQ(m.impulses.size(), 2u);
  EXPECT_EQ(m.impulses[0].time_s, s[kOnset].time_s);
  EXPECT_EQ(m.impulses[0].kinetic_energy_before_J, 0.003);
  EXPECT_EQ(m.impulses[0].kinetic_energy_after_J, 0.0015);
  EXPECT_EQ(m.impulses[1].time_s, s[kOnset + 4].time_s);
  EXPECT_EQ(m.impulses[1].kinetic_energy_after_J, 0.0);
  EXPECT_TRUE(m.force_clipped);
  // 100 ms window at 1 kHz: 10 Hz resolution, most power in 100-400 Hz
  EXPECT_NEAR(m.spectrum_window_s, 0.1, 1e-9);
  EXPECT_GT(m.band_energy_fraction[2], 0.9);
}

TEST(TapMetricsTest, TapWithoutContact) {
  std::vector<TraceSample> s = SyntheticTap(20);
  for (TraceSample& x : s) {
    x.tool_contacts = 0;
    x.penetration_m = 0.0;
  }
  const TapMetrics m = ComputeTapMetrics(s);
  EXPECT_FALSE(m.contact);
  EXPECT_TRUE(std::isnan(m.rate_hardness_N_per_m));
  EXPECT_TRUE(std::isnan(m.time_to_stop_s));
  EXPECT_EQ(m.bounces, 0);
  EXPECT_EQ(m.max_penetration_m, 0.0);
}

TEST(TapMetricsTest, SplitTapsByScriptedIndex) {
  std::vector<TraceSample> s(10);
  const int taps[] = {-1, 0, 0, -1, -1, 1, 1, 1, -1, 2};
  for (int k = 0; k < 10; ++k) s[k].tap = taps[k];
  const auto spans = SplitTaps(s);
  ASSERT_EQ(spans.size(), 3u);
  EXPECT_EQ(spans[0].size(), 2u);
  EXPECT_EQ(spans[0].data(), &s[1]);
  EXPECT_EQ(spans[1].size(), 3u);
  EXPECT_EQ(spans[1].front().tap, 1);
  EXPECT_EQ(spans[2].size(), 1u);
  EXPECT_EQ(spans[2].front().tap, 2);
  EXPECT_TRUE(SplitTaps({}).empty());
}

// the offline tap loop (Read, render, Write, Advance, record) on the simulated Touch with a
// penalty wall at z = 0 rendered from the device's readings: F = max(0, k p - b v_z)
std::vector<TraceSample> SimulatedPenaltyTaps(device::SimulatedDevice& dev, double k_N_per_m,
                                              double b_Ns_per_m) {
  std::vector<TraceSample> trace;
  std::int64_t step = 0;
  while (!dev.finished()) {
    const DeviceState state = dev.Read();
    const double p_m = -state.position_m.z();
    DeviceCommand command;
    if (p_m > 0.0) {
      command.penalty_force_N.z() =
          std::max(0.0, k_N_per_m * p_m - b_Ns_per_m * state.velocity_mps.z());
    }
    command.force_N = command.penalty_force_N;
    TraceSample sample;
    sample.step = step++;
    sample.tap = dev.current_tap();
    sample.time_s = dev.time_s();
    sample.tool_position_m = dev.true_position_m();
    sample.tool_velocity_mps = dev.true_velocity_mps();
    sample.hand_force_N = dev.hand_force_N();
    sample.penetration_m = std::max(0.0, p_m);
    sample.tool_contacts = p_m > 0.0 ? 1 : 0;
    dev.Write(command);
    sample.penalty_force_N = command.penalty_force_N;
    sample.device_force_N = dev.displayed_force_N();
    sample.clipped = dev.last_command_clipped();
    dev.Advance(dev.tick_s());
    trace.push_back(sample);
  }
  return trace;
}

TEST(TapMetricsTest, SimulatedTapsOnAPassivePenaltyWall) {
  device::TapScript script;
  script.taps = 3;
  script.approach_speed_mps = 0.15;
  device::SimulatedDevice dev(device::FindPreset("touch"), device::HandParams{},
                              device::DeviceModelParams{}, script);
  // Touch limits: 400 N/m, 4 N s/m; b = 1 N s/m exceeds k T / 2 = 0.2 N s/m
  const std::vector<TraceSample> trace = SimulatedPenaltyTaps(dev, 400.0, 1.0);

  // the trace's ZOH energy over the whole run equals the device's own bookkeeping (same
  // positions, same held forces; rounding only)
  EXPECT_NEAR(EnergyToUserJ(trace), dev.energy_to_user_J(), 1e-12);

  const auto taps = SplitTaps(trace);
  ASSERT_EQ(taps.size(), 3u);
  for (std::size_t i = 0; i < taps.size(); ++i) {
    const TapMetrics m = ComputeTapMetrics(taps[i]);
    EXPECT_EQ(m.tap, static_cast<int>(i));
    ASSERT_TRUE(m.contact);
    // with the inertia feedforward the hand arrives at the scripted speed (2%)
    EXPECT_NEAR(m.approach_speed_mps, 0.15, 0.02 * 0.15);
    EXPECT_LE(m.energy_to_user_J, 0.0);  // passive wall, tap starts and ends out of contact
    EXPECT_GT(m.max_penetration_m, 0.0);
    EXPECT_GT(m.peak_force_N, 0.0);
    EXPECT_LE(m.peak_force_N, 3.3 + 1e-12);  // the Touch's force limit
    EXPECT_GE(m.rate_hardness_N_per_m, 0.0);
    EXPECT_FALSE(std::isnan(m.time_to_stop_s));
  }
}

}  // namespace
}  // namespace rigidtouch::analysis

namespace rigidtouch::analysis {
namespace {

// The spectrum claims of docs/tap.md on a signal of known content: a slow press (a 40 ms
// half-sine of 5 N, all of its power below 40 Hz but its leakage) with a 250 Hz train of 2 N
// one-tick impulses on top (every 4th tick at 1 kHz). The displayed force is dominated by the
// press; its transient part (displayed minus penalty) is the train, whose spectrum has its line
// at 250 Hz exactly (bin 32 of the 128-point transform).
TEST(TapMetricsTest, TrainOnASlowPressSeparatesDisplayedAndTransientSpectra) {
  const int n = kOnset + 150;
  std::vector<TraceSample> s = SyntheticTap(n);
  for (int k = kOnset; k < n; ++k) {
    const double t = s[k].time_s - s[kOnset].time_s;
    const double press = t < 0.04 ? 5.0 * std::sin(std::numbers::pi * t / 0.04) : 0.0;
    s[k].penalty_force_N.z() = press;
    s[k].impulsive_force_N.z() = (k - kOnset) % 4 == 0 && t < 0.1 ? 2.0 : 0.0;
    s[k].impulses = s[k].impulsive_force_N.z() > 0 ? 1 : 0;
    s[k].device_force_N = s[k].penalty_force_N + s[k].impulsive_force_N;
  }
  TapMetrics m = ComputeTapMetrics(s);
  // the press: the first bin above DC (7.8 Hz), below the 10 Hz resolution of 100 ms (exactly
  // 100 samples, although the trace's times 1.0 + k * 0.001 are rounded)
  EXPECT_NEAR(m.spectrum_resolution_hz, 1000.0 / 100.0, 1e-9);
  EXPECT_NEAR(m.spectrum_window_s, 0.1, 1e-9);
  EXPECT_GT(m.band_energy_fraction[0], 0.5);
  // the train: its repetition rate 250 Hz exactly (a pulse every 4 ticks; 25 pulses, 24/25 at
  // the period), a line far above the mean (> 10), most of its power in 100-400 Hz and above 400
  // (the 500 Hz line of one-tick pulses), little below 40 Hz
  EXPECT_NEAR(m.transient_repetition_hz, 250.0, 1e-9);
  EXPECT_NEAR(m.transient_periodicity, 24.0 / 25.0, 1e-12);
  EXPECT_GT(m.transient_peak_to_mean, 10.0);
  EXPECT_GT(m.transient_band_energy_fraction[2], 0.5);
  EXPECT_LT(m.transient_band_energy_fraction[0], 0.1);
  EXPECT_GT(m.transient_power_ratio, 0.0);
  // pure penalty: no transient part at all (NaN, not a frequency)
  for (TraceSample& x : s) x.device_force_N = x.penalty_force_N;
  m = ComputeTapMetrics(s);
  EXPECT_TRUE(std::isnan(m.transient_repetition_hz));
  EXPECT_EQ(m.transient_power_ratio, 0.0);
}

// one clipped onset pulse: a flat transient (peak over mean power 1 within 0.1: the mean removal
// perturbs the lowest bins only), the requested peak the unclipped one
TEST(TapMetricsTest, ClippedSinglePulseIsAFlatTransient) {
  std::vector<TraceSample> s = SyntheticTap(kOnset + 150);
  s[kOnset].impulsive_force_N.z() = 60.0;
  s[kOnset].penalty_force_N.z() = 1.0;
  s[kOnset].device_force_N.z() = 12.0;
  s[kOnset].clipped = true;
  s[kOnset].impulses = 1;
  const TapMetrics m = ComputeTapMetrics(s);
  EXPECT_EQ(m.peak_requested_force_N, 61.0);
  EXPECT_EQ(m.peak_force_N, 12.0);
  ASSERT_EQ(m.impulses.size(), 1u);
  EXPECT_EQ(m.impulses[0].requested_force_N, 60.0);
  EXPECT_NEAR(m.transient_peak_to_mean, 1.0, 0.1);
}

// Extended rate hardness against rate hardness on a train: the first tick rises by the first
// impulse a, the second impulse (4 ticks later) rises by b > a on top of a penalty ramp of r per
// tick; rate hardness = a / (h v), extended = (b + r) / (h v); with b < a both are a / (h v)
TEST(TapMetricsTest, ExtendedRateHardnessSeesALaterLargerRise) {
  const double a = 2.0, b = 3.0, r = 0.1;
  auto train = [&](double second) {
    std::vector<TraceSample> s = SyntheticTap(60);
    for (int k = kOnset; k < 60; ++k) {
      const int since = k - kOnset;
      s[k].penalty_force_N.z() = r * since;
      s[k].impulsive_force_N.z() = since == 0 ? a : since == 4 ? second : 0.0;
      s[k].device_force_N = s[k].penalty_force_N + s[k].impulsive_force_N;
    }
    return ComputeTapMetrics(s);
  };
  const double hv = kTick * kSpeed;
  TapMetrics m = train(b);
  EXPECT_NEAR(m.rate_hardness_N_per_m, a / hv, 1e-9 * a / hv);
  EXPECT_NEAR(m.extended_rate_hardness_N_per_m, (b + r) / hv, 1e-9 * b / hv);
  m = train(1.0);
  EXPECT_NEAR(m.extended_rate_hardness_N_per_m, m.rate_hardness_N_per_m, 1e-9 * a / hv);
}

}  // namespace
}  // namespace rigidtouch::analysis

namespace rigidtouch::analysis {
namespace {

// The collision window is 100 ticks at 1 kHz wherever the tap starts, although times summed
// sub-step by sub-step (as the simulated device's clock is) are rounded: 100 ticks after onset
// may read 0.09999999999998899 s, and one sample more would make the window 101 ticks and its
// resolution 9.9 Hz (onsets from tick 46 on do so without the tolerance); likewise the extended
// rate hardness's 10 ms must hold tick onset + 10 wherever the tap starts
TEST(TapMetricsTest, WindowsAreWholeNumbersOfTicksDespiteRoundedTimes) {
  for (int start = 0; start < 200; start += 7) {
    std::vector<TraceSample> s = SyntheticTap(kOnset + 150);
    double t = 0.0;
    const auto tick = [&t] {
      for (int j = 0; j < 10; ++j) t += kTick / 10;
    };
    for (int k = 0; k < start; ++k) tick();
    for (TraceSample& x : s) {
      x.time_s = t;
      x.device_force_N.z() = x.tool_contacts > 0 ? 1.0 + 0.1 * (x.step % 3) : 0.0;
      // a 5 N step 10 ticks after onset: inside the extended rate hardness's 10 ms
      if (x.step - s.front().step >= kOnset + 10) x.device_force_N.z() += 5.0;
      tick();
    }
    const TapMetrics m = ComputeTapMetrics(s);
    EXPECT_NEAR(m.spectrum_resolution_hz, 10.0, 1e-6) << start;
    // the step's rise, 5 N +- 0.2 N of ripple, over one tick and the approach speed
    EXPECT_GT(m.extended_rate_hardness_N_per_m, 4.7 / (kTick * kSpeed)) << start;
  }
}

}  // namespace
}  // namespace rigidtouch::analysis
