#include "io/config.h"

#include <filesystem>
#include <functional>
#include <utility>
#include <vector>

#include "base/names.h"
#include "base/text.h"
#include "io/materials.h"
#include "io/strict_json.h"

namespace rigidtouch::io {
namespace {

using NumberFields = std::vector<std::pair<std::string, double*>>;

// reads section `name` if present: `others` (the fields that are not numbers) with `read_others`,
// then the number fields; appends "name.field" to `given` for each field the file has
void ReadSection(const StrictObject& top, const std::string& name, const NumberFields& numbers,
                 std::vector<std::string>& given, const std::vector<std::string>& others = {},
                 const std::function<void(const StrictObject&)>& read_others = {}) {
  if (!top.Has(name)) return;
  std::vector<std::string> fields;
  for (const auto& [field, unused] : numbers) fields.push_back(field);
  fields.insert(fields.end(), others.begin(), others.end());
  const StrictObject in = top.Object(name, fields, "the " + name + " section");
  if (read_others) read_others(in);
  for (const auto& [field, out] : numbers) in.Read(field, *out);
  for (const std::string& field : fields) {
    if (in.Has(field)) given.push_back(name + "." + field);
  }
}

// a material named in a config file: a ".json" path relative to the file's folder, else a
// preset's name
std::string MaterialPath(const std::string& text, const std::string& config_path) {
  const std::filesystem::path p(text);
  if (p.extension() != ".json" || p.is_absolute()) return text;
  return (std::filesystem::path(config_path).parent_path() / p).string();
}

// a connection named in a config file (device.connect): sim, udp://HOST:PORT, or replay:LOG with
// a relative LOG taken from the config file's folder
std::string ConnectionSetting(const std::string& text, const std::string& config_path) {
  const std::string udp = "udp://", replay = "replay:";
  if (text == "sim" || (text.starts_with(udp) && text.size() > udp.size())) return text;
  if (text.starts_with(replay) && text.size() > replay.size()) {
    const std::filesystem::path log(text.substr(replay.size()));
    if (log.is_absolute()) return text;
    return replay + (std::filesystem::path(config_path).parent_path() / log).string();
  }
  throw Error(config_path + ": device.connect: " + text::Quote(text) +
              " is not a connection; valid connections: sim, udp://HOST:PORT, replay:LOG");
}

}  // namespace

RendererKind ParseRenderer(const std::string& name) {
  const int i = text::IndexOf(text::RendererNames(), name);
  if (i < 0) {
    throw Error("unknown renderer " + text::Quote(name) +
                "; valid renderers: " + text::Join(text::RendererNames()));
  }
  return static_cast<RendererKind>(i);
}

Coupling ParseCoupling(const std::string& name) {
  const int i = text::IndexOf(text::CouplingNames(), name);
  if (i < 0) {
    throw Error("unknown coupling " + text::Quote(name) +
                "; valid couplings: " + text::Join(text::CouplingNames()));
  }
  return static_cast<Coupling>(i);
}

std::vector<std::string> ApplyConfigFile(const std::string& path, LoadOptions& options,
                                         std::optional<std::string>* connect) {
  const nlohmann::json root = ReadJsonFile(path, "config file");
  const JsonSource source(path);
  const StrictObject top(source, root, "",
                         {"tool", "timestep_s", "contact", "render", "device", "threads"},
                         "a config object");
  std::vector<std::string> given;
  for (const char* field : {"tool", "timestep_s"}) {
    if (top.Has(field)) given.push_back(field);
  }
  top.Read("tool", options.tool_name);
  if (auto h = top.Number("timestep_s")) options.timestep_s = *h;
  if (top.Has("threads")) given.push_back("threads");
  options.threads = top.Integer("threads", options.threads, 1, 2);

  ContactParams& c = options.contact;
  ReadSection(top, "contact",
              {{"stiffness_N_per_m", &c.stiffness_N_per_m},
               {"damping_Ns_per_m", &c.damping_Ns_per_m},
               {"scene_stiffness_N_per_m", &c.scene_stiffness_N_per_m},
               {"scene_damping_Ns_per_m", &c.scene_damping_Ns_per_m},
               {"friction_static", &c.friction_static},
               {"friction_kinetic", &c.friction_kinetic},
               {"tangential_ratio", &c.tangential_ratio},
               {"onset_speed_mps", &c.onset_speed_mps}},
              given);

  RenderParams& r = options.render;
  ReadSection(
      top, "render",
      {{"restitution", &r.restitution},
       {"t_collision_s", &r.t_collision_s},
       {"frequency_hz", &r.frequency_hz}},
      given,
      {"renderer", "reference_solver", "passivity_control", "material", "joint_limit_renderer"},
      [&r, &path](const StrictObject& in) {
        if (auto name = in.OneOf("renderer", text::RendererNames(), "renderer")) {
          r.renderer = ParseRenderer(*name);
        }
        // a joint limit renders like a wall: penalty, impulse or train (Configure refuses
        // event with the field named)
        if (auto name =
                in.OneOf("joint_limit_renderer", text::RendererNames(), "joint_limit_renderer")) {
          r.joint_limit_renderer = ParseRenderer(*name);
        }
        in.Read("reference_solver", r.reference_solver);
        in.Read("passivity_control", r.passivity_control);
        // a preset's name, or a material file relative to the config file's folder
        if (auto material = in.String("material")) {
          try {
            r.material = ParseMaterial(MaterialPath(*material, path));
          } catch (const Error& e) {
            throw Error(path + ": render.material: " + e.what());
          }
        }
      });

  DeviceParams& d = options.device;
  ReadSection(top, "device",
              {{"max_force_N", &d.limits.max_force_N},
               {"coupling_stiffness_N_per_m", &d.coupling_stiffness_N_per_m},
               {"coupling_damping_Ns_per_m", &d.coupling_damping_Ns_per_m},
               {"plausible_radius_m", &d.plausible_radius_m},
               {"plausible_speed_mps", &d.plausible_speed_mps},
               {"plausible_angular_speed_radps", &d.plausible_angular_speed_radps}},
              given, {"coupling", "connect"}, [&d, &path, connect](const StrictObject& in) {
                if (auto name = in.OneOf("coupling", text::CouplingNames(), "coupling")) {
                  d.coupling = ParseCoupling(*name);
                }
                if (auto value = in.String("connect")) {
                  const std::string connection = ConnectionSetting(*value, path);
                  if (connect != nullptr) *connect = connection;
                }
              });
  return given;
}

}  // namespace rigidtouch::io
