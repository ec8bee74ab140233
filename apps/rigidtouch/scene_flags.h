// Flags shared by the subcommands that load a scene: tool, time step, renderer, contact law.
#pragma once

#include <CLI/CLI.hpp>
#include <array>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "analysis/tap_experiment.h"
#include "device/device_spec.h"
#include "device/presets.h"
#include "io/device_record.h"
#include "loop/trace_queue.h"
#include "rigidtouch/rigidtouch.h"

namespace rigidtouch::cli {

/// Values of the scene flags as parsed; unset optionals keep the config file's or the default.
struct SceneFlags {
  std::string scene;
  std::string config;
  std::optional<std::string> tool;
  std::optional<double> timestep_s;
  std::optional<std::string> renderer;
  std::optional<std::string> joint_limit_renderer;
  std::optional<double> restitution;
  std::optional<double> t_collision_s;
  std::optional<double> frequency_hz;
  std::optional<double> stiffness_N_per_m;
  std::optional<double> damping_Ns_per_m;
  bool reference_solver = false;
  bool passivity_control = false;
  std::optional<std::string> material;
  std::optional<int> threads;  // --threads (AddThreadsFlag)
};

/// How a setting is resolved, stated in every subcommand's --help and in docs/config.md.
extern const char kPrecedence[];

/// A CLI11 check that a number lies in [lo, hi] (hi may be infinity), with the message every
/// subcommand gives: "VALUE is out of range: valid LO to HI UNIT".
CLI::Validator InRange(double lo, double hi, const std::string& unit);

/// A CLI11 transform for --seed: a whole number from 0 to 2^64 - 1 written in decimal, refused
/// otherwise with "VALUE is out of range: valid 0 to 18446744073709551615" (or "is not a whole
/// number: ..."). CLI11 alone wraps -1 to 2^64 - 1, saturates a larger number and reads 0x10 as
/// hexadecimal and 010 as octal; the value is passed on in plain decimal.
CLI::Validator SeedRange();

/// The constant tool force of --tool-force FX FY FZ (simulate, bench); refused unless finite.
Vec3 ToolForce(const std::vector<double>& xyz);

/// Adds --rate with the one range every subcommand takes (limits::kMinRate_hz to kMaxRate_hz).
void AddRateFlag(CLI::App* app, double& rate_hz, const std::string& description);

/// Adds --scene (required unless `scene_required` is false), --config, --tool, --timestep,
/// --renderer, --joint-limit-renderer, --restitution, --t-collision, --frequency, --stiffness,
/// --damping, --reference-solver.
void AddSceneFlags(CLI::App* app, SceneFlags& flags, bool scene_required = true);

/// Adds --threads N (1 or 2): the threads that step the scene (LoadOptions::threads).
void AddThreadsFlag(CLI::App* app, SceneFlags& flags);

/// The load options a user asked for: the defaults, then the config file's fields, then the
/// flags (flag > config > default; a device preset, where one applies, comes between the config
/// and the default: ApplyDevicePreset). `origin` names where each value the user wrote came from,
/// by field path ("contact.stiffness_N_per_m" -> "--stiffness" or "k.json").
struct Settings {
  LoadOptions load;
  std::optional<std::string> connect;  // the config file's device.connect (serve's --connect)
  std::map<std::string, std::string> origin;
  bool Given(const std::string& field) const { return origin.count(field) != 0; }
};
Settings ResolveSettings(const SceneFlags& flags);

/// Where the user did not write them, the tool contact's stiffness and damping and the force
/// limit come from the device preset: the preset's maximum stiffness, damping k h capped at the
/// preset's, the preset's force. A force limit the user wrote above the preset's is refused (the
/// device cannot display it), naming where it was written; a lower one is used. In tap and serve
/// the time step is the haptic period: a timestep_s the user wrote that differs from 1 / rate is
/// refused.
void ApplyDevicePreset(Settings& settings, const DeviceLimits& preset, double rate_hz);

/// Refuses any of `fields` the user wrote: they have no effect here, for the reason `why`.
void RefuseUnused(const Settings& settings, const std::vector<std::string>& fields,
                  const std::string& why);

/// Refuses the renderer parameters the user wrote that none of `renderers` (the renderers a run
/// uses) takes, naming where each was written and the renderers that take it: restitution
/// (impulse, and train, whose e must be 0), t_collision_s and frequency_hz (train),
/// reference_solver when on (impulse, train). A reference solver written as off asks for nothing
/// and is not refused. A material train's f and t_c are refused by ResolveSettings.
void RefuseUnusedRender(const Settings& settings, const std::vector<RendererKind>& renderers);

/// Refuses the device settings the user wrote in a subcommand that has no device (`command`:
/// simulate, bench; the tool is pushed by the constant --tool-force): the force limit, the
/// virtual coupling's spring and damper, and a coupling other than none.
void RefuseDeviceSettings(const Settings& settings, const std::string& command);

/// Runs `load` (which loads or configures a model); an Error about a parameter the user wrote
/// gets where it was written appended ("(set by --stiffness)", "(set in k.json as
/// contact.stiffness_N_per_m)").
template <typename F>
auto WithOrigins(const Settings& settings, F load) -> decltype(load());
std::string OriginNote(const Settings& settings, const std::string& message);

/// The warnings of a run as a JSON object {name: count}, only those that occurred.
nlohmann::json WarningsJson(const std::array<WarningStat, static_cast<int>(Warning::kCount)>& w);
inline nlohmann::json WarningsJson(const Data& data) {
  return WarningsJson(data.warnings);
}

/// Prints a WarningsJson object as "warning: NAME xCOUNT" lines.
void PrintWarnings(const nlohmann::json& warnings, std::ostream& out);

/// Prints the model's load warnings as "rigidtouch: warning: ..." lines to stderr.
void PrintLoadWarnings(const Model& model);

/// Prints a material's conversion note (io::RenderMaterialOnDevice: an acceleration material
/// rendered on a device with another effective mass than its fit's) as one
/// "rigidtouch: note: ..." line to stderr; nothing for an empty note.
void PrintMaterialNote(const std::string& note);

/// The tap experiment on the scene flags' scene (the shipped wall when none is given) with the
/// resolved settings (ApplyDevicePreset for the device `device_preset`, a preset or a JSON
/// device spec, at `rate_hz`), approach speed and taps.
analysis::TapExperimentConfig TapConfig(const SceneFlags& flags, const std::string& device_preset,
                                        double rate_hz, double speed_mps, int taps);

/// The device a subcommand renders for, from --device NAME|FILE.json (its spec: a preset or a
/// JSON device spec, device::ParseDeviceSpec) and, where a device is reached, --connect
/// sim|udp://HOST:PORT (how). The old spellings of serve and study run, --device sim|udp://...
/// with --preset NAME, are read the same way: no preset or spec file is called sim or starts
/// with udp://, so the two forms cannot be confused (docs/decisions.md, "One --device").
/// `connect` is empty when neither spelling gave a connection.
struct DeviceChoice {
  device::DeviceSpec spec;
  std::string spec_text;  // what the user gave (or the default): a preset name or a file
  std::string connect;
};
DeviceChoice ResolveDevice(const std::optional<std::string>& device,
                           const std::optional<std::string>& connect,
                           const std::optional<std::string>& preset);

/// Whether `text` is a connection (sim or udp://...) rather than a device spec.
bool IsConnection(const std::string& text);

/// `--record LOG` of serve and view: the record file and the queue its writer thread drains (the
/// haptic loop only pushes a copy of each tick and never blocks). Both null without a path.
struct RecordOutput {
  std::unique_ptr<io::RecordFileWriter> file;
  std::unique_ptr<loop::RecordQueue> queue;
};
RecordOutput OpenRecord(const std::string& path, double rate_hz);

/// Closes the queue (rethrowing a failed write: exit status 4) and keeps the file only when no
/// tick was dropped, since a record with a gap cannot be replayed tick for tick. The queue's
/// counts as JSON.
nlohmann::json FinishRecord(RecordOutput& record, const std::string& path);

/// JSON array of a Vec3.
inline nlohmann::json Json(const Vec3& v) {
  return nlohmann::json::array({v.x(), v.y(), v.z()});
}

template <typename F>
auto WithOrigins(const Settings& settings, F load) -> decltype(load()) {
  try {
    return load();
  } catch (const Error& e) {
    const std::string note = OriginNote(settings, e.what());
    if (note.empty()) throw;
    throw Error(std::string(e.what()) + note);
  }
}

}  // namespace rigidtouch::cli
