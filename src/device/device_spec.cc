#include "device/device_spec.h"

#include <cmath>
#include <filesystem>
#include <sstream>

#include "base/text.h"
#include "device/presets.h"
#include "io/strict_json.h"
#include "rigidtouch/types.h"

namespace rigidtouch::device {
namespace {

bool EndsWith(std::string_view text, std::string_view tail) {
  return text.size() >= tail.size() && text.substr(text.size() - tail.size()) == tail;
}

// a required number in [lo, hi] (closed), naming the field and its unit when it is not
double RequiredSpecNumber(const io::StrictObject& o, const std::string& key, double lo, double hi,
                          const std::string& unit) {
  const std::optional<double> value = o.Number(key);
  if (!value) o.FailAt(key, "missing; a device spec gives every field (" + unit + ")");
  if (!(*value >= lo && *value <= hi)) {
    o.FailAt(key, text::FormatNumber(*value) + " is out of range: valid " + text::FormatNumber(lo) +
                      " to " + text::FormatNumber(hi) + " " + unit);
  }
  return *value;
}

}  // namespace

double EffectiveMassKg(const DeviceModelParams& model, const HandParams& hand) {
  return model.apparent_mass_kg + hand.mass_kg;
}

DeviceSpec PresetSpec(std::string_view name) {
  DeviceSpec spec;
  spec.limits = FindPreset(name);
  if (spec.limits.name == "ideal") {
    // the method without a device in the way: no force limit (in the table), an encoder 55 times
    // finer than the Touch's, no delay
    spec.model.encoder_resolution_m = 1e-6;
    spec.model.delay_ticks = 0;
  }
  return spec;
}

DeviceSpec ReadDeviceSpec(const std::string& path) {
  const nlohmann::json doc = io::ReadJsonFile(path, "device spec");
  const io::JsonSource source(path);
  const io::StrictObject o(
      source, doc, "",
      {"name", "max_force_N", "max_stiffness_N_per_m", "max_damping_Ns_per_m", "apparent_mass_kg",
       "encoder_resolution_m", "velocity_filter_hz", "delay_ticks", "max_torque_Nm"},
      "a device spec");
  DeviceSpec spec;
  spec.file = path;
  spec.limits.name = o.String("name").value_or(std::filesystem::path(path).stem().string());
  if (spec.limits.name.empty()) o.FailAt("name", "must not be empty");
  // the same ranges the simulated device checks, so a spec that loads also runs
  spec.limits.max_force_N = RequiredSpecNumber(o, "max_force_N", 0.0, 1e4, "N (0: no limit)");
  spec.limits.max_stiffness_N_per_m =
      RequiredSpecNumber(o, "max_stiffness_N_per_m", 0.0, 1e7, "N/m (0: unknown)");
  spec.limits.max_damping_Ns_per_m =
      RequiredSpecNumber(o, "max_damping_Ns_per_m", 0.0, 1e5, "N s/m (0: unknown)");
  // optional: a 3-DoF force device (0, the default) gets no torque
  spec.limits.max_torque_Nm = o.Has("max_torque_Nm") ? RequiredSpecNumber(o, "max_torque_Nm", 0.0,
                                                                          1e3, "N m (0: no torque)")
                                                     : 0.0;
  spec.model.apparent_mass_kg = RequiredSpecNumber(o, "apparent_mass_kg", 0.0, 100.0, "kg");
  spec.model.encoder_resolution_m =
      RequiredSpecNumber(o, "encoder_resolution_m", 0.0, 0.01, "m (0: no quantization)");
  spec.model.velocity_cutoff_hz = RequiredSpecNumber(o, "velocity_filter_hz", 1e-3, 1e5, "Hz");
  if (!o.Has("delay_ticks")) o.FailAt("delay_ticks", "missing; a device spec gives every field");
  spec.model.delay_ticks = o.Integer("delay_ticks", 0, 0, 1);
  return spec;
}

DeviceSpec ParseDeviceSpec(std::string_view text) {
  for (const DeviceLimits& preset : Presets()) {
    if (preset.name == text) return PresetSpec(text);
  }
  if (EndsWith(text, ".json")) return ReadDeviceSpec(std::string(text));
  std::string presets;
  for (const DeviceLimits& preset : Presets()) presets += preset.name + ", ";
  throw Error("unknown device '" + std::string(text) + "'; valid devices: the presets " + presets +
              "or a JSON device spec FILE.json (docs/devices.md)");
}

std::string DeviceSpecHelp() {
  std::string help;
  for (const DeviceLimits& preset : Presets()) help += preset.name + " | ";
  return help + "FILE.json";
}

}  // namespace rigidtouch::device
