// The engine behind the study: simulated taps as percepts (StimulusSource), and walls rendered on
// a device for a person (WallPresenter). Declared in study/stimulus.h.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <iostream>
#include <set>
#include <sstream>

#include "analysis/tap_experiment.h"
#include "device/device_spec.h"
#include "device/presets.h"
#include "device/udp_device.h"
#include "io/materials.h"
#include "io/resources.h"
#include "loop/haptic_loop.h"
#include "study/stimulus.h"

namespace rigidtouch::study {
namespace {

// the condition's renderer, material and passivity control as `tap` renders them (simulated taps
// and the bridge alike)
RenderParams ToRenderParams(const Condition& c) {
  return c.ToRenderParams();
}

analysis::TapExperimentConfig TapConfig(const Condition& c, const std::string& scene,
                                        const std::string& device, double speed_mps) {
  analysis::TapExperimentConfig config;
  config.scene_path =
      c.scene ? *c.scene : (scene.empty() ? io::ShippedFile("scenes/wall.xml") : scene);
  config.device_preset = c.device ? *c.device : (device.empty() ? "touch" : device);
  config.load.render = ToRenderParams(c);
  config.stiffness_N_per_m = c.stiffness_N_per_m;
  config.damping_Ns_per_m = c.damping_Ns_per_m;
  config.script.approach_speed_mps =
      c.approach_speed_mps ? *c.approach_speed_mps : (speed_mps > 0.0 ? speed_mps : 0.2);
  if (c.wall_geom) config.wall_geom = *c.wall_geom;
  if (c.wall_point_m) {
    config.wall_point_m = *c.wall_point_m;
    config.wall_normal = *c.wall_normal;
  }
  return config;
}

// a material's conversion note (analysis::TapRun::material_note), printed once per session for
// each material and device however many taps render it
class MaterialNotes {
 public:
  void Print(const std::string& note) {
    if (note.empty() || !printed_.insert(note).second) return;
    std::cerr << "rigidtouch: note: " << note << "\n";
  }

 private:
  std::set<std::string> printed_;
};

// The transient part of the normal force over the collision window: displayed minus penalty,
// i.e. what the impulses add after the device limit (as TapMetrics' transient spectrum).
std::vector<double> TransientForce(const std::vector<TraceSample>& trace, double onset_s,
                                   double window_s) {
  std::vector<double> x;
  Vec3 n = Vec3::Zero();
  for (const TraceSample& s : trace) {
    if (s.time_s < onset_s || s.time_s >= onset_s + window_s) continue;
    if (x.empty()) n = s.wall_normal;
    x.push_back((s.device_force_N - s.penalty_force_N).dot(n));
  }
  return x;
}

// RMS with the mean removed: the vibration on top of the press
double AcRms(const std::vector<double>& x) {
  if (x.empty()) return 0.0;
  double mean = 0.0;
  for (double v : x) mean += v / static_cast<double>(x.size());
  double power = 0.0;
  for (double v : x) power += (v - mean) * (v - mean) / static_cast<double>(x.size());
  return std::sqrt(power);
}

class TapStimulusSource final : public StimulusSource {
 public:
  explicit TapStimulusSource(const TapSourceOptions& o) : options_(o) {}

  TapPercept RenderTap(const Condition& condition, std::uint64_t tap_seed) override {
    analysis::TapExperimentConfig config =
        TapConfig(condition, options_.scene, options_.device, options_.approach_speed_mps);
    config.script.taps = 1;
    config.script.seed = tap_seed;
    // tap variability comes from the hand: 10% speed spread unless the caller sets one
    config.script.speed_spread =
        options_.approach_speed_relative_sd >= 0.0 ? options_.approach_speed_relative_sd : 0.1;
    const analysis::TapRun run = analysis::RunTapExperiment(config);
    notes_.Print(run.material_note);
    TapPercept p;
    if (run.taps.empty() || !run.taps.front().contact) return p;  // the hand never touched
    const analysis::TapMetrics& m = run.taps.front();
    p.peak_force_N = m.peak_force_N;
    p.rate_hardness_N_per_m = m.rate_hardness_N_per_m;
    // the vibration is what the impulses add (the press is the onset cue): its band fractions
    // and its magnitude; a pitch only where the transient is periodic (a click's spectrum is flat)
    const std::vector<double> x = TransientForce(run.trace, m.contact_onset_time_s, 0.1);
    p.vibration_rms_N = AcRms(x);
    if (p.vibration_rms_N > 0.0) {
      for (int b = 0; b < kPerceptBands; ++b) {
        const double f = m.transient_band_energy_fraction[b];
        p.band_energy_fraction[b] = std::isfinite(f) ? f : 0.0;
      }
    }
    // the pitch is the tap metrics' repetition rate of the transient (one definition, as tap's
    // table, JSON and figures report it): none for a click or a pure penalty wall
    const auto finite_or_zero = [](double v) { return std::isfinite(v) ? v : 0.0; };
    p.transient_peak_to_mean = finite_or_zero(m.transient_peak_to_mean);
    p.dominant_frequency_hz = finite_or_zero(m.transient_repetition_hz);
    p.periodicity = finite_or_zero(m.transient_periodicity);
    p.approach_speed_mps = m.approach_speed_mps;
    return p;
  }

