#include "scene_flags.h"

#include <cmath>

#include "io/config.h"
#include "io/resources.h"

namespace rigidtouch::cli {

void AddSceneFlags(CLI::App* app, SceneFlags& f, bool scene_required) {
  auto* scene = app->add_option("--scene", f.scene, "MJCF scene file");
  if (scene_required) scene->required();
  app->add_option("--config", f.config, "JSON file with rigidtouch parameters (contact, render)");
  app->add_option("--tool", f.tool, "name of the free body that is the tool")
      ->capture_default_str();
  app->add_option("--timestep", f.timestep_s, "time step h [s] (default: the MJCF option)");
  app->add_option("--renderer", f.renderer, "penalty | impulse | train")
      ->check(CLI::IsMember({"penalty", "impulse", "train"}));
  app->add_option("--restitution", f.restitution, "restitution e in [0, 1] (impulse renderer)");
  app->add_option("--t-collision", f.t_collision_s, "collision window t_c [s], at most 0.1");
  app->add_option("--frequency", f.frequency_hz, "impulse-train frequency f [Hz]");
  app->add_option("--stiffness", f.stiffness_N_per_m, "tool contact stiffness k [N/m]");
  app->add_option("--damping", f.damping_Ns_per_m, "tool contact damping b [N s/m]");
  app->add_flag("--reference-solver", f.reference_solver,
                "use the exact pseudo-inverse of Eq. 5/8 (may pull; allocates)");
}

LoadOptions ToLoadOptions(const SceneFlags& f) {
  LoadOptions o;
  if (!f.config.empty()) io::ApplyConfigFile(f.config, o);
  o.tool_name = f.tool;
  if (f.timestep_s) o.timestep_s = *f.timestep_s;
  if (f.renderer) o.render.renderer = io::ParseRenderer(*f.renderer);
  if (f.restitution) o.render.restitution = *f.restitution;
  if (f.t_collision_s) o.render.t_collision_s = *f.t_collision_s;
  if (f.frequency_hz) o.render.frequency_hz = *f.frequency_hz;
  if (f.stiffness_N_per_m) o.contact.stiffness_N_per_m = *f.stiffness_N_per_m;
  if (f.damping_Ns_per_m) o.contact.damping_Ns_per_m = *f.damping_Ns_per_m;
  if (f.reference_solver) o.render.reference_solver = true;
  return o;
}

ContactOverrides ExplicitContact(const SceneFlags& f) {
  ContactOverrides o{f.stiffness_N_per_m, f.damping_Ns_per_m};
  if (!f.config.empty() && (!o.stiffness_N_per_m || !o.damping_Ns_per_m)) {
    // the config reader leaves absent fields as they are, so NaN marks "not in the file"
    LoadOptions probe;
    probe.contact.stiffness_N_per_m = NAN;
    probe.contact.damping_Ns_per_m = NAN;
    io::ApplyConfigFile(f.config, probe);
    if (!o.stiffness_N_per_m && !std::isnan(probe.contact.stiffness_N_per_m)) {
      o.stiffness_N_per_m = probe.contact.stiffness_N_per_m;
    }
    if (!o.damping_Ns_per_m && !std::isnan(probe.contact.damping_Ns_per_m)) {
      o.damping_Ns_per_m = probe.contact.damping_Ns_per_m;
    }
  }
  return o;
}

nlohmann::json WarningsJson(const std::array<WarningStat, static_cast<int>(Warning::kCount)>& w) {
  nlohmann::json j = nlohmann::json::object();
  for (int k = 0; k < static_cast<int>(Warning::kCount); ++k) {
    if (w[k].count > 0) j[WarningName(static_cast<Warning>(k))] = w[k].count;
  }
  return j;
}

void PrintWarnings(const nlohmann::json& warnings, std::ostream& out) {
  for (const auto& [name, count] : warnings.items()) {
    out << "warning: " << name << " x" << count << "\n";
  }
}

analysis::TapExperimentConfig TapConfig(const SceneFlags& f, const std::string& device_preset,
                                        double rate_hz, double speed_mps, int taps) {
  analysis::TapExperimentConfig c;
  c.scene_path = f.scene.empty() ? io::ShippedFile("scenes/wall.xml") : f.scene;
  c.load = ToLoadOptions(f);
  c.device_preset = device_preset;
  c.rate_hz = rate_hz;
  c.stiffness_N_per_m = f.stiffness_N_per_m;
  c.damping_Ns_per_m = f.damping_Ns_per_m;
  c.script.approach_speed_mps = speed_mps;
  c.script.taps = taps;
  return c;
}

}  // namespace rigidtouch::cli
