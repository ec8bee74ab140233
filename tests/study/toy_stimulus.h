// TEST-ONLY analytic stimulus source. It is not the engine and not a model of any device: a toy
// whose percept depends monotonically on the condition's parameters, so the study code can be
// tested before the real tap experiment is wired in (MakeTapStimulusSource).
//
// A tool of mass 0.1 kg hits the wall at speed v (0.2 m/s unless the condition sets one,
// multiplied by exp(speed_log_sd * z) per tap, z from the tap seed), time step 1 ms:
//   impulse: one pulse of force (1 + e) m v / h; a one-step pulse has a flat spectrum up to
//            500 Hz, so its energy splits over the bands in proportion to their width;
//   train:   N = max(1, round(f t_c)) pulses of m v / (N h); the energy is in the band of f;
//   penalty: force k v 10 ms + b v (k defaults to 1000 N/m, b to 0), no vibration.
// The vibration RMS is the pulses' RMS over a 100 ms span.
#pragma once

#include <algorithm>
#include <cmath>
#include <string>

#include "study/random.h"
#include "study/stimulus.h"

namespace rigidtouch::study::testing {

class ToyStimulusSource : public StimulusSource {
 public:
  explicit ToyStimulusSource(double speed_log_sd = 0.1) : speed_log_sd_(speed_log_sd) {}

  TapPercept RenderTap(const Condition& c, std::uint64_t tap_seed) override {
    ++taps_rendered;
    constexpr double kMass_kg = 0.1;
    constexpr double kStep_s = 1e-3;
    constexpr double kSpan_s = 0.1;
    Rng rng(tap_seed);
    const double v = c.approach_speed_mps.value_or(0.2) * std::exp(speed_log_sd_ * rng.Normal());
    TapPercept p;
    p.approach_speed_mps = v;
    const double penalty_N =
        c.stiffness_N_per_m.value_or(1000.0) * v * 0.01 + c.damping_Ns_per_m.value_or(0.0) * v;
    double pulse_N = 0.0;
    int pulses = 0;
    if (c.renderer == RendererKind::kImpulse) {
      pulse_N = (1.0 + c.restitution) * kMass_kg * v / kStep_s;
      pulses = 1;
      p.band_energy_fraction = {40.0 / 500.0, 60.0 / 500.0, 300.0 / 500.0, 100.0 / 500.0};
      p.dominant_frequency_hz = 0.0;
    } else if (c.renderer == RendererKind::kTrain) {
      pulses = std::max(1, static_cast<int>(std::lround(c.frequency_hz * c.t_collision_s)));
      pulse_N = kMass_kg * v / (pulses * kStep_s);
      const double f = c.frequency_hz;
      const int band = f < 40.0 ? 0 : f < 100.0 ? 1 : f < 400.0 ? 2 : 3;
      p.band_energy_fraction = {0.0, 0.0, 0.0, 0.0};
      p.band_energy_fraction[band] = 1.0;
      p.dominant_frequency_hz = f;
      p.periodicity = 1.0;  // an ideal train
    }
    p.peak_force_N = std::max(pulse_N, penalty_N);
    p.vibration_rms_N = pulse_N * std::sqrt(pulses * kStep_s / kSpan_s);
    p.rate_hardness_N_per_m = (pulses > 0 ? pulse_N / kStep_s : penalty_N / 0.01) / v;
    return p;
  }

  std::string Describe() const override { return "test-only toy stimulus source"; }

  int taps_rendered = 0;

 private:
  double speed_log_sd_;
};

}  // namespace rigidtouch::study::testing
