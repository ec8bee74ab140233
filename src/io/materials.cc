#include "io/materials.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>

#include "base/limits.h"
#include "base/text.h"
#include "io/strict_json.h"

namespace rigidtouch::io {
namespace {

// assumptions (docs/renderers.md): f rises and the decay quickens from rubber to wood to
// aluminium, as in the decaying-sinusoid fits of Okamura et al. 2001; A gives a transient of a
// few newtons at a 0.2 m/s tap
const std::array<Material, 3>& Table() {
  static const std::array<Material, 3> table = {{
      {"rubber", 10.0, 40.0, 30.0},
      {"wood", 15.0, 60.0, 100.0},
      {"aluminium", 25.0, 90.0, 300.0},
  }};
  return table;
}

double RequiredMaterialNumber(const io::StrictObject& o, const std::string& key, double lo,
                              double hi, const std::string& unit) {
  const std::optional<double> value = o.Number(key);
  if (!value) o.FailAt(key, "missing; a material gives amplitude, decay and frequency");
  if (!(*value >= lo && *value <= hi)) {
    o.FailAt(key, text::FormatNumber(*value) + " is out of range: valid " + text::FormatNumber(lo) +
                      " to " + text::FormatNumber(hi) + " " + unit);
  }
  return *value;
}

// `material fit` writes these in "fit"; the reader checks the names and leaves the values alone
const std::vector<std::string> kFitFields = {
    "method", "version",        "recordings", "device",   "taps",     "uncertainty",
    "spread", "amplitude_line", "per_tap",    "warnings", "synthetic"};

// amplitude_quantity "force" (the default: amplitude_Ns_per_m is the force at the device) or
// "acceleration" (measured as the handle's acceleration: amplitude_mps2_per_mps, converted with
// effective_mass_kg, and amplitude_Ns_per_m must be their product, so neither is edited alone).
// An acceleration material keeps both: a device converts it with its own mass (MaterialOnDevice).
void ReadAmplitudeSource(const io::StrictObject& o, Material& m) {
  const std::string quantity =
      o.OneOf("amplitude_quantity", {"force", "acceleration"}, "amplitude quantities")
          .value_or("force");
  if (quantity == "force") {
    for (const char* key : {"amplitude_mps2_per_mps", "effective_mass_kg"}) {
      if (o.Has(key)) o.FailAt(key, "only with \"amplitude_quantity\": \"acceleration\"");
    }
    return;
  }
  const double a = RequiredMaterialNumber(o, "amplitude_mps2_per_mps", 0.0, 1e6, "(m/s^2)/(m/s)");
  const double mass = RequiredMaterialNumber(o, "effective_mass_kg", 1e-6, 1e3, "kg");
  if (std::abs(mass * a - m.amplitude_Ns_per_m) > 1e-6 * std::max(1e-9, m.amplitude_Ns_per_m)) {
    o.FailAt("amplitude_Ns_per_m", text::FormatNumber(m.amplitude_Ns_per_m) +
                                       " is not effective_mass_kg x " +
                                       "amplitude_mps2_per_mps = " + text::FormatNumber(mass * a) +
                                       " (docs/materials.md, \"From acceleration to force\")");
  }
  m.amplitude_mps2_per_mps = a;
  m.effective_mass_kg = mass;
}

}  // namespace

std::span<const Material> MaterialPresets() {
  return Table();
}

Material ReadMaterial(const std::string& path) {
  return ReadMaterialJson(io::JsonSource(path), io::ReadJsonFile(path, "material"), "",
                          std::filesystem::path(path).stem().string());
}

const Material* FindPreset(const Material& material) {
  for (const Material& m : Table()) {
    if (!material.acceleration() && m.name == material.name &&
        m.amplitude_Ns_per_m == material.amplitude_Ns_per_m &&
        m.decay_per_s == material.decay_per_s && m.frequency_hz == material.frequency_hz) {
      return &m;
    }
  }
  return nullptr;
}

Material ReadMaterialJson(const io::JsonSource& source, const nlohmann::json& value,
                          const std::string& path, const std::string& default_name) {
  const io::StrictObject o(
      source, value, path,
      {"name", "amplitude_Ns_per_m", "decay_per_s", "frequency_hz", "amplitude_quantity",
       "amplitude_mps2_per_mps", "effective_mass_kg", "fit"},
      "a material");
  Material m;
  m.name = o.String("name").value_or(default_name);
  if (m.name.empty()) o.FailAt("name", "must not be empty");
  m.amplitude_Ns_per_m = RequiredMaterialNumber(o, "amplitude_Ns_per_m", 0.0, 1e4, "N/(m/s)");
  m.decay_per_s = RequiredMaterialNumber(o, "decay_per_s", 1e-3, 1e5, "1/s");
  // the frequency's upper bound depends on the time step (Nyquist): Configure checks it
  m.frequency_hz = RequiredMaterialNumber(o, "frequency_hz", 1e-3, 1e5, "Hz");
  ReadAmplitudeSource(o, m);
  if (o.Has("fit")) {
    // the fit's provenance (docs/materials.md): kept for people, not used to render
    o.Object("fit", kFitFields, "the fit's record");
  }
  return m;
}

Material ParseMaterial(std::string_view text) {
  for (const Material& m : Table()) {
    if (m.name == text) return m;
  }
  if (text.size() >= 5 && text.substr(text.size() - 5) == ".json") {
    return ReadMaterial(std::string(text));
  }
  std::string names;
  for (const Material& m : Table()) names += m.name + ", ";
  throw Error("unknown material '" + std::string(text) + "'; valid materials: the presets " +
              names + "or a JSON material FILE.json (docs/renderers.md)");
}

MaterialTrainParams MaterialTrain(const Material& material) {
  MaterialTrainParams p;
  p.frequency_hz = material.frequency_hz;
  const double window_s = std::log(20.0) / material.decay_per_s;
  p.t_collision_s =
      std::max(std::min(window_s, limits::kMaxCollisionWindow_s), 1.0 / p.frequency_hz);
  return p;
}

Material MaterialOnDevice(const Material& material, double effective_mass_kg) {
  if (!material.acceleration()) return material;
  if (!(std::isfinite(effective_mass_kg) && effective_mass_kg > 0.0)) {
    throw Error("material '" + material.name + "': the device's effective mass " +
                text::FormatNumber(effective_mass_kg) +
                " kg cannot convert its acceleration amplitude to a force: valid > 0 kg");
  }
  // the mass it was converted with: the file's amplitude as written, to the last bit
  const double mass = material.effective_mass_kg;
  if (std::abs(effective_mass_kg - mass) <= kSameMassRelative * std::max(mass, effective_mass_kg)) {
    return material;
  }
  Material m = material;
  m.effective_mass_kg = effective_mass_kg;
  m.amplitude_Ns_per_m = material.amplitude_mps2_per_mps * effective_mass_kg;
  return m;
}

std::string MaterialDeviceNote(const Material& material, const Material& rendered,
                               const std::string& device) {
  if (!material.acceleration() || !rendered.acceleration()) return "";
  const double fit = material.effective_mass_kg, now = rendered.effective_mass_kg;
  if (std::abs(now - fit) <= kSameMassRelative * std::max(fit, now)) return "";
  return "material '" + material.name + "' was fitted as an acceleration with effective mass " +
         text::FormatNumber(fit) + " kg; on " + device + " (effective mass " +
         text::FormatNumber(now) + " kg) its amplitude is " +
         text::FormatNumber(rendered.amplitude_mps2_per_mps) + " (m/s^2)/(m/s) x " +
         text::FormatNumber(now) + " kg = " + text::FormatNumber(rendered.amplitude_Ns_per_m) +
         " N/(m/s) (the file's " + text::FormatNumber(material.amplitude_Ns_per_m) +
         " N/(m/s); docs/materials.md, \"From acceleration to force\")";
}

std::string RenderMaterialOnDevice(RenderParams& render, double effective_mass_kg,
                                   const std::string& device) {
  if (render.material.name.empty()) return "";
  const Material rendered = MaterialOnDevice(render.material, effective_mass_kg);
  // only the event renderer plays A; a material train takes f and t_c (no note for it)
  std::string note = render.renderer == RendererKind::kEvent
                         ? MaterialDeviceNote(render.material, rendered, device)
                         : std::string();
  render.material = rendered;
  return note;
}

void ApplyMaterial(RenderParams& render, const Material& material) {
  render.material = material;
  if (render.renderer != RendererKind::kTrain) return;
  const MaterialTrainParams t = MaterialTrain(material);
  render.frequency_hz = t.frequency_hz;
  render.t_collision_s = t.t_collision_s;
}

}  // namespace rigidtouch::io
