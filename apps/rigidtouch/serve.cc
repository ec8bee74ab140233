// `rigidtouch serve`: the real-time haptic loop against a device (the UDP bridge, the in-process
// simulated device or a recorded session replayed), with loop statistics at the end; `--record`
// writes every tick's device state and command from the trace writer's side of the loop.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <optional>
#include <sstream>
#include <string_view>

#include "analysis/tap_experiment.h"
#include "base/limits.h"
#include "command.h"
#include "device/presets.h"
#include "device/replay_device.h"
#include "device/udp_device.h"
#include "device/udp_json.h"
#include "io/device_record.h"
#include "io/materials.h"
#include "io/output_file.h"
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
  std::optional<std::string> device;   // the device: a preset or a JSON spec (or old: connection)
  std::optional<std::string> connect;  // sim | udp://HOST:PORT; default sim
  std::optional<std::string> preset;   // old spelling of --device NAME
  double rate_hz = 1000.0;
  double duration_s = 0.0;
  bool realtime = false;
  double spin_us = 0.0;
  int cpu = -1;
  double watchdog_s = 0.05;
  double test_drop = 0.0;
  std::string key_file;  // udp: empty means the per-user default key, created on first use
  int taps = 3;
  double speed_mps = 0.2;
  // sim and replay: what the simulated hand taps (as `tap`'s flags); default the surface below
  // the scene's tool
  std::string wall_geom;
  std::vector<double> wall_point, wall_normal;
  // udp: tool position = device position + this [m] (where the device's workspace sits in the
  // scene)
  std::vector<double> workspace_offset;
  double startup_timeout_s = 1.0;
  // default: the config's device.plausible_radius_m / plausible_speed_mps, else DeviceParams'
  std::optional<double> max_device_radius_m;
  std::optional<double> max_device_speed_mps;
  std::string trace;
  std::string record;                // --record LOG: every tick's device state and command
  std::string replay_pace = "rate";  // replay: "rate" (the loop's deadlines) or "max"
  bool rate_given = false;           // --rate was on the command line
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
            << result["safe_fallback_ticks"] << ", stale device ticks "
            << result["stale_device_ticks"] << "\n"
            << "max force " << result["max_force_N"] << " N (limit " << result["force_limit_N"]
            << " N, 0: none), clipped ticks " << result["clipped_ticks"] << "\n";
  for (const auto& w : t["warnings"]) {
    std::cerr << "rigidtouch: warning: " << w.get<std::string>() << "\n";
  }
}

// What the run rendered and under which limits, for the summary.
nlohmann::json RenderJson(const Model& model, const Data& data) {
  const DeviceParams& d = model.device;
  return {{"contact",
           {{"stiffness_N_per_m", model.contact.stiffness_N_per_m},
            {"damping_Ns_per_m", model.contact.damping_Ns_per_m}}},
          {"limits",
           {{"max_force_N", d.limits.max_force_N},
            {"max_stiffness_N_per_m", d.limits.max_stiffness_N_per_m},
            {"max_damping_Ns_per_m", d.limits.max_damping_Ns_per_m},
            {"plausible_radius_m", d.plausible_radius_m},
            {"plausible_speed_mps", d.plausible_speed_mps}}},
          {"warnings", WarningsJson(data)},
          {"joints", loop::JointsJson(model, data)}};
}

void SetPlausibility(const ServeFlags& f, DeviceParams& d) {
  if (f.max_device_radius_m) d.plausible_radius_m = *f.max_device_radius_m;
  if (f.max_device_speed_mps) d.plausible_speed_mps = *f.max_device_speed_mps;
}

