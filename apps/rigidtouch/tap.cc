// `rigidtouch tap`: the tap experiment on the simulated hand and device, with metrics, trace and
// figures; `--compare LIST` runs renderers side by side, `--compare-walls` the method's three
// walls and pure penalty (the main job).
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <set>
#include <sstream>
#include <vector>

#include "analysis/figures.h"
#include "analysis/renderer_spec.h"
#include "analysis/tap_experiment.h"
#include "base/text.h"
#include "command.h"
#include "io/config.h"
#include "io/materials.h"
#include "io/output_file.h"
#include "io/resources.h"
#include "io/trace_csv.h"
#include "scene_flags.h"
#include "simulate_nonfinite.h"
#include "tap_run.h"
#include "tap_table.h"

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
  std::string compare;
  std::string compare_joint_limit;  // the joint limits' renderers, side by side
  std::string out_dir = "out";
  bool json = false;
  bool quiet = false;          // `tap` only: no progress on stderr
  bool out_dir_given = false;  // --out-dir was written (it has a default)
};

// the method's walls fix the render parameters: a value the user wrote for one is refused
const std::vector<std::string> kWallFixedFields = {"render.restitution", "render.t_collision_s",
                                                   "render.frequency_hz"};
constexpr const char* kWallFixedWhy =
    "the method's walls (--wall, wall0/1/2 in --compare, --compare-walls) fix e, t_c and f";

