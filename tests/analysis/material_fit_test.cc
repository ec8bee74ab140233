// Materials from measurements (analysis/material_fit.h): the fit recovers known parameters from
// synthetic recordings with noise and onset jitter, refuses recordings that cannot support a fit
// with the reason and the line, and the fitted material renders passively as a material train.
#include "analysis/material_fit.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <numbers>
#include <string>
#include <vector>

#include "analysis/tap_experiment.h"
#include "device/presets.h"
#include "io/materials.h"
#include "rigidtouch/types.h"

namespace rigidtouch::analysis {
namespace {

io::TapRecording Synthetic(const SyntheticTapsOptions& o, const std::string& name = "taps.csv") {
  return io::ParseTapRecording(SyntheticTapsCsv(o, "# synthetic\n"), name);
}

SyntheticTapsOptions FromPreset(const Material& m, unsigned seed) {
  SyntheticTapsOptions o;
  o.slope = m.amplitude_Ns_per_m / 0.599;  // an acceleration per speed, as `material synth`
  o.decay_per_s = m.decay_per_s;
  o.frequency_hz = m.frequency_hz;
  o.seed = seed;
  return o;  // five speeds 0.05-0.4 m/s, one tap each, SNR 20 dB, onset 20 ms +- 2 ms
}

std::string FitError(const std::vector<io::TapRecording>& r) {
  try {
    MaterialFitOptions o;
    o.effective_mass_kg = 0.6;
    FitMaterial(r, o);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

// every preset, five seeds: recordings at SNR 20 dB with a +-2 ms onset jitter off the sample
// grid, five impact speeds and three taps at each give f, B and A's slope within 2 % (the issue's
// tolerance). One tap per speed is not enough for 2 % at 20 dB: B's standard error over five
// taps is about 1 %, and seeds reach 2.5 % (docs/materials.md)
TEST(MaterialFitTest, RecoversFrequencyDecayAndSlopeWithinTwoPercent) {
  for (const Material& m : io::MaterialPresets()) {
    double worst_f = 0.0, worst_b = 0.0, worst_a = 0.0, worst_r2 = 1.0;
    for (unsigned seed = 1; seed <= 5; ++seed) {
      SyntheticTapsOptions o = FromPreset(m, seed);
      o.taps_per_speed = 3;
      const std::vector<io::TapRecording> r = {Synthetic(o)};
      MaterialFitOptions fo;
      fo.effective_mass_kg = 0.599;
      const MaterialFit fit = FitMaterial(r, fo);
      ASSERT_EQ(fit.taps.size(), 15u);
      const double ef = std::abs(fit.material.frequency_hz / m.frequency_hz - 1.0);
      const double eb = std::abs(fit.material.decay_per_s / m.decay_per_s - 1.0);
      const double ea = std::abs(fit.amplitude.slope / o.slope - 1.0);
      EXPECT_LT(ef, 0.02) << m.name << " seed " << seed;
      EXPECT_LT(eb, 0.02) << m.name << " seed " << seed;
      EXPECT_LT(ea, 0.02) << m.name << " seed " << seed;
      EXPECT_NEAR(fit.material.amplitude_Ns_per_m, m.amplitude_Ns_per_m,
                  0.02 * m.amplitude_Ns_per_m);
      worst_f = std::max(worst_f, ef);
      worst_b = std::max(worst_b, eb);
      worst_a = std::max(worst_a, ea);
      for (const TapFit& t : fit.taps) {
        worst_r2 = std::min(worst_r2, t.r2);
        const double v = o.speeds_mps[static_cast<std::size_t>(t.tap / o.taps_per_speed)];
        EXPECT_NEAR(t.impact_speed_mps, v, 0.02 * v);
        EXPECT_GT(t.frequency_sd_hz, 0.0);
        EXPECT_GT(t.decay_sd_per_s, 0.0);
      }
    }
    std::cout << m.name << ": worst relative error over 5 seeds: f " << worst_f << ", B " << worst_b
              << ", slope " << worst_a << "; lowest tap R^2 " << worst_r2 << "\n";
  }
}

// a tap fitted alone: the Jacobian's standard deviations cover the truth (within 4 sd) and the
// onset lands within half a sample of the true one's spread (the detector's sample is later)
TEST(MaterialFitTest, UncertaintiesCoverTheTruth) {
  SyntheticTapsOptions o = FromPreset(io::ParseMaterial("wood"), 7);
  o.speeds_mps = {0.3};
  const io::TapRecording r = Synthetic(o);
  const TapFit t = FitTap(r, r.taps[0]);
  EXPECT_LT(std::abs(t.frequency_hz - o.frequency_hz), 4.0 * t.frequency_sd_hz);
  EXPECT_LT(std::abs(t.decay_per_s - o.decay_per_s), 4.0 * t.decay_sd_per_s);
  EXPECT_LT(std::abs(t.amplitude - o.slope * 0.3), 4.0 * t.amplitude_sd);
  EXPECT_GT(t.r2, 0.9);
  EXPECT_LE(t.onset_s, t.detected_onset_s);
}

// a recording clipped at the level 1 % of its first tap's samples exceed is refused, naming
// the file, the line of the first clipped sample and the reason
TEST(MaterialFitTest, AOnePercentClipIsDetectedAndNamed) {
  SyntheticTapsOptions o = FromPreset(io::ParseMaterial("aluminium"), 3);
  o.clip_fraction = 0.01;
  const std::string e = FitError({Synthetic(o, "clipped.csv")});
  EXPECT_NE(e.find("clipped.csv:"), std::string::npos) << e;
  EXPECT_NE(e.find("tap 0: clipped (saturated)"), std::string::npos) << e;
  EXPECT_NE(e.find("at the extreme value"), std::string::npos) << e;
  o.clip_fraction = 0.0;
  EXPECT_EQ(FitError({Synthetic(o, "clean.csv")}), "");
}

// a one-sample spike of twice the transient's peak, 10 ms before the tap, does not move the
// onset (nor the fit)
TEST(MaterialFitTest, OnsetDetectorIgnoresAPreContactSpike) {
  SyntheticTapsOptions o = FromPreset(io::ParseMaterial("wood"), 2);
  o.speeds_mps = {0.2};
  io::TapRecording r = Synthetic(o);
  const TapFit clean = FitTap(r, r.taps[0]);
  io::RecordedTap& tap = r.taps[0];
  const auto spike = static_cast<std::size_t>(0.010 * clean.sample_rate_hz);
  tap.signal[spike] = 2.0 * clean.amplitude;
  const TapFit spiked = FitTap(r, tap);
  EXPECT_EQ(spiked.detected_onset_s, clean.detected_onset_s);
  // the spike moves the baseline's median by a little: f within 0.01 %, far inside its sd
  EXPECT_NEAR(spiked.frequency_hz, clean.frequency_hz, 1e-4 * clean.frequency_hz);
  EXPECT_LT(std::abs(spiked.frequency_hz - clean.frequency_hz), 0.1 * clean.frequency_sd_hz);
}

// the impact speed from a position column (the slope over the last 5 ms before the onset)
TEST(MaterialFitTest, ImpactSpeedFromPosition) {
  SyntheticTapsOptions o = FromPreset(io::ParseMaterial("wood"), 4);
  o.speeds_mps = {0.25};
  io::TapRecording r = Synthetic(o);
  io::RecordedTap& tap = r.taps[0];
  for (double t : tap.time_s) tap.position_m.push_back(0.01 - 0.25 * std::min(t, 0.02));
  tap.velocity_mps.clear();
  const TapFit fit = FitTap(r, tap);
  EXPECT_EQ(fit.speed_from, "position_m");
  EXPECT_NEAR(fit.impact_speed_mps, 0.25, 1e-6);
}

// recordings that cannot support a fit, each refused with its reason
TEST(MaterialFitTest, RecordingsThatCannotSupportAFitAreRefused) {
  const SyntheticTapsOptions base = FromPreset(io::ParseMaterial("aluminium"), 5);
  SyntheticTapsOptions slow = base;
  slow.sample_rate_hz = 1000.0;  // under 4 x 300 Hz
  EXPECT_NE(FitError({Synthetic(slow)}).find("below 4 f"), std::string::npos)
      << FitError({Synthetic(slow)});
  SyntheticTapsOptions quiet = base;
  quiet.slope = 0.0;  // noise only: sigma from the slope is 0, so add a level of noise by hand
  io::TapRecording noise = Synthetic(quiet);
  unsigned s = 1;
  for (double& x : noise.taps[0].signal) x = ((s = s * 1103515245u + 12345u) >> 16) % 1000 * 1e-3;
  EXPECT_NE(FitError({noise}).find("no contact onset"), std::string::npos) << FitError({noise});
  io::TapRecording shortr = Synthetic(base);
  io::RecordedTap& t = shortr.taps[0];
  const std::size_t keep = static_cast<std::size_t>(0.0215 * 6000.0);  // 1 ms after the onset
  for (auto* v : {&t.time_s, &t.signal, &t.velocity_mps}) v->resize(keep);
  t.line.resize(keep);
  EXPECT_NE(FitError({shortr}).find("too short"), std::string::npos) << FitError({shortr});
  io::TapRecording nospeed = Synthetic(base);
  for (io::RecordedTap& tap : nospeed.taps) tap.velocity_mps.clear();
  EXPECT_NE(FitError({nospeed}).find("no impact speed"), std::string::npos);
}

// the material file is read back by --material's reader, with its amplitude as force
TEST(MaterialFitTest, TheMaterialFileIsReadBack) {
  const std::vector<io::TapRecording> r = {Synthetic(FromPreset(io::ParseMaterial("wood"), 1))};
  MaterialFitOptions fo;
  fo.name = "my_wood";
  fo.effective_mass_kg = 0.599;
  const MaterialFit fit = FitMaterial(r, fo);
  nlohmann::json j = MaterialFileJson(fit);
  const Material m = io::ReadMaterialJson(io::JsonSource("m.json"), j, "", "x");
  EXPECT_EQ(m.name, "my_wood");
  EXPECT_EQ(m.amplitude_Ns_per_m, fit.material.amplitude_Ns_per_m);
  EXPECT_EQ(j["amplitude_quantity"], "acceleration");
  EXPECT_NEAR(j["effective_mass_kg"].get<double>() * j["amplitude_mps2_per_mps"].get<double>(),
              m.amplitude_Ns_per_m, 1e-9 * m.amplitude_Ns_per_m);
  // the force no longer the product of mass and acceleration: refused, naming the field
  j["amplitude_Ns_per_m"] = 2.0 * m.amplitude_Ns_per_m;
  EXPECT_THROW(io::ReadMaterialJson(io::JsonSource("m.json"), j, "", "x"), Error);
}

// the fitted material as a passive material train on every preset device at four speeds: no tap
// gives the user energy (1e-9 J, as the presets' test in tests/io/materials_test.cc)
TEST(MaterialFitTest, TheFittedMaterialTrainIsPassiveOnEveryPresetDevice) {
  const std::vector<io::TapRecording> r = {Synthetic(FromPreset(io::ParseMaterial("wood"), 1))};
  MaterialFitOptions fo;
  fo.effective_mass_kg = 0.599;
  const Material m = FitMaterial(r, fo).material;
  int taps = 0;
  for (const DeviceLimits& device : device::Presets()) {
    for (const double speed : {0.05, 0.15, 0.3, 0.5}) {
      TapExperimentConfig c;
      c.scene_path = std::string(RIGIDTOUCH_SOURCE_DIR) + "/scenes/wall.xml";
      c.device_preset = device.name;
      c.load.render.renderer = RendererKind::kTrain;
      io::ApplyMaterial(c.load.render, m);
      c.script.approach_speed_mps = speed;
      c.script.taps = 2;
      if (device.name == "ideal") {
        c.stiffness_N_per_m = 400.0;
        c.damping_Ns_per_m = 10.0;
      }
      const TapRun run = RunTapExperiment(c);
      for (const TapMetrics& tap : run.taps) {
        ++taps;
        EXPECT_LE(tap.energy_to_user_J, 1e-9) << device.name << " " << speed << " m/s";
      }
    }
  }
  EXPECT_EQ(taps, 2 * 4 * static_cast<int>(device::Presets().size()));
}

}  // namespace
}  // namespace rigidtouch::analysis