// a replay runs at the recorded rate: the recorded states are one period apart
double ReadServeRecord(const ServeFlags& f, const std::string& connect,
                       std::optional<io::Record>& recorded) {
  double rate_hz = f.rate_hz;
  if (connect.starts_with(kReplayPrefix)) {
    const std::string log = connect.substr(kReplayPrefix.size());
    if (log.empty()) throw Error("serve: --connect replay:LOG needs the record file's path");
    recorded = io::ReadRecord(log);
    if (f.rate_given && f.rate_hz != recorded->rate_hz) {
      std::ostringstream m;
      m << "serve: --rate " << f.rate_hz << " Hz differs from the record's rate "
        << recorded->rate_hz << " Hz in '" << log
        << "': a replay runs at the recorded rate (leave --rate out)";
      throw Error(m.str());
    }
    rate_hz = recorded->rate_hz;
  }
  return rate_hz;
}

// what the three device paths share: the flags, the device, the loop and its writers
struct ServeRun {
  const ServeFlags& f;
  const DeviceChoice& choice;
  const std::string& connect;
  double rate_hz;
  loop::LoopOptions& lo;
  const std::atomic<bool>& stop;
  loop::TraceQueue* traces;
  loop::RecordQueue* records;
};

// the tap experiment's model and simulated device for the flags, direct coupling; its load
// warnings printed
analysis::TapSetup PrepareServeTap(const ServeRun& s) {
  analysis::TapExperimentConfig c =
      TapConfig(s.f.scene, s.choice.spec_text, s.rate_hz, s.f.speed_mps, s.f.taps);
  c.load.device.coupling = Coupling::kDirect;
  c.wall_geom = s.f.wall_geom;
  if (!s.f.wall_point.empty()) {
    c.wall_point_m = Vec3(s.f.wall_point[0], s.f.wall_point[1], s.f.wall_point[2]);
    c.wall_normal = Vec3(s.f.wall_normal[0], s.f.wall_normal[1], s.f.wall_normal[2]);
  }
  // without a wall named, the hand taps what lies below the scene's tool (a pile's top box, not
  // the floor under it)
  c.aim_below_tool = s.f.wall_geom.empty();
  c.widen_plausible_radius =
      !s.f.max_device_radius_m && !ResolveSettings(s.f.scene).Given("device.plausible_radius_m");
  analysis::TapSetup setup = analysis::PrepareTap(c);
  PrintLoadWarnings(setup.model);
  PrintMaterialNote(setup.material_note);
  return setup;
}

// replays a --record session through the model the simulated path builds
nlohmann::json ServeReplay(const ServeRun& s, io::Record& recorded, loop::HapticLoopResult& r) {
  const DeviceLimits& preset = s.choice.spec.limits;
  // the model is built as on the simulated path, so a session recorded there replays through
  // the same model; the tool starts where the recorded handle did
  analysis::TapSetup setup = PrepareServeTap(s);
  Model& model = setup.model;
  device::ReplayDevice dev(std::move(recorded.samples), setup.device);
  model.initial[model.tool].x_W = dev.first_state().position_m;
  device::TightenDeviceParams(model.device, dev.limits());
  SetPlausibility(s.f, model.device);
  Configure(model);
  const std::int64_t ticks =
      s.f.duration_s > 0.0 ? std::llround(s.f.duration_s * s.rate_hz) : dev.size();
  Data data = MakeData(model);
  if (s.f.replay_pace == "max") {
    r = loop::RunHapticTicks(model, data, dev, s.rate_hz, ticks, &s.stop, s.traces, s.records);
  } else {
    // without --duration the loop runs until the record ends (the device says so), so a
    // skipped deadline does not cut the last ticks off
    s.lo.duration_s = s.f.duration_s;
    r = loop::RunHapticLoop(model, data, dev, s.lo, &s.stop, s.traces, s.records);
  }
  nlohmann::json result = RenderJson(model, data);
  result["device"] = {{"kind", "replay"},
                      {"record", s.connect.substr(kReplayPrefix.size())},
                      {"pace", s.f.replay_pace},
                      {"preset", preset.name},
                      {"spec", s.choice.spec_text},
                      {"recorded_ticks", dev.size()},
                      {"replayed_ticks", dev.position()}};
  return result;
}