analysis::TapExperimentConfig MakeConfig(const TapFlags& f, std::optional<int> wall,
                                         const analysis::RendererSpec* spec = nullptr,
                                         bool joint_limit = false) {
  std::optional<RenderParams> wall_params;
  if (wall) wall_params = analysis::WallRenderParams(*wall);
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
  if (spec && joint_limit) {
    // --compare-joint-limit: the spec is how the joint limits render; the contact keeps its own
    c.load.render.joint_limit_renderer = spec->renderer;
  } else if (spec) {
    c.load.render.renderer = spec->renderer;
    if (spec->render) wall_params = spec->render;
    if (spec->material) {
      // as --material: the event renderer's transient, or a material train's f and window
      if (spec->renderer == RendererKind::kTrain) {
        RefuseUnused(ResolveSettings(f.scene), {"render.t_collision_s", "render.frequency_hz"},
                     "a material train takes f and t_c from its material (docs/renderers.md)");
      }
      io::ApplyMaterial(c.load.render, *spec->material);
    }
  }
  if (wall_params) {
    RefuseUnused(ResolveSettings(f.scene), kWallFixedFields, kWallFixedWhy);
    const RenderParams r = *wall_params;
    c.load.render.renderer = r.renderer;
    c.load.render.restitution = r.restitution;
    c.load.render.t_collision_s = r.t_collision_s;
    c.load.render.frequency_hz = r.frequency_hz;
  }
  const Settings settings = ResolveSettings(f.scene);
  RefuseUnused(settings, {"device.connect"}, "tap runs its own simulated device in process");
  c.widen_plausible_radius = !settings.Given("device.plausible_radius_m");
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
  // a comparison's renderers share the flags: RunTap checks them against the whole list
  if (!spec) RefuseUnusedRender(settings, {c.load.render.renderer});
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

// a moving wall's joint: what it is, its motion per tick (WallSample) and per tap; null for a
// static wall or a link without a hinge or slide
nlohmann::json JointJson(const analysis::TapRun& run) {
  if (!run.wall.moving() || run.wall.joint < 0) return nullptr;
  const bool hinge = run.joint_kind == JointKind::kHinge;
  nlohmann::json time = nlohmann::json::array(), position = nlohmann::json::array(),
                 velocity = nlohmann::json::array();
  for (std::size_t k = 0; k < run.wall_trace.size(); ++k) {
    time.push_back(run.trace[k].time_s);
    position.push_back(run.wall_trace[k].joint_position);
    velocity.push_back(run.wall_trace[k].joint_velocity);
  }
  return {{"name", run.joint_name},
          {"kind", JointKindName(run.joint_kind)},
          {"position_unit", hinge ? "rad" : "m"},
          {"velocity_unit", hinge ? "rad/s" : "m/s"},
          {"impulse_unit", hinge ? "N m s" : "N s"},
          {"inertia", run.joint_inertia},
          {"inertia_unit", hinge ? "kg m^2" : "kg"},
          {"damping", run.joint_damping},
          {"stiffness", run.joint_stiffness},
          {"time_s", time},
          {"position", position},
          {"velocity", velocity}};
}

// one tap's joint motion (JointMotion) with the swing a damper alone allows: impulse / damping
nlohmann::json JointTapJson(const analysis::TapRun& run, std::size_t tap) {
  if (tap >= run.joint_taps.size()) return nullptr;
  const analysis::JointMotion& j = run.joint_taps[tap];
  const JointModel& joint = run.model.trees[run.wall.tree].joints[run.wall.joint];
  const bool at_limit = joint.limited && (j.max_position > joint.range_hi_rad_or_m + 1e-9 ||
                                          j.min_position < joint.range_lo_rad_or_m - 1e-9);
  const bool closed_form = run.joint_damping > 0.0 && run.joint_stiffness == 0.0 && !at_limit;
  return {{"position_at_start", j.position_at_start},
          {"position_at_end", j.position_at_end},
          {"velocity_at_end", j.velocity_at_end},
          {"min_position", j.min_position},
          {"max_position", j.max_position},
          {"peak_speed", j.peak_speed},
          {"impulse", j.impulse},
          {"past_limit", at_limit},
          {"damped_swing",
           closed_form ? nlohmann::json(j.impulse / run.joint_damping) : nlohmann::json(nullptr)}};
}

nlohmann::json WallJson(const analysis::TapRun& run) {
  const analysis::Wall& w = run.wall;
  return {{"geom", w.geom.empty() ? nlohmann::json(nullptr) : nlohmann::json(w.geom)},
          {"moving", w.moving()},
          {"point_m", {w.point_m.x(), w.point_m.y(), w.point_m.z()}},
          {"normal", {w.normal.x(), w.normal.y(), w.normal.z()}}};
}

nlohmann::json RunJson(const analysis::TapRun& run, const char* coupling) {
  const Model& m = run.model;
  const bool material = !m.render.material.name.empty();
  nlohmann::json taps = nlohmann::json::array();
  for (const analysis::TapMetrics& t : run.taps) {
    nlohmann::json impulses = nlohmann::json::array();
    for (const auto& e : t.impulses) {
      impulses.push_back({{"time_s", e.time_s},
                          {"requested_force_N", e.requested_force_N},
                          {"kinetic_energy_before_J", e.kinetic_energy_before_J},
                          {"kinetic_energy_after_J", e.kinetic_energy_after_J}});
    }
    taps.push_back({{"tap", t.tap},
                    {"contact", t.contact},
                    {"approach_speed_mps", t.approach_speed_mps},
                    {"impulses", impulses},
                    {"peak_force_N", t.peak_force_N},
                    {"peak_requested_force_N", t.peak_requested_force_N},
                    {"rate_hardness_N_per_m", t.rate_hardness_N_per_m},
                    {"extended_rate_hardness_N_per_m", t.extended_rate_hardness_N_per_m},
                    {"max_penetration_m", t.max_penetration_m},
                    {"time_to_stop_s", t.time_to_stop_s},
                    {"bounces", t.bounces},
                    {"energy_to_user_J", t.energy_to_user_J},
                    {"band_energy_fraction", t.band_energy_fraction},
                    {"spectrum_window_s", t.spectrum_window_s},
                    {"spectrum_resolution_hz", t.spectrum_resolution_hz},
                    {"transient_repetition_hz", t.transient_repetition_hz},
                    {"transient_periodicity", t.transient_periodicity},
                    {"transient_peak_to_mean", t.transient_peak_to_mean},
                    {"transient_band_energy_fraction", t.transient_band_energy_fraction},
                    {"transient_power_ratio", t.transient_power_ratio},
                    {"force_clipped", t.force_clipped},
                    {"passivity_dissipated_J", t.passivity_dissipated_J}});
    if (run.wall.moving()) taps.back()["joint"] = JointTapJson(run, taps.size() - 1);
  }
  const bool train = m.render.renderer == RendererKind::kTrain;
  // what the device displays (the contact law under direct coupling, the coupling under virtual)
  // against what the preset says it can: tap's device is simulated and renders a wall beyond
  // them (a Z-width map explores past them), where serve refuses it for a real device
  const bool direct = m.device.coupling == Coupling::kDirect;
  const double k = direct ? m.contact.stiffness_N_per_m : m.device.coupling_stiffness_N_per_m;
  const double b = direct ? m.contact.damping_Ns_per_m : m.device.coupling_damping_Ns_per_m;
  const auto within = [](double value, double limit) { return !(limit > 0.0) || value <= limit; };
  const bool displayable =
      within(k, run.device.max_stiffness_N_per_m) && within(b, run.device.max_damping_Ns_per_m);
  return {
      {"renderer", text::RendererName(m.render.renderer)},
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
      {"displayable", displayable},
      {"tool_mass_kg", m.bodies[m.tool].mass_kg},
      {"energy_to_user_J", run.energy_to_user_J},
      {"passivity_control", m.render.passivity_control},
      {"material", material ? nlohmann::json(m.render.material.name) : nlohmann::json(nullptr)},
      // the amplitude as rendered on this device, and the mass an acceleration material was
      // converted with (io::MaterialOnDevice)
      {"material_amplitude_Ns_per_m",
       material ? nlohmann::json(m.render.material.amplitude_Ns_per_m) : nlohmann::json(nullptr)},
      {"material_effective_mass_kg", material && m.render.material.acceleration()
                                         ? nlohmann::json(m.render.material.effective_mass_kg)
                                         : nlohmann::json(nullptr)},
      {"clipped_ticks", run.clipped_ticks},
      {"clipped_impulse_ticks", run.clipped_impulse_ticks},
      {"taps", taps},
      {"warnings", WarningsJson(run.warnings)},
      {"non_finite_state", NonFiniteJson(NonFinite(run))},
      {"joint_limit_renderer",
       run.wall.moving() ? nlohmann::json(text::RendererName(m.render.joint_limit_renderer))
                         : nlohmann::json(nullptr)},
      {"wall", WallJson(run)},
      {"joint", JointJson(run)}};
}

// a moving wall's joint per tick, for the figures: time, tap, position, velocity and the
// impulse the tool gave the joint (units in the header); nothing for a static wall
bool WriteJointCsv(const std::string& path, const analysis::TapRun& run) {
  if (!run.wall.moving() || run.wall.joint < 0) return false;
  const bool hinge = run.joint_kind == JointKind::kHinge;
  std::ostringstream out;
  out << std::setprecision(10) << "time_s,tap,"
      << (hinge ? "position_rad,velocity_rad_per_s,impulse_Nms"
                : "position_m,velocity_mps,impulse_Ns")
      << "\n";
  for (std::size_t k = 0; k < run.wall_trace.size(); ++k) {
    const analysis::WallSample& w = run.wall_trace[k];
    out << run.trace[k].time_s << "," << run.trace[k].tap << "," << w.joint_position << ","
        << w.joint_velocity << "," << w.joint_impulse << "\n";
  }
  io::WriteFileAtomically(path, out.str(), "joint trace");
  return true;
}

// a trace's joint file: beside it, "_joint" before the extension
std::string JointPath(const std::string& trace) {
  std::filesystem::path p(trace);
  return (p.parent_path() / (p.stem().string() + "_joint.csv")).string();
}

// matplotlib takes the figure's format from the extension: one it cannot write is refused before
// the run (it failed after it, with a Python traceback)
void CheckFigureFormat(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  for (const char* ok : {".png", ".pdf", ".svg", ".eps", ".ps", ".jpg", ".jpeg", ".tif", ".tiff"}) {
    if (ext == ok) return;
  }
  throw Error("--plot '" + path + "': the figure's format comes from its extension, one of .png, " +
              ".pdf, .svg, .eps, .ps, .jpg, .tif (got '" + ext + "')");
}

// draws a figure; a missing matplotlib is reported, not fatal (the trace is already written)
void RunPlotScript(const std::string& script, const std::vector<std::string>& args, bool quiet) {
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

// plot_tap.py's arguments for tap 0 of `run`: its title (what was rendered, with which
// material, on which device), what the impulsive part is, and the tap metrics' spectral figures,
// which the figure states as they are (one definition for the table, the JSON and the figure)
std::vector<std::string> TapFigureArgs(const analysis::TapRun& run, const std::string& what) {
  const Model& m = run.model;
  const std::string material = m.render.material.name;
  const bool event = m.render.renderer == RendererKind::kEvent;
  std::string parts = event ? "event transient" : "impulses (Eq. 9 force)";
  if (!material.empty()) parts += ", material " + material;
  std::vector<std::string> args = {"--title",       what + " on the " + run.device.name + ", tap 0",
                                   "--parts-label", parts,
                                   "--limit",       text::FormatNumber(run.device.max_force_N)};
  if (!run.taps.empty() && std::isfinite(run.taps.front().spectrum_window_s)) {
    const analysis::TapMetrics& t = run.taps.front();
    const double rate_hz = t.transient_repetition_hz;
    args.insert(args.end(),
                {"--window-ms", text::Significant(1e3 * t.spectrum_window_s, 3), "--resolution-hz",
                 text::Significant(t.spectrum_resolution_hz, 3), "--repetition",
                 !std::isfinite(rate_hz) ? "-"
                 : rate_hz == 0.0        ? "none"
                                         : text::Fixed(rate_hz, 1) + " Hz"});
  }
  // a material's renderer: its model Q(t) = A v e^(-B t) sin(2 pi f t) beside the rendered force,
  // at tap 0's impact speed (a fitted material's is the recordings' model)
  if (!material.empty() && !run.taps.empty() && run.taps.front().contact) {
    const Material& mat = m.render.material;
    args.insert(args.end(),
                {"--material-model", material, text::FormatNumber(mat.amplitude_Ns_per_m),
                 text::FormatNumber(mat.decay_per_s), text::FormatNumber(mat.frequency_hz),
                 text::FormatNumber(run.taps.front().approach_speed_mps)});
  }
  return args;
}

std::string OutPath(const TapFlags& f, const std::string& name) {
  return (std::filesystem::path(f.out_dir) / name).string();
}

// a spec's file name: its name with ':' (name:material) made safe for every file system
std::string FileStem(const analysis::RendererSpec& spec) {
  std::string stem = spec.name;
  std::replace(stem.begin(), stem.end(), ':', '_');
  std::replace(stem.begin(), stem.end(), '/', '_');
  return stem;
}

// every file a comparison writes, checked before the runs
void CheckCompareOutputs(const TapFlags& f, const std::vector<analysis::RendererSpec>& specs,
                         const std::string& set) {
  io::CheckOutputDir(f.out_dir, "output folder (--out-dir)");
  std::error_code ec;
  if (!std::filesystem::exists(f.out_dir, ec)) return;
  for (const analysis::RendererSpec& spec : specs) {
    io::CheckOutputPath(OutPath(f, FileStem(spec) + ".csv"), "trace file");
    io::CheckOutputPath(OutPath(f, FileStem(spec) + "_joint.csv"), "joint trace");
    io::CheckOutputPath(OutPath(f, FileStem(spec) + "_tap.png"), "figure");
  }
  io::CheckOutputPath(OutPath(f, set + ".md"), "table");
  io::CheckOutputPath(OutPath(f, set + ".png"), "figure");
}

// --compare-joint-limit on a scene whose wall moves on a limited joint, else it compares nothing
void CheckJointLimits(const analysis::TapRun& run, const std::string& scene) {
  const bool limited = run.wall.moving() && run.wall.joint >= 0 &&
                       run.model.trees[run.wall.tree].joints[run.wall.joint].limited;
  if (!limited) {
    throw Error(
        "--compare-joint-limit: the wall " +
        (run.wall.geom.empty() ? std::string("(a point and normal)") : "'" + run.wall.geom + "'") +
        " of scene file '" + scene +
        "' is not a link moved by a hinge or slide with a range; choose one with "
        "--wall-geom NAME (e.g. panel in scenes/door.xml)");
  }
}

// runs every renderer of `specs` on the same taps; `set` names the table and the figure
// where a comparison wrote its files; each renderer's (a door stop's comparison prefixes them
// with limit_)
void PrintCompareFiles(const std::string& out_dir, const std::string& set,
                       const std::string& table_path, const std::string& fig) {
  const std::string each = out_dir + (set == "joint_limit" ? "/limit_<renderer>" : "/<renderer>");
  std::cout << "\nfull table: " << table_path << "\nfigures: " << fig << " and " << each
            << "_tap.png\ntraces: " << each << ".csv\n";
}

void Compare(const TapFlags& f, const std::vector<analysis::RendererSpec>& specs,
             const std::string& set, bool joint_limit = false) {
  CheckCompareOutputs(f, specs, set);
  std::error_code created;
  std::filesystem::create_directories(f.out_dir, created);
  if (created) {
    throw Error("cannot create the output folder (--out-dir) '" + f.out_dir +
                "': " + created.message());
  }
  std::vector<std::string> traces, labels, joints;
  std::set<std::string> notes;  // a material's conversion note, once however many renderers
  nlohmann::json renderers = nlohmann::json::array();
  std::ostringstream table, compact;
  table << TapTableHeader(TapTable::kFull) << "\n";
  compact << TapTableHeader(TapTable::kCompact) << "\n";
  std::string note, compact_note, joint_rows, non_finite_name;
  std::vector<std::vector<std::string>> figure_args;
  std::string coupling = "direct";
  double max_force_N = 0.0;
  NonFiniteReport non_finite;
  const std::unique_ptr<Progress> progress = StartProgress("tap --" + set, f.quiet);
  for (std::size_t i = 0; i < specs.size(); ++i) {
    const analysis::RendererSpec& spec = specs[i];
    analysis::TapExperimentConfig config = MakeConfig(f, std::nullopt, &spec, joint_limit);
    const double n = static_cast<double>(specs.size());
    config.progress = progress.get();
    config.progress_from = static_cast<double>(i) / n;
    config.progress_to = static_cast<double>(i + 1) / n;
    config.progress_where = "renderer " + std::to_string(i + 1) + " of " +
                            std::to_string(specs.size()) + ", " + spec.label;
    config.progress_kept = i == 0 ? std::string("nothing was written")
                                  : "the traces of the " + std::to_string(i) +
                                        " renderer(s) before it are in " + f.out_dir;
    const analysis::TapRun run = analysis::RunTapExperiment(config);
    if (i == 0) PrintLoadWarnings(run.model);  // the same scene for every renderer: once
    if (notes.insert(run.material_note).second) PrintMaterialNote(run.material_note);
    if (joint_limit) CheckJointLimits(run, f.scene.scene);
    const std::string trace = OutPath(f, FileStem(spec) + ".csv");
    io::WriteTraceCsv(trace, run.trace);
    if (WriteJointCsv(JointPath(trace), run)) joints.push_back(JointPath(trace));
    traces.push_back(trace);
    labels.push_back(spec.label);
    max_force_N = run.device.max_force_N;
    coupling = text::CouplingName(run.model.device.coupling);
    nlohmann::json entry = {{"name", spec.name}, {"label", spec.label}};
    entry.update(RunJson(run, coupling.c_str()));
    entry["trace"] = trace;
    renderers.push_back(entry);
    table << TapTableRow(TapTable::kFull, spec.label, run) << "\n";
    compact << TapTableRow(TapTable::kCompact, spec.label, run) << "\n";
    if (i == 0) note = TapTableNote(TapTable::kFull, run);
    if (i == 0) compact_note = TapTableNote(TapTable::kCompact, run);
    joint_rows += JointTableRow(spec.label, run);
    figure_args.push_back(TapFigureArgs(run, spec.label));
    if (non_finite.count == 0 && NonFinite(run).count > 0) {
      non_finite = NonFinite(run);
      non_finite_name = spec.label;
    }
  }
  progress->Finish();
  const std::string table_path = OutPath(f, set + ".md");
  {
    std::ostringstream out;
    out << f.taps << " taps per renderer at " << f.speed_mps << " m/s on the " << f.device
        << " preset (" << coupling << " coupling, " << f.rate_hz
        << " Hz); each column names its statistic over the taps\n\n"
        << table.str() << "\n"
        << note << "\n";
    if (!joint_rows.empty()) out << "\n" << JointTableHeader() << "\n" << joint_rows;
    io::WriteFileAtomically(table_path, out.str(), "table");
  }
  const std::string fig = OutPath(f, set + ".png");
  std::vector<std::string> args = traces;
  args.push_back("--labels");
  args.insert(args.end(), labels.begin(), labels.end());
  args.insert(args.end(), {"--limit", text::FormatNumber(max_force_N), "--out", fig});
  // the spectral figures as the tap metrics give them (TapFigureArgs: window, resolution and
  // each renderer's repetition after the flag's name)
  for (const char* flag : {"--window-ms", "--resolution-hz"}) {
    const auto at = std::find(figure_args.front().begin(), figure_args.front().end(), flag);
    if (at != figure_args.front().end()) args.insert(args.end(), {flag, *(at + 1)});
  }
  std::vector<std::string> repetitions;
  for (const std::vector<std::string>& a : figure_args) {
    const auto at = std::find(a.begin(), a.end(), "--repetition");
    if (at != a.end()) repetitions.push_back(*(at + 1));
  }
  if (repetitions.size() == figure_args.size()) {
    args.push_back("--repetitions");
    args.insert(args.end(), repetitions.begin(), repetitions.end());
  }
  if (joints.size() == traces.size()) {
    args.push_back("--joints");
    args.insert(args.end(), joints.begin(), joints.end());
  }
  RunPlotScript("python/plot_walls.py", args, f.json);
  std::vector<std::string> figures = {fig};
  for (std::size_t i = 0; i < specs.size(); ++i) {
    const std::string tap_fig = OutPath(f, FileStem(specs[i]) + "_tap.png");
    std::vector<std::string> tap_args = {traces[i], "--out", tap_fig};
    tap_args.insert(tap_args.end(), figure_args[i].begin(), figure_args[i].end());
    if (joints.size() == traces.size()) tap_args.insert(tap_args.end(), {"--joint", joints[i]});
    RunPlotScript("python/plot_tap.py", tap_args, f.json);
    figures.push_back(tap_fig);
  }
  auto check = [&non_finite, &non_finite_name] {
    if (non_finite.count > 0) throw Error(non_finite_name + ": " + NonFiniteMessage(non_finite));
  };
  if (f.json) {
    const nlohmann::json results = {
        {"renderers", renderers}, {"table", table_path}, {"figures", figures}};
    std::cout << results.dump() << "\n";
    check();
    return;
  }
  std::cout << compact.str() << "\n" << compact_note << "\n";
  if (!joint_rows.empty()) std::cout << "\n" << JointTableHeader() << "\n" << joint_rows;
  PrintCompareFiles(f.out_dir, set, table_path, fig);
  check();
}

// --compare-joint-limit LIST: each entry a joint-limit renderer (penalty, impulse, train), the
// contact's renderer the flags' (--renderer, the config, the default)
std::vector<analysis::RendererSpec> JointLimitSpecs(const TapFlags& f) {
  if (f.compare_walls || !f.compare.empty() || f.wall) {
    throw Error("give either --compare-joint-limit or --compare/--compare-walls/--wall, not both");
  }
  if (f.scene.joint_limit_renderer) {
    throw Error("give either --joint-limit-renderer or --compare-joint-limit, not both");
  }
  if (!f.trace.empty() || !f.plot.empty()) {
    throw Error(
        "--trace and --plot are for one renderer; a comparison writes its traces and "
        "figures to --out-dir");
  }
  std::vector<analysis::RendererSpec> specs;
  try {
    specs = analysis::ParseRendererList(f.compare_joint_limit);
  } catch (const Error& e) {
    throw Error(std::string("--compare-joint-limit: ") + e.what());
  }
  for (analysis::RendererSpec& spec : specs) {
    const RendererKind k = spec.renderer;
    if (spec.render || spec.material || k == RendererKind::kEvent) {
      throw Error("--compare-joint-limit: '" + spec.name +
                  "' is not a joint-limit renderer; valid: penalty, impulse, train");
    }
    spec.label = "limit: " + spec.label;
    spec.name = "limit_" + spec.name;
  }
  return specs;
}

void RunTap(const TapFlags& f) {
  if (!f.compare_joint_limit.empty()) {
    const std::vector<analysis::RendererSpec> specs = JointLimitSpecs(f);
    // a parameter is used when the contact's renderer or one of the limit's takes it
    const Settings settings = ResolveSettings(f.scene);
    std::vector<RendererKind> renderers = {settings.load.render.renderer};
    for (const analysis::RendererSpec& spec : specs) renderers.push_back(spec.renderer);
    RefuseUnusedRender(settings, renderers);
    Compare(f, specs, "joint_limit", /*joint_limit=*/true);
    return;
  }
  if (f.compare_walls || !f.compare.empty()) {
    if (f.wall) throw Error("give either --wall or --compare/--compare-walls, not both");
    if (f.scene.renderer) {
      throw Error("give either --renderer or --compare/--compare-walls, not both");
    }
    if (f.compare_walls && !f.compare.empty()) {
      throw Error("give either --compare or --compare-walls (the set " +
                  std::string(analysis::kWallsSet) + "), not both");
    }
    if (!f.trace.empty() || !f.plot.empty()) {
      throw Error(
          "--trace and --plot are for one renderer; a comparison writes its traces and "
          "figures to --out-dir");
    }
    const std::vector<analysis::RendererSpec> specs =
        analysis::ParseRendererList(f.compare_walls ? analysis::kWallsSet : f.compare);
    // refused before the first run, not when its wall comes
    std::vector<RendererKind> renderers;
    for (const analysis::RendererSpec& spec : specs) {
      if (spec.render) RefuseUnused(ResolveSettings(f.scene), kWallFixedFields, kWallFixedWhy);
      renderers.push_back(spec.renderer);
    }
    // a parameter is used when one renderer of the list takes it
    RefuseUnusedRender(ResolveSettings(f.scene), renderers);
    Compare(f, specs, f.compare_walls ? "walls" : "compare");
    return;
  }
  if (f.wall && f.scene.renderer) throw Error("give either --wall or --renderer, not both");
  if (f.out_dir_given) {
    throw Error(
        "--out-dir is the output folder of --compare and --compare-walls; one renderer "
        "writes where --trace and --plot say");
  }
  std::string trace = f.trace;
  bool temporary = false;
  if (trace.empty() && !f.plot.empty()) {
    trace = f.plot + ".trace.csv";
    temporary = true;
  }
  // a bad output path fails now, not after the run; the figure first, so a missing folder is
  // blamed on the path the user wrote, not on the temporary trace beside it
  if (!f.plot.empty()) {
    CheckFigureFormat(f.plot);
    io::CheckOutputPath(f.plot, "figure");
  }
  if (!trace.empty()) io::CheckOutputPath(trace, "trace file");
  const std::unique_ptr<Progress> progress = StartProgress("tap", f.quiet);
  analysis::TapExperimentConfig config = MakeConfig(f, f.wall);
  config.progress = progress.get();
  config.progress_where = std::to_string(f.taps) + " taps";
  config.progress_kept = "nothing was written";
  const analysis::TapRun run = analysis::RunTapExperiment(config);
  progress->Finish();
  PrintLoadWarnings(run.model);
  PrintMaterialNote(run.material_note);
  if (!trace.empty()) io::WriteTraceCsv(trace, run.trace);
  const bool joint = !trace.empty() && WriteJointCsv(JointPath(trace), run);
  if (!f.plot.empty()) {
    // the temporary trace goes whether or not the figure could be drawn
    std::error_code ignored;
    try {
      std::string what = text::RendererName(run.model.render.renderer);
      if (!run.model.render.material.name.empty()) what += ": " + run.model.render.material.name;
      std::vector<std::string> tap_args = {trace, "--out", f.plot};
      const std::vector<std::string> more = TapFigureArgs(run, what);
      tap_args.insert(tap_args.end(), more.begin(), more.end());
      if (joint) tap_args.insert(tap_args.end(), {"--joint", JointPath(trace)});
      RunPlotScript("python/plot_tap.py", tap_args, f.json);
    } catch (...) {
      if (temporary) std::filesystem::remove(trace, ignored);
      if (temporary && joint) std::filesystem::remove(JointPath(trace), ignored);
      throw;
    }
    if (temporary) std::filesystem::remove(trace, ignored);
    if (temporary && joint) std::filesystem::remove(JointPath(trace), ignored);
  }
  nlohmann::json result = RunJson(run, text::CouplingName(run.model.device.coupling));
  if (!f.trace.empty()) result["trace"] = f.trace;
  if (f.json) {
    std::cout << result.dump() << "\n";
    ThrowIfNonFinite(NonFinite(run));
    return;
  }
  std::cout << TapTableHeader(TapTable::kCompact) << "\n"
            << TapTableRow(TapTable::kCompact, result["renderer"].get<std::string>(), run) << "\n\n"
            << TapTableNote(TapTable::kCompact, run) << "\n";
  if (const std::string rows = JointTableRow(result["renderer"].get<std::string>(), run);
      !rows.empty()) {
    std::cout << "\n" << JointTableHeader() << "\n" << rows << "\n";
  }
  std::cout << "Every figure per tap: --json.\n";
  PrintWarnings(result["warnings"], std::cerr);
  if (!result["displayable"].get<bool>()) {
    std::cout << "note: the rendered stiffness or damping is above what the " << run.device.name
              << " can display (its max_stiffness_N_per_m, max_damping_Ns_per_m); the simulated "
                 "device renders it, serve would refuse it\n";
  }
  ThrowIfNonFinite(NonFinite(run));
}

// tap's options, on the subcommand or on RunTapFlags' own parser (one definition for both)
std::shared_ptr<TapFlags> AddTapOptions(CLI::App* app) {
  auto f = std::make_shared<TapFlags>();
  AddSceneFlags(app, f->scene, /*scene_required=*/false);
  AddThreadsFlag(app, f->scene);
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
  app->add_option("--speed", f->speed_mps, "approach speed [m/s], in (0, 2]")
      ->capture_default_str();
  app->add_option("--spread", f->spread, "relative random spread of the speed (seeded)");
  app->add_option("--taps", f->taps, "number of taps")->capture_default_str();
  app->add_option("--seed", f->seed, "random seed, 0 to 2^64 - 1")
      ->capture_default_str()
      ->transform(SeedRange());
  app->add_option("--trace", f->trace, "write the trace CSV here");
  app->add_option(
      "--plot", f->plot,
      "draw tap 0 to this PNG: displayed force against the device limit, requested force and its "
      "parts, penetration, velocity, spectra");
  app->add_flag("--compare-walls", f->compare_walls,
                "run penalty and walls 0, 1, 2; write traces, a table and figures to --out-dir");
  app->add_option("--compare", f->compare,
                  "run these renderers side by side, comma-separated: penalty, impulse, train "
                  "(with the flags' parameters), wall0, wall1, wall2 (the method's walls), "
                  "event:MATERIAL and train:MATERIAL (e.g. penalty,train,event:wood,train:wood); "
                  "writes traces, compare.md and figures to --out-dir");
  app->add_option("--compare-joint-limit", f->compare_joint_limit,
                  "render the joint limits (a door's stop) each of these ways side by side, "
                  "comma-separated: penalty, impulse, train (e, t_c and f from the flags); the "
                  "contact keeps --renderer; writes traces, joint_limit.md and figures to "
                  "--out-dir");
  app->add_option("--out-dir", f->out_dir,
                  "output folder of --compare, --compare-walls and --compare-joint-limit")
      ->capture_default_str();
  app->add_flag("--json", f->json, "print one JSON object");
  return f;
}

void RegisterTap(CLI::App& root) {
  CLI::App* app = root.add_subcommand(
      "tap", "tap a wall with the simulated hand and device; metrics, trace and figures");
  auto f = AddTapOptions(app);
  AddQuietFlag(*app, f->quiet);
  // an error about a parameter the user wrote says where it was written
  app->callback([f, app] {
    f->out_dir_given = app->get_option("--out-dir")->count() > 0;
    WithOrigins(ResolveSettings(f->scene), [&] { RunTap(*f); });
  });
}

const CommandRegistrar tap_registrar("tap", &RegisterTap);

}  // namespace

namespace {

// tap's flags parsed from `args`, for the in-process runs below
std::shared_ptr<TapFlags> ParseTapFlags(const std::vector<std::string>& args) {
  CLI::App app{"rigidtouch tap"};
  auto f = AddTapOptions(&app);
  std::vector<std::string> reversed(args.rbegin(), args.rend());  // CLI11 parses from the back
  try {
    app.parse(reversed);
  } catch (const CLI::ParseError& e) {
    throw Error(std::string("tap: ") + e.what());
  }
  f->out_dir_given = app.get_option("--out-dir")->count() > 0;
  if (f->compare_walls || !f->compare.empty() || !f->compare_joint_limit.empty() ||
      f->out_dir_given || !f->trace.empty() || !f->plot.empty() || f->json) {
    throw Error(
        "tap: --compare, --compare-walls, --compare-joint-limit, --out-dir, --trace, --plot and "
        "--json write files or print; here the run is returned instead");
  }
  if (f->wall && f->scene.renderer) throw Error("give either --wall or --renderer, not both");
  return f;
}

}  // namespace

TapOutcome RunTapFlags(const std::vector<std::string>& args) {
  const auto f = ParseTapFlags(args);
  return WithOrigins(ResolveSettings(f->scene), [&] {
    TapOutcome out;
    out.run = analysis::RunTapExperiment(MakeConfig(*f, f->wall));
    out.result = RunJson(out.run, text::CouplingName(out.run.model.device.coupling));
    return out;
  });
}

std::vector<std::string> TapFlagNames() {
  CLI::App app{"rigidtouch tap"};
  AddTapOptions(&app);
  std::vector<std::string> names;
  for (const CLI::Option* option : app.get_options()) {
    for (const std::string& name : option->get_lnames()) names.push_back(name);
  }
  return names;
}

analysis::TapSetup PrepareTapFlags(const std::vector<std::string>& args) {
  const auto f = ParseTapFlags(args);
  return WithOrigins(ResolveSettings(f->scene),
                     [&] { return analysis::PrepareTap(MakeConfig(*f, f->wall)); });
}

}  // namespace rigidtouch::cli
