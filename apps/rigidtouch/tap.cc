// `rigidtouch tap`: the tap experiment on the simulated hand and device, with metrics, trace and
// figures; `--compare-walls` runs the method's three walls side by side (the main job).
#include <cstdio>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <sstream>
#include <vector>

#include "analysis/figures.h"
#include "analysis/tap_experiment.h"
#include "command.h"
#include "io/config.h"
#include "io/output_file.h"
#include "io/resources.h"
#include "io/trace_csv.h"
#include "scene_flags.h"
#include "simulate_nonfinite.h"

namespace rigidtouch::cli {
namespace {

struct TapFlags {
  SceneFlags scene;
  std::optional<int> wall;
  std::string wall_geom;
  std::vector<double> wall_point, wall_normal;
  double rate_hz = 1000.0;
  std::string device = "touch";
  std::optional<std::string> coupling;  // default: the config file's, else direct
  double speed_mps = 0.2;
  double spread = 0.0;
  int taps = 3;
  std::uint64_t seed = 1;
  std::string trace;
  std::string plot;
  bool compare_walls = false;
  std::string out_dir = "out";
  bool json = false;
};

analysis::TapExperimentConfig MakeConfig(const TapFlags& f, std::optional<int> wall) {
  if (!(f.speed_mps > 0.0 && f.speed_mps <= 2.0)) {
    throw Error("--speed " + std::to_string(f.speed_mps) + " m/s is out of range: valid (0, 2]");
  }
  if (f.taps < 1 || f.taps > 1000) {
    throw Error("--taps " + std::to_string(f.taps) + " is out of range: valid 1 to 1000");
  }
  if (!(f.spread >= 0.0 && f.spread <= 0.5)) {
    throw Error("--spread " + std::to_string(f.spread) + " is out of range: valid [0, 0.5]");
  }
  analysis::TapExperimentConfig c = TapConfig(f.scene, f.device, f.rate_hz, f.speed_mps, f.taps);
  c.wall_geom = f.wall_geom;
  if (!f.wall_point.empty()) {
    c.wall_point_m = Vec3(f.wall_point[0], f.wall_point[1], f.wall_point[2]);
    c.wall_normal = Vec3(f.wall_normal[0], f.wall_normal[1], f.wall_normal[2]);
  }
  if (wall) {
    const RenderParams r = analysis::WallRenderParams(*wall);
    c.load.render.renderer = r.renderer;
    c.load.render.restitution = r.restitution;
    c.load.render.t_collision_s = r.t_collision_s;
    c.load.render.frequency_hz = r.frequency_hz;
  }
  const Settings settings = ResolveSettings(f.scene);
  if (f.coupling) {
    c.load.device.coupling = io::ParseCoupling(*f.coupling);
  } else if (!settings.Given("device.coupling")) {
    c.load.device.coupling = Coupling::kDirect;
  }
  if (c.load.device.coupling == Coupling::kDirect) {
    RefuseUnused(settings,
                 {"device.coupling_stiffness_N_per_m", "device.coupling_damping_Ns_per_m"},
                 "the coupling is direct (the device renders the tool's contact)");
  }
  if (c.load.device.coupling == Coupling::kNone) {
    throw Error(std::string(f.coupling ? "--coupling" : "device.coupling in " + f.scene.config) +
                " none has no device; valid couplings for tap: direct, virtual");
  }
  c.script.seed = f.seed;
  c.script.speed_spread = f.spread;
  return c;
}

// the run's non-finite resets: the experiment keeps the count and the last step only
NonFiniteReport NonFinite(const analysis::TapRun& run) {
  const WarningStat& w = run.warnings[static_cast<int>(Warning::kNonFiniteState)];
  NonFiniteReport r;
  r.count = w.count;
  r.step = w.last_step;
  r.time_s = static_cast<double>(w.last_step) * run.model.timestep_s;
  r.first = false;
  return r;
}

nlohmann::json RunJson(const analysis::TapRun& run, const char* coupling) {
  const Model& m = run.model;
  nlohmann::json taps = nlohmann::json::array();
  for (const analysis::TapMetrics& t : run.taps) {
    nlohmann::json impulses = nlohmann::json::array();
    for (const auto& e : t.impulses) {
      impulses.push_back({{"time_s", e.time_s},
                          {"kinetic_energy_before_J", e.kinetic_energy_before_J},
                          {"kinetic_energy_after_J", e.kinetic_energy_after_J}});
    }
    taps.push_back({{"tap", t.tap},
                    {"contact", t.contact},
                    {"approach_speed_mps", t.approach_speed_mps},
                    {"impulses", impulses},
                    {"peak_force_N", t.peak_force_N},
                    {"rate_hardness_N_per_m", t.rate_hardness_N_per_m},
                    {"extended_rate_hardness_N_per_m", t.extended_rate_hardness_N_per_m},
                    {"max_penetration_m", t.max_penetration_m},
                    {"time_to_stop_s", t.time_to_stop_s},
                    {"bounces", t.bounces},
                    {"energy_to_user_J", t.energy_to_user_J},
                    {"dominant_frequency_hz", t.dominant_frequency_hz},
                    {"band_energy_fraction", t.band_energy_fraction},
                    {"force_clipped", t.force_clipped},
                    {"passivity_dissipated_J", t.passivity_dissipated_J}});
  }
  const bool train = m.render.renderer == RendererKind::kTrain;
  return {
      {"renderer", io::RendererName(m.render.renderer)},
      {"restitution", m.render.restitution},
      {"frequency_hz", train ? nlohmann::json(m.render.frequency_hz) : nlohmann::json(nullptr)},
      {"t_collision_s", train ? nlohmann::json(m.render.t_collision_s) : nlohmann::json(nullptr)},
      {"impulses_per_window",
       train ? m.schedule.impulses : (m.render.renderer == RendererKind::kImpulse ? 1 : 0)},
      {"timestep_s", m.timestep_s},
      {"device", run.device.name},
      {"max_force_N", run.device.max_force_N},
      {"coupling", coupling},
      {"stiffness_N_per_m", m.contact.stiffness_N_per_m},
      {"damping_Ns_per_m", m.contact.damping_Ns_per_m},
      {"tool_mass_kg", m.bodies[m.tool].mass_kg},
      {"energy_to_user_J", run.energy_to_user_J},
      {"passivity_control", m.render.passivity_control},
      {"material", m.render.material.name.empty() ? nlohmann::json(nullptr)
                                                  : nlohmann::json(m.render.material.name)},
      {"clipped_ticks", run.clipped_ticks},
      {"clipped_impulse_ticks", run.clipped_impulse_ticks},
      {"taps", taps},
      {"warnings", WarningsJson(run.warnings)},
      {"non_finite_state", NonFiniteJson(NonFinite(run))}};
}

// draws a figure; a missing matplotlib is reported, not fatal (the trace is already written)
void Plot(const std::string& script, const std::vector<std::string>& args, bool quiet) {
  const analysis::FigureResult r = analysis::RunPlotScript(io::ShippedFile(script), args);
  if (r.status == analysis::FigureStatus::kOk) return;
  if (r.status == analysis::FigureStatus::kMissingMatplotlib) {
    std::cerr << "rigidtouch: matplotlib is missing (Debian: apt-get install python3-matplotlib); "
                 "no figure drawn, the trace was still written\n";
    return;
  }
  if (!quiet) std::cerr << r.output;
  throw Error("drawing " + script + " failed: " + r.message);
}

std::string Row(const std::string& name, const analysis::TapRun& run) {
  double peak = 0, rh = 0, erh = 0, pen = 0, energy = 0;
  int impulses = 0, bounces = 0;
  for (const auto& t : run.taps) {
    peak += t.peak_force_N;
    rh += t.rate_hardness_N_per_m;
    erh += t.extended_rate_hardness_N_per_m;
    pen += t.max_penetration_m;
    energy += t.energy_to_user_J;
    impulses += static_cast<int>(t.impulses.size());
    bounces += t.bounces;
  }
  const double n = std::max<std::size_t>(1, run.taps.size());
  std::ostringstream s;
  s << "| " << name << " | " << std::fixed << std::setprecision(2) << peak / n << " | "
    << std::setprecision(0) << rh / n << " | " << erh / n << " | " << std::setprecision(2)
    << 1000.0 * pen / n << " | " << std::setprecision(1) << impulses / n << " | " << bounces
    << " | " << std::scientific << std::setprecision(2) << energy << " |";
  return s.str();
}

const char* kTableHeader =
    "| wall | peak force [N] | rate hardness [N/m] | extended rate hardness [N/m] | "
    "max penetration [mm] | impulses per tap | bounces | energy to user [J] |\n"
    "|---|---|---|---|---|---|---|---|";

const char* kWallKeys[] = {"penalty", "wall0", "wall1", "wall2"};

std::string OutPath(const TapFlags& f, const std::string& name) {
  return (std::filesystem::path(f.out_dir) / name).string();
}

// every file --compare-walls writes, checked before the four runs
void CheckCompareWallsOutputs(const TapFlags& f) {
  io::CheckOutputDir(f.out_dir, "output folder (--out-dir)");
  std::error_code ec;
  if (!std::filesystem::exists(f.out_dir, ec)) return;
  for (const char* key : kWallKeys) {
    io::CheckOutputPath(OutPath(f, std::string(key) + ".csv"), "trace file");
  }
  io::CheckOutputPath(OutPath(f, "walls.md"), "table");
  io::CheckOutputPath(OutPath(f, "walls.png"), "figure");
  for (int w = 0; w <= 2; ++w) {
    io::CheckOutputPath(OutPath(f, "wall" + std::to_string(w) + "_tap.png"), "figure");
  }
}

void CompareWalls(const TapFlags& f) {
  CheckCompareWallsOutputs(f);
  std::error_code created;
  std::filesystem::create_directories(f.out_dir, created);
  if (created) {
    throw Error("cannot create the output folder (--out-dir) '" + f.out_dir +
                "': " + created.message());
  }
  const char* names[] = {"penalty (no impulses)", "wall 0: single impulse", "wall 1: train 250 Hz",
                         "wall 2: train 50 Hz"};
  std::vector<std::string> traces;
  nlohmann::json results = nlohmann::json::object();
  std::ostringstream table;
  table << kTableHeader << "\n";
  std::string coupling = "direct";
  NonFiniteReport non_finite;
  std::string non_finite_wall;
  for (int w = -1; w <= 2; ++w) {
    TapFlags g = f;
    std::optional<int> wall;
    if (w < 0) {
      g.scene.renderer = "penalty";
    } else {
      wall = w;
    }
    const analysis::TapRun run = analysis::RunTapExperiment(MakeConfig(g, wall));
    if (w < 0) PrintLoadWarnings(run.model);  // the same scene for every wall: once
    const std::string key = kWallKeys[w + 1];
    const std::string trace = OutPath(f, key + ".csv");
    io::WriteTraceCsv(trace, run.trace);
    if (w >= 0) traces.push_back(trace);
    coupling = io::CouplingName(run.model.device.coupling);
    results[key] = RunJson(run, coupling.c_str());
    results[key]["trace"] = trace;
    table << Row(names[w + 1], run) << "\n";
    if (non_finite.count == 0 && NonFinite(run).count > 0) {
      non_finite = NonFinite(run);
      non_finite_wall = names[w + 1];
    }
  }
  const std::string table_path = OutPath(f, "walls.md");
  {
    std::ostringstream out;
    out << "Means over " << f.taps << " taps at " << f.speed_mps << " m/s on the " << f.device
        << " preset (" << coupling << " coupling, " << f.rate_hz << " Hz)\n\n"
        << table.str();
    io::WriteFileAtomically(table_path, out.str(), "table");
  }
  const std::string fig = OutPath(f, "walls.png");
  std::vector<std::string> args = traces;
  args.insert(args.end(), {"--out", fig});
  Plot("python/plot_walls.py", args, f.json);
  for (int w = 0; w <= 2; ++w) {
    const std::string tap_fig = OutPath(f, "wall" + std::to_string(w) + "_tap.png");
    Plot("python/plot_tap.py", {traces[w], "--out", tap_fig}, f.json);
  }
  results["table"] = table_path;
  results["figures"] = {fig};
  auto check = [&non_finite, &non_finite_wall] {
    if (non_finite.count > 0) throw Error(non_finite_wall + ": " + NonFiniteMessage(non_finite));
  };
  if (f.json) {
    std::cout << results.dump() << "\n";
    check();
    return;
  }
  std::cout << table.str() << "\ntable: " << table_path << "\nfigures: " << fig << " and "
            << f.out_dir << "/wall{0,1,2}_tap.png\ntraces: " << f.out_dir
            << "/{penalty,wall0,wall1,wall2}.csv\n";
  check();
}

void Run(const TapFlags& f) {
  if (f.compare_walls) {
    CompareWalls(f);
    return;
  }
  if (f.wall && f.scene.renderer) throw Error("give either --wall or --renderer, not both");
  std::string trace = f.trace;
  bool temporary = false;
  if (trace.empty() && !f.plot.empty()) {
    trace = f.plot + ".trace.csv";
    temporary = true;
  }
  // a bad output path fails now, not after the run
  if (!trace.empty()) io::CheckOutputPath(trace, "trace file");
  if (!f.plot.empty()) io::CheckOutputPath(f.plot, "figure");
  const analysis::TapRun run = analysis::RunTapExperiment(MakeConfig(f, f.wall));
  PrintLoadWarnings(run.model);
  if (!trace.empty()) io::WriteTraceCsv(trace, run.trace);
  if (!f.plot.empty()) {
    // the temporary trace goes whether or not the figure could be drawn
    std::error_code ignored;
    try {
      Plot("python/plot_tap.py", {trace, "--out", f.plot}, f.json);
    } catch (...) {
      if (temporary) std::filesystem::remove(trace, ignored);
      throw;
    }
    if (temporary) std::filesystem::remove(trace, ignored);
  }
  nlohmann::json result = RunJson(run, io::CouplingName(run.model.device.coupling));
  if (!f.trace.empty()) result["trace"] = f.trace;
  if (f.json) {
    std::cout << result.dump() << "\n";
    ThrowIfNonFinite(NonFinite(run));
    return;
  }
  std::cout << kTableHeader << "\n" << Row(result["renderer"].get<std::string>(), run) << "\n";
  PrintWarnings(result["warnings"], std::cout);
  ThrowIfNonFinite(NonFinite(run));
}

void Register(CLI::App& root) {
  auto f = std::make_shared<TapFlags>();
  CLI::App* app = root.add_subcommand(
      "tap", "tap a wall with the simulated hand and device; metrics, trace and figures");
  AddSceneFlags(app, f->scene, /*scene_required=*/false);
  app->add_option("--wall", f->wall,
                  "the method's walls: 0 single impulse, 1 train 250 Hz, "
                  "2 train 50 Hz")
      ->check(CLI::IsMember({0, 1, 2}));
  auto* wall_geom =
      app->add_option("--wall-geom", f->wall_geom,
                      "the static plane or box the taps aim at (default: the geom named wall, "
                      "else the scene's only plane)");
  auto* wall_point = app->add_option("--wall-point", f->wall_point,
                                     "a point of the wall's surface X Y Z [m] (with --wall-normal)")
                         ->expected(3);
  auto* wall_normal =
      app->add_option("--wall-normal", f->wall_normal, "the wall's outward normal X Y Z")
          ->expected(3);
  wall_point->needs(wall_normal)->excludes(wall_geom);
  wall_normal->needs(wall_point);
  AddRateFlag(app, f->rate_hz, "haptic rate [Hz]");
  app->add_option("--device", f->device,
                  "the device: a preset or a JSON device spec (" + device::DeviceSpecHelp() +
                      "; docs/devices.md)")
      ->capture_default_str();
  app->add_option("--coupling", f->coupling,
                  "direct | virtual (default: the config's device.coupling, else direct)");
  app->add_option("--speed", f->speed_mps, "approach speed [m/s]")->capture_default_str();
  app->add_option("--spread", f->spread, "relative random spread of the speed (seeded)");
  app->add_option("--taps", f->taps, "number of taps")->capture_default_str();
  app->add_option("--seed", f->seed, "random seed")->capture_default_str();
  app->add_option("--trace", f->trace, "write the trace CSV here");
  app->add_option("--plot", f->plot, "draw one tap (penalty, impulsive, sum) to this PNG");
  app->add_flag("--compare-walls", f->compare_walls,
                "run penalty and walls 0, 1, 2; write traces, a table and figures to --out-dir");
  app->add_option("--out-dir", f->out_dir, "output folder of --compare-walls")
      ->capture_default_str();
  app->add_flag("--json", f->json, "print one JSON object");
  // an error about a parameter the user wrote says where it was written
  app->callback([f] { WithOrigins(ResolveSettings(f->scene), [&] { Run(*f); }); });
}

const CommandRegistrar registrar(&Register);

}  // namespace
}  // namespace rigidtouch::cli
