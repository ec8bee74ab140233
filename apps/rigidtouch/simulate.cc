// `rigidtouch simulate`: run a scene offline with a constant user force on the tool.
#include <algorithm>
#include <iostream>
#include <limits>

#include "base/text.h"
#include "command.h"
#include "io/config.h"
#include "loop/loop_json.h"
#include "scene_flags.h"
#include "simulate_nonfinite.h"

namespace rigidtouch::cli {
namespace {

struct SimulateFlags {
  SceneFlags scene;
  long steps = 1000;
  std::vector<double> tool_force{0.0, 0.0, 0.0};
  bool json = false;
};

void RunSimulate(const SimulateFlags& f) {
  if (f.steps < 0) throw Error("--steps must be >= 0, got " + std::to_string(f.steps));
  const Vec3 tool_force = ToolForce(f.tool_force);
  const Settings settings = ResolveSettings(f.scene);
  RefuseUnusedRender(settings, {settings.load.render.renderer});
  RefuseDeviceSettings(settings, "simulate");
  const Model model = LoadModel(f.scene.scene, settings.load);
  if (!model.has_tool && !tool_force.isZero(0.0)) {
    throw Error("--tool-force needs a tool; the scene is loaded with --tool none");
  }
  PrintLoadWarnings(model);
  Data data = MakeData(model);
  TickInput input;
  input.tool_wrench.force_N = tool_force;
  nlohmann::json impulses = nlohmann::json::array();
  int max_contacts = 0;
  const WarningStat& non_finite = data.warnings[static_cast<int>(Warning::kNonFiniteState)];
  NonFiniteReport report;
  for (long s = 0; s < f.steps; ++s) {
    Tick(model, data, input);
    max_contacts = std::max(max_contacts, data.ncontact);
    if (non_finite.count > 0 && report.count == 0) {
      report.step = non_finite.last_step;
      report.time_s = data.time_s;
    }
    report.count = non_finite.count;
    for (int k = 0; k < data.nimpulse; ++k) {
      const ImpulseEvent& e = data.impulses[k];
      impulses.push_back({{"step", e.step},
                          {"time_s", e.time_s},
                          {"index", e.index},
                          {"total", e.total},
                          {"contacts", e.contacts},
                          {"tool", e.tool},
                          {"kinetic_energy_before_J", e.kinetic_energy_before_J},
                          {"kinetic_energy_after_J", e.kinetic_energy_after_J},
                          {"impulse_norm_Ns", e.impulse_norm_Ns}});
    }
  }
  nlohmann::json bodies = nlohmann::json::array();
  for (std::size_t i = 0; i < model.bodies.size(); ++i) {
    if (!model.has_tool && static_cast<int>(i) == model.tool) continue;  // the placeholder
    const BodyState& s = data.bodies[i];
    bodies.push_back({{"name", model.bodies[i].name},
                      {"position_m", Json(s.x_W)},
                      {"velocity_mps", Json(s.v_W)},
                      {"angular_velocity_radps", Json(s.w_W)}});
  }
  const nlohmann::json result = {{"scene", model.source},
                                 {"steps", f.steps},
                                 {"timestep_s", model.timestep_s},
                                 {"time_s", data.time_s},
                                 {"renderer", text::RendererName(model.render.renderer)},
                                 {"schedule",
                                  {{"window_steps", model.schedule.window_steps},
                                   {"interval_steps", model.schedule.interval_steps},
                                   {"impulses", model.schedule.impulses}}},
                                 {"bodies", bodies},
                                 {"joints", loop::JointsJson(model, data)},
                                 {"impulses", impulses},
                                 {"max_contacts", max_contacts},
                                 {"warnings", WarningsJson(data)},
                                 {"non_finite_state", NonFiniteJson(report)}};
  if (f.json) {
    std::cout << result.dump() << "\n";
    ThrowIfNonFinite(report);
    return;
  }
  // for people: positions to the micrometre, velocities to 0.1 mm/s (and the same in rad for
  // angles), never "-0"; the JSON keeps every digit
  const auto numbers = [](const auto& values, int decimals) {
    std::string out;
    for (const auto& v : values) {
      // two appends, not a temporary from " " + string: GCC 12 (-Wrestrict, PR 105329) warns
      // falsely on that one when it inlines it
      if (!out.empty()) out += ' ';
      out += text::Fixed(static_cast<double>(v), decimals);
    }
    return out;
  };
  const auto vec = [](const Vec3& v) { return std::vector<double>{v.x(), v.y(), v.z()}; };
  // a hinge's or slide's value is a number, a ball's or free joint's an array
  const auto list = [](const nlohmann::json& j) {
    return j.is_array() ? j.get<std::vector<double>>() : std::vector<double>{j.get<double>()};
  };
  std::cout << "simulated " << f.steps << " steps of " << text::FormatNumber(model.timestep_s)
            << " s (" << text::FormatNumber(data.time_s) << " s) of " << model.source
            << " with the " << text::RendererName(model.render.renderer) << " renderer\n";
  std::cout << "impulses applied: " << impulses.size()
            << ", most contacts in a step: " << max_contacts << "\n";
  for (std::size_t i = 0; i < model.bodies.size(); ++i) {
    if (!model.has_tool && static_cast<int>(i) == model.tool) continue;
    const BodyState& s = data.bodies[i];
    std::cout << "  " << model.bodies[i].name << ": position " << numbers(vec(s.x_W), 6)
              << " m, velocity " << numbers(vec(s.v_W), 4) << " m/s\n";
  }
  for (const nlohmann::json& j : result["joints"]) {
    std::cout << "  joint " << j["name"].get<std::string>() << " (" << j["type"].get<std::string>()
              << "): position " << numbers(list(j["position"]), 6) << ", velocity "
              << numbers(list(j["velocity"]), 4)
              << (j["at_limit"].get<bool>() ? ", at its limit" : "") << "\n";
  }
  PrintWarnings(result["warnings"], std::cerr);
  ThrowIfNonFinite(report);
}

void RegisterSimulate(CLI::App& root) {
  auto flags = std::make_shared<SimulateFlags>();
  CLI::App* app = root.add_subcommand("simulate", "run a scene offline with a constant tool force");
  AddSceneFlags(app, flags->scene);
  AddThreadsFlag(app, flags->scene);
  app->add_option("--steps", flags->steps, "number of steps")->capture_default_str();
  app->add_option("--tool-force", flags->tool_force, "constant force on the tool FX FY FZ [N]")
      ->expected(3);
  app->add_flag("--json", flags->json, "print one JSON object");
  // an error about a parameter the user wrote says where it was written
  app->callback(
      [flags] { WithOrigins(ResolveSettings(flags->scene), [&] { RunSimulate(*flags); }); });
}

const CommandRegistrar simulate_registrar("simulate", &RegisterSimulate);

}  // namespace
}  // namespace rigidtouch::cli
