// `rigidtouch device-sim`: the simulated hand and device as their own real-time process, serving
// the UDP device protocol (docs/device-protocol.md) to `rigidtouch serve`.
#include <cmath>
#include <iostream>

#include "command.h"
#include "device/device_spec.h"
#include "device/simulated_device.h"
#include "device/udp_json.h"
#include "loop/loop_json.h"
#include "loop/rate_loop.h"
#include "loop/stop_signal.h"
#include "rigidtouch/bridge.h"
#include "rigidtouch/types.h"
#include "scene_flags.h"

namespace rigidtouch::cli {
namespace {

struct DeviceSimFlags {
  std::string listen = "udp://127.0.0.1:47000";
  std::optional<std::string> device;  // a preset or a JSON device spec; default touch
  std::optional<std::string> preset;  // old spelling of --device NAME
  double rate_hz = 1000.0;
  double duration_s = 0.0;
  int taps = 3;
  double speed_mps = 0.2;
  double wall_height_m = 0.005;  // where the tool centre touches the shipped wall scene
  double watchdog_s = 0.05;
  double session_timeout_s = 0.5;
  std::string key_file;  // empty: the per-user default key, created on first use
  double test_drop = 0.0;
  bool realtime = false;
  bool json = false;
};

void RunDeviceSim(const DeviceSimFlags& f) {
  if (f.device && f.preset) {
    throw Error("--device " + *f.device + " and --preset " + *f.preset +
                " both name the device (--preset is the old spelling of --device); give one");
  }
  const device::DeviceSpec spec =
      device::ParseDeviceSpec(f.device.value_or(f.preset.value_or("touch")));
  device::DeviceModelParams dm = spec.model;
  dm.tick_rate_hz = f.rate_hz;
  device::TapScript script;
  script.taps = f.taps;
  script.approach_speed_mps = f.speed_mps;
  script.surface_point_m = Vec3(0.0, 0.0, f.wall_height_m);
  device::SimulatedDevice sim(spec.limits, device::HandParams{}, dm, script);
  device::UdpDeviceServerOptions so;
  so.listen = f.listen;
  so.watchdog_s = f.watchdog_s;
  so.session_timeout_s = f.session_timeout_s;
  so.key_file = f.key_file;
  so.test_loss.incoming_fraction = f.test_drop;
  so.test_loss.outgoing_fraction = f.test_drop;
  device::UdpDeviceServer server(sim, so);
  loop::LoopOptions lo;
  lo.rate_hz = f.rate_hz;
  lo.duration_s = f.duration_s;
  lo.realtime_priority = f.realtime;
  lo.lock_memory = f.realtime;
  loop::RateLoop loop(lo);
  const std::atomic<bool>& stop = loop::InstallStopSignalHandlers();
  const double period_s = 1.0 / f.rate_hz;
  const loop::LoopStats stats = loop.Run(
      [&](std::int64_t, double) {
        server.Step();  // Read and Write
        sim.EndPeriod(period_s);
        return true;
      },
      &stop);
  server.Release();  // the device stops pushing with the renderer's last command
  const nlohmann::json result = {{"loop", loop::ToJson(stats)},
                                 {"link", device::ToJson(server.counters())},
                                 {"energy_to_user_J", sim.energy_to_user_J()},
                                 {"taps_finished", sim.finished()}};
  if (f.json) {
    std::cout << result.dump() << "\n";
  } else {
    std::cout << "device-sim served " << stats.ticks << " ticks at " << stats.achieved_rate_hz
              << " Hz; energy delivered to the user " << sim.energy_to_user_J() << " J\n";
  }
}

void RegisterDeviceSim(CLI::App& root) {
  auto f = std::make_shared<DeviceSimFlags>();
  CLI::App* app =
      root.add_subcommand("device-sim", "run the simulated hand and device as a UDP device server");
  app->add_option("--listen", f->listen, "udp://HOST:PORT to bind (loopback unless told)")
      ->capture_default_str();
  app->add_option("--device", f->device,
                  "the simulated device: a preset or a JSON device spec (" +
                      device::DeviceSpecHelp() + ", default touch)");
  app->add_option("--preset", f->preset, "old spelling of --device NAME");
  AddRateFlag(app, f->rate_hz, "device rate [Hz]");
  app->add_option("--duration", f->duration_s, "run time [s]; 0: until SIGINT/SIGTERM")
      ->check(InRange(0.0, INFINITY, "s"));
  app->add_option("--taps", f->taps, "scripted taps")->capture_default_str();
  app->add_option("--speed", f->speed_mps, "approach speed [m/s]")->capture_default_str();
  app->add_option("--wall-height", f->wall_height_m,
                  "height of the tool centre at contact [m] (the shipped wall: 0.005)");
  app->add_option("--watchdog", f->watchdog_s, "no fresh command for this long: zero force")
      ->capture_default_str();
  app->add_option("--session-timeout", f->session_timeout_s,
                  "no authenticated datagram from the renderer for this long ends its session [s]")
      ->capture_default_str();
  app->add_option("--key", f->key_file,
                  "pre-shared key file (rigidtouch keygen); default: the per-user key, "
                  "created on first use");
  app->add_option("--test-drop", f->test_drop, "TEST ONLY: drop this fraction of packets");
  app->add_flag("--realtime", f->realtime, "SCHED_FIFO and locked memory when allowed");
  app->add_flag("--json", f->json, "print one JSON object");
  app->callback([f] { RunDeviceSim(*f); });
}

const CommandRegistrar device_sim_registrar("device-sim", &RegisterDeviceSim);

}  // namespace
}  // namespace rigidtouch::cli
