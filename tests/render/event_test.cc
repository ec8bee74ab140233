// The event renderer's transient (render::EventTransient) and the passivity controller over it,
// through the tap experiment: the closed form tick by tick, its spectrum, its scaling with the
// approach speed, and the energy it gives the user with and without the controller.
#include "render/event.h"

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <numbers>
#include <string>
#include <vector>

#include "analysis/spectrum.h"
#include "analysis/tap_experiment.h"
#include "io/materials.h"

namespace rigidtouch::render {
namespace {

analysis::TapExperimentConfig EventTap(const std::string& material, const std::string& device,
                                       double speed, int taps = 1) {
  analysis::TapExperimentConfig c;
  c.scene_path = std::string(RIGIDTOUCH_SOURCE_DIR) + "/scenes/wall.xml";
  c.device_preset = device;
  c.load.render.renderer = RendererKind::kEvent;
  c.load.render.material = io::ParseMaterial(material);
  c.script.approach_speed_mps = speed;
  c.script.taps = taps;
  if (device == "ideal") {
    // a wall the tool stays on for the whole transient (docs/devices.md)
    c.stiffness_N_per_m = 400.0;
    c.damping_Ns_per_m = 10.0;
  }
  return c;
}

// the transient along the wall normal from the first contact tick, over `window_s`
std::vector<double> Transient(const analysis::TapRun& run, double window_s) {
  std::vector<double> f;
  bool on = false;
  for (const TraceSample& s : run.trace) {
    if (!on && s.tool_contacts > 0) on = true;
    if (!on) continue;
    f.push_back(s.impulsive_force_N.dot(s.wall_normal));
    if (static_cast<double>(f.size()) * run.model.timestep_s >= window_s) break;
  }
  return f;
}

// tick k after onset shows A v_in e^(-B t) sin(2 pi f t) at t = (k + 1/2) h: the ratio of the
// force to e^(-B t) sin(2 pi f t) is the same A v_in on every tick (1e-9 relative), and v_in is
// the approach speed the device measured (within 2 %, its 100 Hz velocity filter's lag)
TEST(EventTest, TransientIsTheDecayingSinusoidScaledByTheApproachSpeed) {
  const analysis::TapRun run = analysis::RunTapExperiment(EventTap("wood", "ideal", 0.2));
  const Material& m = run.model.render.material;
  const std::vector<double> f = Transient(run, 0.05);
  ASSERT_EQ(f.size(), 50u);
  const double h = run.model.timestep_s;
  double scale = 0.0;
  int checked = 0;
  for (std::size_t k = 0; k < f.size(); ++k) {
    const double t = (static_cast<double>(k) + 0.5) * h;
    const double shape =
        std::exp(-m.decay_per_s * t) * std::sin(2.0 * std::numbers::pi * m.frequency_hz * t);
    if (std::abs(shape) < 0.05) continue;
    if (checked++ == 0) scale = f[k] / shape;
    EXPECT_NEAR(f[k] / shape, scale, 1e-9 * std::abs(scale)) << "tick " << k;
  }
  EXPECT_GT(checked, 20);
  EXPECT_NEAR(scale / m.amplitude_Ns_per_m, 0.2, 0.2 * 0.02);
}

// the transient's power spectrum over the 0.1 s window peaks within 5 % of the material's f
TEST(EventTest, SpectrumPeaksAtTheMaterialsFrequency) {
  for (const Material& m : io::MaterialPresets()) {
    const analysis::TapRun run = analysis::RunTapExperiment(EventTap(m.name, "ideal", 0.2));
    const std::vector<double> f = Transient(run, 0.1);
    analysis::SpectrumOptions o;
    o.window = analysis::SpectrumOptions::Window::kTaperedEnd;  // it starts at the first sample
    o.remove_mean = false;
    o.min_fft_length = 8192;
    const double peak =
        analysis::DominantFrequencyHz(analysis::PowerSpectrum(f, 1.0 / run.model.timestep_s, o));
    EXPECT_NEAR(peak, m.frequency_hz, 0.05 * m.frequency_hz) << m.name;
  }
}

// the largest transient force is linear in the approach speed: R^2 > 0.99 over five speeds
TEST(EventTest, AmplitudeIsLinearInApproachSpeed) {
  std::vector<double> v, a;
  for (const double speed : {0.05, 0.1, 0.2, 0.3, 0.4}) {
    const analysis::TapRun run = analysis::RunTapExperiment(EventTap("aluminium", "ideal", speed));
    double peak = 0.0;
    for (const double f : Transient(run, 0.1)) peak = std::max(peak, std::abs(f));
    v.push_back(run.taps[0].approach_speed_mps);
    a.push_back(peak);
  }
  const double n = static_cast<double>(v.size());
  double mv = 0, ma = 0;
  for (std::size_t i = 0; i < v.size(); ++i) mv += v[i] / n, ma += a[i] / n;
  double svv = 0, sva = 0, saa = 0;
  for (std::size_t i = 0; i < v.size(); ++i) {
    svv += (v[i] - mv) * (v[i] - mv);
    sva += (v[i] - mv) * (a[i] - ma);
    saa += (a[i] - ma) * (a[i] - ma);
  }
  const double r2 = sva * sva / (svv * saa);
  EXPECT_GT(r2, 0.99);
  EXPECT_GT(sva / svv, 0.0);
}

// the walls' passivity sweep (tests/analysis/tap_experiment_test.cc: Touch, Omni, Falcon at
// 0.05-0.5 m/s, two taps) with each material: the open-loop transient gives the user energy in
// some configuration; with the passivity controller no tap does
TEST(EventTest, ActiveWithoutThePassivityControllerAndPassiveWithIt) {
  int active = 0, runs = 0;
  double worst_without = -1.0, worst_with = -1.0;
  for (const std::string device : {"touch", "omni", "falcon"}) {
    for (const double speed : {0.05, 0.15, 0.3, 0.5}) {
      for (const Material& m : io::MaterialPresets()) {
        for (const bool control : {false, true}) {
          analysis::TapExperimentConfig c = EventTap(m.name, device, speed, 2);
          c.load.render.passivity_control = control;
          const analysis::TapRun run = analysis::RunTapExperiment(c);
          for (const analysis::TapMetrics& t : run.taps) {
            if (control) {
              worst_with = std::max(worst_with, t.energy_to_user_J);
              // tolerance: 1e-9 J, as the walls' passivity test
              EXPECT_LE(t.energy_to_user_J, 1e-9)
                  << device << " " << speed << " m/s " << m.name << " tap " << t.tap;
            } else {
              worst_without = std::max(worst_without, t.energy_to_user_J);
              if (t.energy_to_user_J > 1e-9) ++active;
            }
          }
          ++runs;
        }
      }
    }
  }
  EXPECT_GT(active, 0) << "the event renderer was passive everywhere in the sweep";
  std::cout << "event sweep: " << runs << " runs, " << active
            << " active taps without the controller; largest energy to the user without "
            << worst_without << " J, with " << worst_with << " J\n";
}

}  // namespace
}  // namespace rigidtouch::render