// the in-process simulated device: the preset's model and a simulated hand's taps
nlohmann::json ServeSim(const ServeRun& s, loop::HapticLoopResult& r) {
  const DeviceLimits& preset = s.choice.spec.limits;
  analysis::TapSetup setup = PrepareServeTap(s);
  Model& model = setup.model;
  device::TightenDeviceParams(model.device, setup.simulated->limits());
  SetPlausibility(s.f, model.device);
  // refuses a stiffness or damping the device cannot display
  Configure(model);
  s.lo.duration_s = s.f.duration_s > 0.0 ? s.f.duration_s : setup.simulated->duration_s();
  Data data = MakeData(model);
  r = loop::RunHapticLoop(model, data, *setup.simulated, s.lo, &s.stop, s.traces, s.records);
  nlohmann::json result = RenderJson(model, data);
  result["device"] = {{"kind", "simulated"},
                      {"preset", preset.name},
                      {"spec", s.choice.spec_text},
                      {"energy_to_user_J", setup.simulated->energy_to_user_J()}};
  return result;
}

// the UDP bridge to a device server; false when interrupted before the device answered
bool ServeUdp(const ServeRun& s, nlohmann::json& result, loop::HapticLoopResult& r) {
  const DeviceLimits& preset = s.choice.spec.limits;
  // the wall defaults to what the device can display, as on the simulated path (and the tap
  // experiment): the preset's stiffness, damping k h capped at the preset's
  Settings settings = ResolveSettings(s.f.scene);
  ApplyDevicePreset(settings, preset, s.rate_hz);
  LoadOptions load = settings.load;
  load.device.coupling = Coupling::kDirect;
  load.device.position_resolution_m = s.choice.spec.model.encoder_resolution_m;
  device::TightenDeviceParams(load.device, preset);
  SetPlausibility(s.f, load.device);
  if (!s.f.workspace_offset.empty()) {
    load.device.workspace_offset_m =
        Vec3(s.f.workspace_offset[0], s.f.workspace_offset[1], s.f.workspace_offset[2]);
  }
  const std::string scene =
      s.f.scene.scene.empty() ? io::ShippedFile("scenes/wall.xml") : s.f.scene.scene;
  // an acceleration material's force: this device's effective mass times its acceleration
  const std::string note = io::RenderMaterialOnDevice(
      load.render, device::EffectiveMassKg(s.choice.spec.model), s.choice.spec.limits.name);
  // Configure refuses what the preset cannot display
  Model model = LoadModel(scene, load);
  // the tool is the end effector: the spec's apparent mass plus a modelled hand's
  analysis::UseDeviceAndHandMass(model, s.choice.spec.model, device::HandParams{});
  Configure(model);
  PrintLoadWarnings(model);
  PrintMaterialNote(note);
  device::UdpDeviceOptions o;
  o.server = s.connect;
  o.watchdog_s = s.f.watchdog_s;
  // a state waits at most this long in the socket before it is rendered; two periods at least,
  // so that a loop at the lowest rates, whose Reads are one period apart, renders every state
  o.max_state_age_s = std::max(o.max_state_age_s, 2.0 / s.rate_hz);
  o.limits = preset;
  o.key_file = s.f.key_file;
  o.test_loss.incoming_fraction = s.f.test_drop;
  o.test_loss.outgoing_fraction = s.f.test_drop;
  device::UdpDevice dev(o);
  if (!loop::AwaitFirstState(dev, s.f.startup_timeout_s, &s.stop)) {
    // interrupted before the device answered: nothing was rendered
    if (s.stop.load()) return false;
    std::cerr << "rigidtouch: error: serve: no state from the device at " << s.connect << " within "
              << s.f.startup_timeout_s << " s (--startup-timeout); is the device server running?\n";
    throw CLI::RuntimeError(kExitNoDevice);
  }
  // the device's own limits, known once its session has started, tighten the preset's
  device::TightenDeviceParams(model.device, dev.limits());
  Configure(model);
  s.lo.duration_s = s.f.duration_s;
  Data data = MakeData(model);
  r = loop::RunHapticLoop(model, data, dev, s.lo, &s.stop, s.traces, s.records);
  result = RenderJson(model, data);
  result["device"] = {{"kind", "udp"},
                      {"server", s.connect},
                      {"preset", preset.name},
                      {"spec", s.choice.spec_text},
                      {"link", ToJson(dev.counters())},
                      {"watchdog_tripped", dev.watchdog_tripped()}};
  return true;
}

