// Flags shared by the subcommands that load a scene: tool, time step, renderer, contact law.
#pragma once

#include <CLI/CLI.hpp>
#include <array>
#include <nlohmann/json.hpp>
#include <optional>
#include <ostream>
#include <string>

#include "analysis/tap_experiment.h"
#include "rigidtouch/rigidtouch.h"

namespace rigidtouch::cli {

/// Values of the scene flags as parsed; unset optionals keep the config file's or the default.
struct SceneFlags {
  std::string scene;
  std::string config;
  std::string tool = "tool";
  std::optional<double> timestep_s;
  std::optional<std::string> renderer;
  std::optional<double> restitution;
  std::optional<double> t_collision_s;
  std::optional<double> frequency_hz;
  std::optional<double> stiffness_N_per_m;
  std::optional<double> damping_Ns_per_m;
  bool reference_solver = false;
};

/// Adds --scene (required unless `scene_required` is false), --config, --tool, --timestep,
/// --renderer, --restitution, --t-collision, --frequency, --stiffness, --damping,
/// --reference-solver.
void AddSceneFlags(CLI::App* app, SceneFlags& flags, bool scene_required = true);

/// Load options from the config file (if any) overridden by the flags.
LoadOptions ToLoadOptions(const SceneFlags& flags);

/// The tool contact's stiffness and damping the user set, by flag or else in the config file;
/// unset where neither gives one (a caller may then default them to what a device can display).
struct ContactOverrides {
  std::optional<double> stiffness_N_per_m;
  std::optional<double> damping_Ns_per_m;
};
ContactOverrides ExplicitContact(const SceneFlags& flags);

/// The warnings of a run as a JSON object {name: count}, only those that occurred.
nlohmann::json WarningsJson(const std::array<WarningStat, static_cast<int>(Warning::kCount)>& w);
inline nlohmann::json WarningsJson(const Data& data) {
  return WarningsJson(data.warnings);
}

/// Prints a WarningsJson object as "warning: NAME xCOUNT" lines.
void PrintWarnings(const nlohmann::json& warnings, std::ostream& out);

/// The tap experiment on the scene flags' scene (the shipped wall when none is given), load
/// options and contact overrides, with the device preset, haptic rate, approach speed and taps.
analysis::TapExperimentConfig TapConfig(const SceneFlags& flags, const std::string& device_preset,
                                        double rate_hz, double speed_mps, int taps);

/// JSON array of a Vec3.
inline nlohmann::json Json(const Vec3& v) {
  return nlohmann::json::array({v.x(), v.y(), v.z()});
}

}  // namespace rigidtouch::cli
