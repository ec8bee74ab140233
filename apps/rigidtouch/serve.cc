// `rigidtouch serve`: the real-time haptic loop against a device (the UDP bridge or the
// in-process simulated device), with loop statistics at the end.
#include <cstdio>
#include <iostream>

#include "analysis/tap_experiment.h"
#include "command.h"
#include "device/udp_device.h"
#include "device/udp_json.h"
#include "io/resources.h"
#include "io/trace_csv.h"
#include "loop/haptic_loop.h"
#include "loop/loop_json.h"
#include "loop/stop_signal.h"
#include "scene_flags.h"

namespace rigidtouch::cli {
namespace {

struct ServeFlags {
  SceneFlags scene;
  std::string device = "sim";
  std::string preset = "touch";
  double rate_hz = 1000.0;
  double duration_s = 0.0;
  bool realtime = false;
  double spin_us = 0.0;
  double watchdog_s = 0.05;
  double test_drop = 0.0;
  std::string key_file;  // udp: empty means the per-user default key, created on first use
  int taps = 3;
  double speed_mps = 0.2;
  std::string trace;
  bool json = false;
};

void PrintResult(const nlohmann::json& result, bool json) {
  if (json) {
    std::cout << result.dump() << "\n";
    return;
  }
  const auto& t = result["loop"];
  // periods in microseconds, rates to 0.1 Hz: the JSON keeps the full values
  const auto us = [&t](const char* key) { return 1e6 * t[key].get<double>(); };
  char line[320];
  std::snprintf(line, sizeof line,
                "ticks %lld at %.1f Hz (asked %.1f), overruns %lld, skipped periods %lld, period "
                "error p50 / p99 / p99.9 / max %.1f / %.1f / %.1f / %.1f us\n",
                t["ticks"].get<long long>(), t["achieved_rate_hz"].get<double>(),
                t["rate_hz"].get<double>(), t["overruns"].get<long long>(),
                t["skipped_periods"].get<long long>(), us("period_error_p50_s"),
                us("period_error_p99_s"), us("period_error_p999_s"), us("period_error_max_s"));
  std::cout << line << "impulses " << result["impulses"] << ", invalid device ticks "
            << result["invalid_device_ticks"] << ", safe zero-force ticks "
            << result["safe_fallback_ticks"] << "\n";
  for (const auto& w : t["warnings"]) std::cout << "warning: " << w.get<std::string>() << "\n";
}

void Run(const ServeFlags& f) {
  loop::LoopOptions lo;
  lo.rate_hz = f.rate_hz;
  lo.realtime_priority = f.realtime;
  lo.lock_memory = f.realtime;
  lo.spin_us = f.spin_us;
  loop::ValidateLoopOptions(lo);
  std::vector<TraceSample> samples;
  std::unique_ptr<loop::TraceQueue> traces;
  if (!f.trace.empty()) {
    traces = std::make_unique<loop::TraceQueue>(1 << 16, loop::VectorSink(&samples));
  }
  const std::atomic<bool>& stop = loop::InstallStopSignalHandlers();
  nlohmann::json result;
  loop::HapticLoopResult r;
  if (f.device == "sim") {
    analysis::TapExperimentConfig c;
    c.scene_path = f.scene.scene.empty() ? io::ShippedFile("scenes/wall.xml") : f.scene.scene;
    c.load = ToLoadOptions(f.scene);
    c.load.device.coupling = Coupling::kDirect;
    c.device_preset = f.preset;
    c.rate_hz = f.rate_hz;
    c.stiffness_N_per_m = f.scene.stiffness_N_per_m;
    c.damping_Ns_per_m = f.scene.damping_Ns_per_m;
    c.script.taps = f.taps;
    c.script.approach_speed_mps = f.speed_mps;
    analysis::TapSetup setup = analysis::PrepareTap(c);
    lo.duration_s = f.duration_s > 0.0 ? f.duration_s : setup.simulated->duration_s();
    Data data = MakeData(setup.model);
    r = loop::RunHapticLoop(setup.model, data, *setup.simulated, lo, &stop, traces.get());
    result["device"] = {{"kind", "simulated"},
                        {"preset", f.preset},
                        {"energy_to_user_J", setup.simulated->energy_to_user_J()}};
  } else {
    LoadOptions load = ToLoadOptions(f.scene);
    load.timestep_s = 1.0 / f.rate_hz;
    load.device.coupling = Coupling::kDirect;
    const std::string scene =
        f.scene.scene.empty() ? io::ShippedFile("scenes/wall.xml") : f.scene.scene;
    Model model = LoadModel(scene, load);
    // the tool is the end effector; without a model of the real device, the simulated one's
    analysis::UseDeviceAndHandMass(model, device::DeviceModelParams{}, device::HandParams{});
    Configure(model);
    device::UdpDeviceOptions o;
    o.server = f.device;
    o.watchdog_s = f.watchdog_s;
    o.limits = device::FindPreset(f.preset);
    o.key_file = f.key_file;
    o.test_loss.incoming_fraction = f.test_drop;
    o.test_loss.outgoing_fraction = f.test_drop;
    device::UdpDevice dev(o);
    lo.duration_s = f.duration_s;
    Data data = MakeData(model);
    r = loop::RunHapticLoop(model, data, dev, lo, &stop, traces.get());
    result["device"] = {{"kind", "udp"},
                        {"server", f.device},
                        {"link", ToJson(dev.counters())},
                        {"watchdog_tripped", dev.watchdog_tripped()}};
  }
  result["loop"] = loop::ToJson(r.timing);
  result["impulses"] = r.impulses;
  result["invalid_device_ticks"] = r.invalid_device_ticks;
  result["safe_fallback_ticks"] = r.safe_fallback_ticks;
  result["clipped_ticks"] = r.clipped_ticks;
  result["max_force_N"] = r.max_force_N;
  result["finite"] = r.finite;
  if (traces) {
    traces->Close();
    result["trace_queue"] = loop::ToJson(traces->stats());
    io::WriteTraceCsv(f.trace, samples);
    result["trace"] = f.trace;
  }
  PrintResult(result, f.json);
}

void Register(CLI::App& root) {
  auto f = std::make_shared<ServeFlags>();
  CLI::App* app = root.add_subcommand("serve", "run the real-time haptic loop against a device");
  AddSceneFlags(app, f->scene, /*scene_required=*/false);
  app->add_option("--device", f->device, "sim (in-process simulated device) or udp://HOST:PORT")
      ->capture_default_str();
  app->add_option("--preset", f->preset, "device preset (limits; the simulated device's)")
      ->capture_default_str();
  app->add_option("--rate", f->rate_hz, "loop rate [Hz], 1 to 20000")->capture_default_str();
  app->add_option("--duration", f->duration_s,
                  "run time [s]; 0: until SIGINT (udp) or the end of the taps (sim)");
  app->add_flag("--realtime", f->realtime, "SCHED_FIFO and locked memory when allowed");
  app->add_option("--spin-us", f->spin_us, "busy-wait before each deadline [us]");
  app->add_option("--watchdog", f->watchdog_s, "no fresh device state for this long: zero force")
      ->capture_default_str();
  app->add_option("--test-drop", f->test_drop, "TEST ONLY: drop this fraction of packets");
  app->add_option("--key", f->key_file,
                  "udp: pre-shared key file (rigidtouch keygen); default: the per-user key, "
                  "created on first use");
  app->add_option("--taps", f->taps, "taps of the simulated hand (sim)")->capture_default_str();
  app->add_option("--speed", f->speed_mps, "approach speed of the simulated hand [m/s] (sim)")
      ->capture_default_str();
  app->add_option("--trace", f->trace, "write the trace CSV here");
  app->add_flag("--json", f->json, "print one JSON object");
  app->callback([f] { Run(*f); });
}

const CommandRegistrar registrar(&Register);

}  // namespace
}  // namespace rigidtouch::cli