  std::string Describe() const override {
    std::ostringstream s;
    s << "simulated taps (rigidtouch tap experiment, device "
      << (options_.device.empty() ? "touch" : options_.device) << ")";
    return s.str();
  }

 private:
  TapSourceOptions options_;
  MaterialNotes notes_;
};

// renders a wall for a person: on the in-process simulated device (a dry run that reports what
// the simulated hand felt) or, with a udp:// address, on a real device through the bridge
class DeviceWallPresenter final : public WallPresenter {
 public:
  explicit DeviceWallPresenter(const PresenterOptions& o) : options_(o) {
    // a person's session needs a real device; the simulated one only as an explicit dry run
    if (o.device != "sim" && o.device.rfind("udp://", 0) != 0) {
      throw Error(
          "study run: --connect " + (o.device.empty() ? std::string("is missing") : o.device) +
          ": a participant's session needs a device: udp://HOST:PORT (a device through the "
          "bridge), or sim for a dry run on the in-process simulated device, which no person "
          "feels (it is recorded in the log as a dry run)");
    }
    device::ParseDeviceSpec(o.preset);  // an unknown device is an error before the session
  }

  void Present(const Condition& condition, int taps) override {
    if (options_.device.rfind("udp://", 0) == 0) {
      PresentOnBridge(condition, taps);
      return;
    }
    analysis::TapExperimentConfig config = TapConfig(condition, options_.scene, options_.preset, 0);
    config.script.taps = taps;
    const analysis::TapRun run = analysis::RunTapExperiment(config);
    notes_.Print(run.material_note);
    double peak = 0.0;
    for (const auto& t : run.taps) peak = std::max(peak, t.peak_force_N);
    std::cout << "  (simulated device rendered " << taps << " taps, peak force " << peak << " N)\n";
  }

  std::string Describe() const override {
    return options_.device.rfind("udp://", 0) == 0
               ? "device bridge " + options_.device + " (" + options_.preset + " limits)"
               : "in-process simulated device, " + options_.preset +
                     " preset (dry run: no person felt these walls)";
  }
  bool dry_run() const override { return options_.device == "sim"; }

 private:
  void PresentOnBridge(const Condition& condition, int taps) {
    // the preset's limits on every path, as serve applies them: the wall defaults to what the
    // device can display (its stiffness, damping k h capped at its damping), the force to its
    // limit, and the device's own announced limits tighten them further
    const device::DeviceSpec spec = device::ParseDeviceSpec(options_.preset);
    const DeviceLimits& preset = spec.limits;
    const double h = 0.001;
    LoadOptions load;
    load.render = ToRenderParams(condition);
    // an acceleration material's force on this device, as serve converts it
    notes_.Print(
        io::RenderMaterialOnDevice(load.render, device::EffectiveMassKg(spec.model), preset.name));
    load.device.coupling = Coupling::kDirect;
    load.timestep_s = h;
    load.contact.stiffness_N_per_m = condition.stiffness_N_per_m.value_or(
        device::DefaultWall(preset, h, load.contact.stiffness_N_per_m).stiffness_N_per_m);
    load.contact.damping_Ns_per_m = condition.damping_Ns_per_m.value_or(
        device::DefaultDamping(preset, h, load.contact.stiffness_N_per_m));
    device::TightenDeviceParams(load.device, preset);
    const std::string scene = condition.scene          ? *condition.scene
                              : options_.scene.empty() ? io::ShippedFile("scenes/wall.xml")
                                                       : options_.scene;
    const Model model = LoadModel(scene, load);
    Data data = MakeData(model);
    device::UdpDeviceOptions dev_options;
    dev_options.server = options_.device;
    dev_options.limits = preset;
    dev_options.key_file = options_.key_file;
    device::UdpDevice dev(dev_options);
    loop::LoopOptions loop;
    loop.rate_hz = 1000.0;
    loop.duration_s = 1.5 * taps;  // time for the participant's taps
    std::cout << "  tap the wall " << taps << " times now (" << loop.duration_s << " s)\n"
              << std::flush;
    const loop::HapticLoopResult r = loop::RunHapticLoop(model, data, dev, loop, nullptr);
    if (r.invalid_device_ticks > r.timing.ticks / 2) {
      std::cerr << "rigidtouch: warning: the device sent no valid state for most of the series\n";
    }
  }

  PresenterOptions options_;
  MaterialNotes notes_;
};

}  // namespace

std::unique_ptr<StimulusSource> MakeTapStimulusSource(const TapSourceOptions& options) {
  return std::make_unique<TapStimulusSource>(options);
}

std::unique_ptr<WallPresenter> MakeDeviceWallPresenter(const PresenterOptions& options) {
  return std::make_unique<DeviceWallPresenter>(options);
}

}  // namespace rigidtouch::study
