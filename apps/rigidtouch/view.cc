// `rigidtouch view`: the live viewer. The haptic loop runs on its own thread exactly as in `serve`
// (the same loop::RunHapticLoop, at its rate); the window draws the snapshots the loop publishes,
// at display rate, without ever blocking or locking the haptic thread.
#include <atomic>
#include <cmath>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>
#include <string_view>
#include <thread>

#include "analysis/tap_experiment.h"
#include "base/text.h"
#include "command.h"
#include "device/device_spec.h"
#include "device/mouse_device.h"
#include "device/presets.h"
#include "device/replay_device.h"
#include "device/udp_device.h"
#include "io/config.h"
#include "io/device_record.h"
#include "io/output_file.h"
#include "loop/haptic_loop.h"
#include "loop/loop_json.h"
#include "loop/stop_signal.h"
#include "scene_flags.h"
#include "view/feed.h"
#include "view/viewer.h"

namespace rigidtouch::cli {
namespace {

struct ViewFlags {
  SceneFlags scene;
  std::string device = "mouse";
  std::string preset = "touch";
  std::optional<std::string> connect;  // --connect: how the device is reached (then --device is it)
  double rate_hz = 1000.0;
  bool rate_given = false;
  int taps = 3;
  double speed_mps = 0.2;
  std::string record;
  int frames = 0;
  std::string screenshot;
  std::string mouse_path;
  int tap_frame = -1;
  int switch_frame = -1;
  std::string switch_to = "penalty";
  bool switch_at_contact = false;
  double display_hz = 60.0;
  int width_px = 1280, height_px = 720;
  bool realtime = false;
  bool json = false;
  std::string key_file;  // udp: empty means the per-user default key
  double startup_timeout_s = 1.0;
};

std::vector<std::pair<double, double>> ParsePath(const std::string& text) {
  std::vector<std::pair<double, double>> out;
  std::istringstream in(text);
  std::string point;
  while (in >> point) {
    const auto comma = point.find(',');
    double x = 0.0, y = 0.0;
    char* end = nullptr;
    bool ok = comma != std::string::npos;
    if (ok) {
      x = std::strtod(point.c_str(), &end);
      ok = end == point.c_str() + comma;
      y = std::strtod(point.c_str() + comma + 1, &end);
      ok = ok && *end == '\0' && std::isfinite(x) && std::isfinite(y);
    }
    if (!ok) throw Error("view: --mouse-path point '" + point + "' is not X,Y in pixels");
    out.emplace_back(x, y);
  }
  if (out.empty()) throw Error("view: --mouse-path holds no point");
  return out;
}

// the flags that do not go together, before anything is opened
void CheckViewFlags(const ViewFlags& f) {
  const bool replay = f.device.starts_with(kReplayPrefix);
  const bool udp = f.device.starts_with("udp://");
  if (f.device != "mouse" && f.device != "sim" && !replay && !udp) {
    throw Error("view: --device '" + f.device +
                "' is not mouse, sim, udp://HOST:PORT or replay:LOG");
  }
  if (!udp && !f.key_file.empty()) throw Error("view: --key applies to --device udp://HOST:PORT");
  if (!f.screenshot.empty() && f.frames <= 0) {
    throw Error("view: --screenshot needs --frames N (the last of N frames is written)");
  }
  if (f.device != "mouse" && (!f.mouse_path.empty() || f.tap_frame >= 0)) {
    throw Error("view: --mouse-path and --tap-at-frame drive --device mouse only");
  }
}

// a replay runs at its record's rate (an explicit --rate must agree); the others at --rate
double ReadReplayRecord(const ViewFlags& f, std::optional<io::Record>& recorded) {
  double rate_hz = f.rate_hz;
  if (f.device.starts_with(kReplayPrefix)) {
    const std::string log = f.device.substr(kReplayPrefix.size());
    recorded = io::ReadRecord(log);
    if (f.rate_given && f.rate_hz != recorded->rate_hz) {
      std::ostringstream m;
      m << "view: --rate " << f.rate_hz << " Hz differs from the record's rate "
        << recorded->rate_hz << " Hz in '" << log << "'";
      throw Error(m.str());
    }
    rate_hz = recorded->rate_hz;
  }
  return rate_hz;
}

view::ViewerOptions MakeViewerOptions(const ViewFlags& f, double rate_hz) {
  view::ViewerOptions vo;
  vo.frames = f.frames;
  vo.hidden = f.frames > 0;
  vo.screenshot = f.screenshot;
  vo.tap_frame = f.tap_frame;
  vo.display_hz = f.display_hz;
  vo.rate_hz = rate_hz;
  vo.device = f.device;
  vo.width_px = f.width_px;
  vo.height_px = f.height_px;
  if (!f.mouse_path.empty()) vo.mouse_path = ParsePath(f.mouse_path);
  // SIGINT or SIGTERM closes the window as its close button does, so a record is still committed
  vo.stop = &loop::InstallStopSignalHandlers();
  vo.switch_frame = f.switch_frame;
  vo.switch_at_contact = f.switch_at_contact;
  if (f.switch_frame >= 0 || f.switch_at_contact) vo.switch_to = io::ParseRenderer(f.switch_to);
  return vo;
}

// the device the loop drives: owned here unless it is the tap setup's simulated one
struct ViewDevice {
  std::unique_ptr<device::Device> owned;
  device::MouseDevice* mouse = nullptr;
  device::Device* dev = nullptr;
};

// opens --device; the replay's first position and the UDP device's announced limits go into the
// model, and the simulated hand's script sets the loop's duration
ViewDevice OpenViewDevice(const ViewFlags& f, analysis::TapSetup& setup,
                          std::optional<io::Record>& recorded, loop::LoopOptions& lo) {
  Model& model = setup.model;
  ViewDevice d;
  d.dev = setup.simulated.get();
  if (f.device == "mouse") {
    auto m = std::make_unique<device::MouseDevice>(setup.device, device::MouseDeviceParams{},
                                                   model.initial[model.tool].x_W);
    d.mouse = m.get();
    d.owned = std::move(m);
  } else if (f.device.starts_with(kReplayPrefix)) {
    auto r = std::make_unique<device::ReplayDevice>(std::move(recorded->samples), setup.device);
    model.initial[model.tool].x_W = r->first_state().position_m;
    d.owned = std::move(r);
  } else if (f.device.starts_with("udp://")) {
    // the UDP bridge as in serve: the preset's limits until the device announces its own
    device::UdpDeviceOptions uo;
    uo.server = f.device;
    uo.limits = setup.device;
    uo.key_file = f.key_file;
    auto u = std::make_unique<device::UdpDevice>(uo);
    if (!loop::AwaitFirstState(*u, f.startup_timeout_s, nullptr)) {
      std::cerr << "rigidtouch: error: view: no state from the device at " << f.device << " within "
                << f.startup_timeout_s << " s (--startup-timeout); is the device server running?\n";
      throw CLI::RuntimeError(kExitNoDevice);
    }
    device::TightenDeviceParams(model.device, u->limits());
    d.owned = std::move(u);
  } else {
    lo.duration_s = setup.simulated->duration_s();
  }
  if (d.owned) d.dev = d.owned.get();
  return d;
}

// what the loop segments add up to (a renderer switch ends one segment and starts the next)
struct LoopTotals {
  std::int64_t impulses = 0, ticks = 0;
  double max_force_N = 0.0;
  bool finite = true;
};

void PrintViewResult(const ViewFlags& f, const Model& model, const Data& data,
                     const loop::HapticLoopResult& r, const LoopTotals& totals,
                     const view::ViewerResult& vr, RecordOutput& record) {
  nlohmann::json result;
  result["loop"] = loop::ToJson(r.timing);  // the last segment's timing
  result["ticks"] = totals.ticks;
  result["renderer_switches"] = vr.renderer_switches;
  result["renderer_switch_wait_frames"] = vr.switch_wait_frames;
  result["renderer"] = text::RendererName(model.render.renderer);
  result["frames"] = vr.frames;
  result["display_rate_hz"] = vr.elapsed_s > 0.0 ? vr.frames / vr.elapsed_s : 0.0;
  result["impulses"] = totals.impulses;
  result["max_force_N"] = totals.max_force_N;
  result["force_limit_N"] = r.force_limit_N;
  result["finite"] = totals.finite;
  result["device"] = f.device;
  result["warnings"] = WarningsJson(data);
  result["joints"] = loop::JointsJson(model, data);
  if (!f.screenshot.empty()) result["screenshot"] = f.screenshot;
  if (record.queue) {
    result["record_queue"] = FinishRecord(record, f.record);
    result["record"] = f.record;
  }
  if (f.json) {
    std::cout << result.dump() << "\n";
  } else {
    const auto& t = result["loop"];
    std::cout << "frames " << vr.frames << " in " << text::Significant(vr.elapsed_s, 3)
              << " s; loop ticks " << t["ticks"] << " at "
              << text::Significant(t["achieved_rate_hz"].get<double>(), 4)
              << " Hz, period error p99 "
              << text::Significant(1e6 * t["period_error_p99_s"].get<double>(), 3) << " us, max "
              << text::Significant(1e6 * t["period_error_max_s"].get<double>(), 3) << " us\n";
  }
}

void RunView(const ViewFlags& f) {
  CheckViewFlags(f);
  std::optional<io::Record> recorded;
  const double rate_hz = ReadReplayRecord(f, recorded);
  const view::ViewerOptions vo = MakeViewerOptions(f, rate_hz);

  loop::LoopOptions lo;
  lo.rate_hz = rate_hz;
  lo.realtime_priority = f.realtime;
  lo.lock_memory = f.realtime;
  loop::ValidateLoopOptions(lo);

  // the model as on serve's simulated path: the preset's wall, the device and hand on the tool
  analysis::TapExperimentConfig c = TapConfig(f.scene, f.preset, rate_hz, f.speed_mps, f.taps);
  c.load.device.coupling = Coupling::kDirect;
  c.aim_below_tool = true;
  analysis::TapSetup setup = analysis::PrepareTap(c);
  Model& model = setup.model;
  PrintLoadWarnings(model);
  PrintMaterialNote(setup.material_note);
  const ViewDevice vd = OpenViewDevice(f, setup, recorded, lo);
  device::Device* dev = vd.dev;
  device::TightenDeviceParams(model.device, setup.device);
  Configure(model);

  RecordOutput record = OpenRecord(f.record, rate_hz);
  loop::RecordQueue* records = record.queue.get();
  // the scope queue holds 0.25 s of ticks between two frames
  view::ViewFeed feed(rate_hz, static_cast<std::size_t>(std::max(1024.0, 0.25 * rate_hz)));
  Data data = MakeData(model);
  std::atomic<bool> stop{false};
  loop::HapticLoopResult r;  // the current segment's (a renderer switch starts a new one)
  LoopTotals totals;
  std::exception_ptr loop_error;
  std::thread haptic;
  const double sim_duration_s = lo.duration_s;
  const auto start = [&] {
    stop.store(false);
    if (f.device == "sim") {
      // a restarted loop runs what is left of the simulated hand's script
      lo.duration_s = std::max(1.0 / rate_hz, sim_duration_s - setup.simulated->time_s());
    }
    haptic = std::thread([&] {
      try {
        // stops when the window closes, the frames are drawn or the renderer is switched
        r = loop::RunHapticLoop(model, data, *dev, lo, &stop, nullptr, records, &feed);
      } catch (...) {
        loop_error = std::current_exception();
      }
    });
  };
  const auto halt = [&] {
    stop.store(true);
    haptic.join();
    totals.impulses += r.impulses;
    totals.ticks += r.timing.ticks;
    totals.max_force_N = std::max(totals.max_force_N, r.max_force_N);
    totals.finite = totals.finite && r.finite;
  };
  // between two loop runs on the same Data: the model's renderer changes only while the haptic
  // thread is stopped, and only when no contact is active (checked on the stopped state)
  const view::RendererSwitch switch_renderer =
      [&](RendererKind kind) -> std::optional<std::string> {
    halt();
    std::optional<std::string> outcome;
    if (data.tool_contacts == 0 && !loop_error) {
      const RenderParams before = model.render;
      model.render.renderer = kind;
      try {
        Configure(model);
        outcome = "";
      } catch (const Error& e) {
        model.render = before;
        Configure(model);
        outcome = std::string("cannot switch: ") + e.what();
      }
    }
    start();
    return outcome;
  };
  start();
  view::ViewerResult vr;
  std::exception_ptr view_error;
  try {
    vr = view::RunViewer(model, feed, vd.mouse, vo, switch_renderer);
  } catch (...) {
    view_error = std::current_exception();
  }
  halt();
  if (view_error) std::rethrow_exception(view_error);
  if (loop_error) std::rethrow_exception(loop_error);

  PrintViewResult(f, model, data, r, totals, vr, record);
}

void RegisterView(CLI::App& root) {
  auto f = std::make_shared<ViewFlags>();
  CLI::App* app = root.add_subcommand("view", "live viewer: the scene, the tool, the forces");
  AddSceneFlags(app, f->scene, /*scene_required=*/false);
  AddThreadsFlag(app, f->scene);
  app->add_option("--device", f->device,
                  "mouse (drag the tool; wheel: depth; T: tap), sim (the simulated hand's taps), "
                  "udp://HOST:PORT (the device bridge), replay:LOG (a --record file), or a "
                  "device (" +
                      device::DeviceSpecHelp() +
                      ": the simulated hand's taps on that device, as sim with --preset)")
      ->capture_default_str();
  app->add_option("--connect", f->connect,
                  "how the device is reached: mouse (default), sim, udp://HOST:PORT or "
                  "replay:LOG, as --device's first forms (then --device names the device)");
  app->add_option("--preset", f->preset,
                  "the device (" + device::DeviceSpecHelp() +
                      "): its limits and the simulated device's model")
      ->capture_default_str();
  AddRateFlag(app, f->rate_hz, "haptic loop rate [Hz]");
  app->add_option("--taps", f->taps, "taps of the simulated hand (sim)")->capture_default_str();
  app->add_option("--speed", f->speed_mps, "approach speed of the simulated hand [m/s] (sim)")
      ->capture_default_str();
  app->add_option("--record", f->record, "write every tick's device state and command here");
  app->add_option("--frames", f->frames, "draw this many frames off-screen, then exit")
      ->check(CLI::Range(1, 1000000));
  app->add_option("--screenshot", f->screenshot, "write the last of --frames as PNG");
  app->add_option("--mouse-path", f->mouse_path,
                  "scripted cursor for --frames: 'X,Y X,Y ...' in pixels, followed evenly");
  app->add_option("--tap-at-frame", f->tap_frame, "press the tap key at this frame (scripted)")
      ->check(CLI::Range(0, 1000000));
  app->add_option("--switch-at-frame", f->switch_frame,
                  "switch the renderer at this frame, once no contact is active (scripted)")
      ->check(CLI::Range(0, 1000000));
  app->add_flag("--switch-at-contact", f->switch_at_contact,
                "ask for the switch at the first frame showing a tool contact (scripted; it "
                "happens once the contact is over)");
  app->add_option("--switch-to", f->switch_to, "the renderer --switch-at-frame switches to")
      ->check(CLI::IsMember({"penalty", "impulse", "train"}))
      ->capture_default_str();
  app->add_option("--display-rate", f->display_hz, "frames per second [Hz]")
      ->check(CLI::Range(1.0, 240.0))
      ->capture_default_str();
  app->add_option("--width", f->width_px, "window width [px]")->check(CLI::Range(320, 4096));
  app->add_option("--height", f->height_px, "window height [px]")->check(CLI::Range(240, 4096));
  app->add_option("--key", f->key_file, "udp: pre-shared key file (default: the per-user key)");
  app->add_option("--startup-timeout", f->startup_timeout_s,
                  "udp: no first state from the device within this long [s]: exit status 5")
      ->check(CLI::Range(1e-3, 3600.0))
      ->capture_default_str();
  app->add_flag("--realtime", f->realtime, "SCHED_FIFO and locked memory when allowed");
  app->add_flag("--json", f->json, "print one JSON object at the end");
  app->callback([f, app] {
    f->rate_given = app->count("--rate") > 0;
    if (f->connect) {
      // serve's spelling: --connect says how, --device which device
      const std::string& how = *f->connect;
      if (how != "mouse" && !IsConnection(how)) {
        throw Error("view: --connect " + how +
                    ": valid: mouse, sim, udp://HOST:PORT or replay:LOG; the device itself is "
                    "--device " +
                    device::DeviceSpecHelp());
      }
      if (app->count("--device") > 0) {
        if (f->device == "mouse" || IsConnection(f->device)) {
          throw Error("view: --device " + f->device + " and --connect " + how +
                      " both say how the device is reached; give it once, with --connect");
        }
        if (app->count("--preset") > 0) {
          throw Error("view: --device " + f->device + " and --preset " + f->preset +
                      " both name the device (--preset is the old spelling); give one");
        }
        device::ParseDeviceSpec(f->device);
        f->preset = f->device;
      }
      f->device = how;
    }
    if (f->device != "mouse" && !IsConnection(f->device)) {
      // a device spec (a preset name or FILE.json): the simulated hand taps on that device
      if (app->count("--preset") > 0) {
        throw Error("view: --device " + f->device + " and --preset " + f->preset +
                    " both name the device; give one");
      }
      device::ParseDeviceSpec(f->device);  // a bad spec names its field before anything runs
      f->preset = f->device;
      f->device = "sim";
    }
    if (f->device != "sim" && (app->count("--taps") + app->count("--speed")) > 0) {
      throw Error("view: --taps and --speed script the simulated hand (--device sim)");
    }
    if (app->count("--switch-to") > 0 && f->switch_frame < 0 && !f->switch_at_contact) {
      throw Error("view: --switch-to needs --switch-at-frame or --switch-at-contact");
    }
    WithOrigins(ResolveSettings(f->scene), [&] { RunView(*f); });
  });
}

const CommandRegistrar view_registrar("view", &RegisterView);

}  // namespace
}  // namespace rigidtouch::cli
