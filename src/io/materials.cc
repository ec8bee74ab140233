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
    if (m.name == material.name && m.amplitude_Ns_per_m == material.amplitude_Ns_per_m &&
        m.decay_per_s == material.decay_per_s && m.frequency_hz == material.frequency_hz) {
      return &m;
    }
  }
  return nullptr;
}

Material ReadMaterialJson(const io::JsonSource& source, const nlohmann::json& value,
                          const std::string& path, const std::string& default_name) {
  const io::StrictObject o(source, value, path,
                           {"name", "amplitude_Ns_per_m", "decay_per_s", "frequency_hz"},
                           "a material");
  Material m;
  m.name = o.String("name").value_or(default_name);
  if (m.name.empty()) o.FailAt("name", "must not be empty");
  m.amplitude_Ns_per_m = RequiredMaterialNumber(o, "amplitude_Ns_per_m", 0.0, 1e4, "N/(m/s)");
  m.decay_per_s = RequiredMaterialNumber(o, "decay_per_s", 1e-3, 1e5, "1/s");
  // the frequency's upper bound depends on the time step (Nyquist): Configure checks it
  m.frequency_hz = RequiredMaterialNumber(o, "frequency_hz", 1e-3, 1e5, "Hz");
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

void ApplyMaterial(RenderParams& render, const Material& material) {
  render.material = material;
  if (render.renderer != RendererKind::kTrain) return;
  const MaterialTrainParams t = MaterialTrain(material);
  render.frequency_hz = t.frequency_hz;
  render.t_collision_s = t.t_collision_s;
}

}  // namespace rigidtouch::io