void RunServe(const ServeFlags& f) {
  const DeviceChoice choice = ResolveDevice(f.device, f.connect, f.preset);
  const std::string connect = choice.connect.empty() ? "sim" : choice.connect;
  const bool replay = connect.starts_with(kReplayPrefix);
  std::optional<io::Record> recorded;
  const double rate_hz = ReadServeRecord(f, connect, recorded);
  loop::LoopOptions lo;
  lo.rate_hz = rate_hz;
  lo.realtime_priority = f.realtime;
  lo.lock_memory = f.realtime;
  lo.spin_us = f.spin_us;
  lo.cpu = f.cpu;
  loop::ValidateLoopOptions(lo);
  if (!(f.startup_timeout_s > 0.0) || !std::isfinite(f.startup_timeout_s)) {
    throw Error("serve: --startup-timeout must be > 0 s, finite");
  }
  std::vector<TraceSample> samples;
  std::unique_ptr<loop::TraceQueue> traces;
  if (!f.trace.empty()) {
    io::CheckOutputPath(f.trace, "trace file");  // before the session, not after it
    traces = std::make_unique<loop::TraceQueue>(1 << 16, loop::VectorSink(&samples));
    // the trace writer keeps off the loop's CPU
    if (f.cpu >= 0 && !traces->AvoidCpu(f.cpu)) {
      std::cerr << "rigidtouch: warning: could not keep the trace writer off CPU " << f.cpu << "\n";
    }
  }
  // the writer thread formats and writes the rows; the loop only pushes a copy (never blocks)
  RecordOutput record = OpenRecord(f.record, rate_hz);
  loop::RecordQueue* records = record.queue.get();
  if (records && f.cpu >= 0 && !records->AvoidCpu(f.cpu)) {
    std::cerr << "rigidtouch: warning: could not keep the record writer off CPU " << f.cpu << "\n";
  }
  const std::atomic<bool>& stop = loop::InstallStopSignalHandlers();
  nlohmann::json result;
  loop::HapticLoopResult r;
  {
    const Settings settings = ResolveSettings(f.scene);
    const char* why = "serve couples the tool to the device directly";
    if (settings.load.device.coupling != Coupling::kDirect) {
      RefuseUnused(settings, {"device.coupling"}, why);
    }
    RefuseUnused(settings,
                 {"device.coupling_stiffness_N_per_m", "device.coupling_damping_Ns_per_m"}, why);
    RefuseUnusedRender(settings, {settings.load.render.renderer});
  }
  const ServeRun s{f, choice, connect, rate_hz, lo, stop, traces.get(), records};
  if (replay) {
    result = ServeReplay(s, *recorded, r);
  } else if (connect == "sim") {
    result = ServeSim(s, r);
  } else if (!ServeUdp(s, result, r)) {
    return;  // interrupted before the device answered: nothing was rendered
  }
  result["loop"] = loop::ToJson(r.timing);
  result["impulses"] = r.impulses;
  result["invalid_device_ticks"] = r.invalid_device_ticks;
  result["stale_device_ticks"] = r.stale_device_ticks;
  result["held_force_ticks"] = r.held_force_ticks;
  result["safe_fallback_ticks"] = r.safe_fallback_ticks;
  result["non_finite_commands"] = r.non_finite_commands;
  result["clipped_ticks"] = r.clipped_ticks;
  result["guard_clipped_ticks"] = r.guard_clipped_ticks;
  result["force_limit_N"] = r.force_limit_N;
  result["max_force_N"] = r.max_force_N;
  result["finite"] = r.finite;
  if (traces) {
    traces->Close();
    result["trace_queue"] = loop::ToJson(traces->stats());
    io::WriteTraceCsv(f.trace, samples);
    result["trace"] = f.trace;
  }
  if (records) {
    result["record_queue"] = FinishRecord(record, f.record);
    result["record"] = f.record;
  }
  PrintResult(result, f.json);
}

// flags that belong to another connection than the one chosen are refused, not ignored
void CheckServeFlags(const ServeFlags& f, const CLI::App& app) {
  const auto replay = [](const std::optional<std::string>& v) {
    return v && v->starts_with(kReplayPrefix);
  };
  const bool replaying = replay(f.device) || replay(f.connect);
  const auto udp = [](const std::optional<std::string>& v) {
    return v && v->starts_with("udp://");
  };
  const bool bridged = udp(f.device) || udp(f.connect);
  if (!replaying && app.count("--replay-pace") > 0) {
    throw Error("serve: --replay-pace applies to --connect replay:LOG only");
  }
  if (bridged && (app.count("--wall-geom") + app.count("--wall-point")) > 0) {
    throw Error(
        "serve: --wall-geom and --wall-point aim the simulated hand; a device through the bridge "
        "is moved by its own hand (place its workspace with --workspace-offset)");
  }
  if (!bridged && app.count("--workspace-offset") > 0) {
    throw Error("serve: --workspace-offset applies to --connect udp://HOST:PORT only");
  }
  if ((replaying || bridged) && (app.count("--taps") + app.count("--speed")) > 0) {
    throw Error(std::string("serve: --taps and --speed script the simulated hand; ") +
                (replaying ? "a replay moves the handle as recorded"
                           : "a device through the bridge is moved by its own hand"));
  }
  // the bridge's own settings: unused by the in-process simulated device and by a replay
  for (const char* flag : {"--key", "--watchdog", "--startup-timeout", "--test-drop"}) {
    if (!bridged && app.count(flag) > 0) {
      throw Error(std::string("serve: ") + flag + " applies to --connect udp://HOST:PORT only");
    }
  }
}

void RegisterServe(CLI::App& root) {
  auto f = std::make_shared<ServeFlags>();
  CLI::App* app = root.add_subcommand("serve", "run the real-time haptic loop against a device");
  AddSceneFlags(app, f->scene, /*scene_required=*/false);
  AddThreadsFlag(app, f->scene);
  app->add_option("--device", f->device,
                  "the device: a preset or a JSON device spec (" + device::DeviceSpecHelp() +
                      ", default touch); its force, stiffness and damping limits apply on every "
                      "connection (with the device's own, the stricter wins), and it is the "
                      "simulated device's model");
  app->add_option("--connect", f->connect,
                  "sim (the in-process simulated device, default), udp://HOST:PORT (a device "
                  "through the bridge), or replay:LOG (a --record file's handle motion, at its "
                  "rate, through this scene and renderer)");
  app->add_option("--preset", f->preset, "old spelling of --device NAME");
  AddRateFlag(app, f->rate_hz, "loop rate [Hz]");
  app->add_option("--duration", f->duration_s,
                  "run time [s]; 0: until SIGINT (udp), the end of the taps (sim) or of the record "
                  "(replay)")
      ->check(InRange(0.0, INFINITY, "s"));
  app->add_flag("--realtime", f->realtime, "SCHED_FIFO and locked memory when allowed");
  app->add_option("--spin-us", f->spin_us, "busy-wait before each deadline [us]");
  app->add_option("--cpu", f->cpu,
                  "pin the loop thread to this CPU (the trace writer runs on the others); -1: "
                  "not pinned")
      ->capture_default_str();
  app->add_option("--watchdog", f->watchdog_s,
                  "udp: no fresh device state for this long: zero force")
      ->capture_default_str();
  app->add_option("--startup-timeout", f->startup_timeout_s,
                  "udp: no first state from the device within this long [s]: exit with status 5")
      ->capture_default_str();
  app->add_option("--max-device-radius", f->max_device_radius_m,
                  "a device state farther from the device's origin [m] is implausible: zero "
                  "force (default: the config's device.plausible_radius_m, else 1)");
  app->add_option("--max-device-speed", f->max_device_speed_mps,
                  "a device state faster than this [m/s] is implausible: zero force (default: "
                  "the config's device.plausible_speed_mps, else 10)");
  app->add_option("--test-drop", f->test_drop, "udp, TEST ONLY: drop this fraction of packets");
  app->add_option("--key", f->key_file,
                  "udp: pre-shared key file (rigidtouch keygen); default: the per-user key, "
                  "created on first use");
  app->add_option("--taps", f->taps, "taps of the simulated hand (sim)")->capture_default_str();
  app->add_option("--speed", f->speed_mps, "approach speed of the simulated hand [m/s] (sim)")
      ->capture_default_str();
  auto* wall_geom = app->add_option("--wall-geom", f->wall_geom,
                                    "sim, replay: the geom the simulated hand taps, as tap's "
                                    "--wall-geom takes it (default: the surface below the scene's "
                                    "tool)");
  auto* wall_point =
      app->add_option("--wall-point", f->wall_point,
                      "sim, replay: a point of the surface the hand taps X Y Z [m] (with "
                      "--wall-normal)")
          ->expected(3);
  auto* wall_normal = app->add_option("--wall-normal", f->wall_normal,
                                      "sim, replay: that surface's outward normal X Y Z; the hand "
                                      "taps along its opposite")
                          ->expected(3);
  wall_point->needs(wall_normal)->excludes(wall_geom);
  wall_normal->needs(wall_point);
  app->add_option("--workspace-offset", f->workspace_offset,
                  "udp: the tool is at the device's position plus this X Y Z [m] (default 0 0 0)")
      ->expected(3);
  app->add_option("--trace", f->trace, "write the trace CSV here");
  app->add_option("--record", f->record,
                  "write every tick's device state and command here (replay with --device "
                  "replay:LOG; docs/device-protocol.md)");
  app->add_option("--replay-pace", f->replay_pace,
                  "replay: rate (at the loop's deadlines) or max (as fast as it computes)")
      ->check(CLI::IsMember({"rate", "max"}))
      ->capture_default_str();
  app->add_flag("--json", f->json, "print one JSON object");
  app->footer(
      std::string(kPrecedence) +
      "\n\nDevice limits: a --stiffness or --damping (or config value) above what the preset or "
      "the "
      "device can display is refused with an error naming the parameter and the limit (exit "
      "status 2); unset, they default to the preset's stiffness and to k h capped at its "
      "damping. Every command is clipped to the stricter force limit. Exit status 5: the UDP "
      "device sent no state within --startup-timeout.");
  // an error about a parameter the user wrote says where it was written
  app->callback([f, app] {
    f->rate_given = app->count("--rate") > 0;
    // no connection on the command line (--connect, or the old --device udp://...|sim): the
    // config file's device.connect, if any
    if (!f->connect && !(f->device && IsConnection(*f->device))) {
      f->connect = ResolveSettings(f->scene).connect;
    }
    CheckServeFlags(*f, *app);
    WithOrigins(ResolveSettings(f->scene), [&] { RunServe(*f); });
  });
}

const CommandRegistrar serve_registrar("serve", &RegisterServe);

}  // namespace
}  // namespace rigidtouch::cli
