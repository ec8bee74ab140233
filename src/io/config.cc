#include "io/config.h"

#include <fstream>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>

namespace rigidtouch::io {
namespace {

using nlohmann::json;
using Setter = std::function<void(const json&)>;

std::string Keys(const std::map<std::string, Setter>& fields) {
  std::string keys;
  for (const auto& [k, v] : fields) keys += (keys.empty() ? "" : ", ") + k;
  return keys;
}

void ApplySection(const std::string& path, const std::string& section, const json& object,
                  const std::map<std::string, Setter>& fields) {
  if (!object.is_object()) {
    throw Error("config file '" + path + "': \"" + section + "\" must be a JSON object");
  }
  for (const auto& [key, value] : object.items()) {
    const auto it = fields.find(key);
    if (it == fields.end()) {
      throw Error("config file '" + path + "': unknown field \"" + section + "." + key +
                  "\"; valid fields: " + Keys(fields));
    }
    try {
      it->second(value);
    } catch (const json::exception& e) {
      throw Error("config file '" + path + "': field \"" + section + "." + key +
                  "\" has the wrong type: " + e.what());
    }
  }
}

Setter Number(double& out) {
  return [&out](const json& v) {
    if (!v.is_number()) throw json::type_error::create(302, "expected a number", &v);
    out = v.get<double>();
  };
}

}  // namespace

RendererKind ParseRenderer(const std::string& name) {
  if (name == "penalty") return RendererKind::kPenalty;
  if (name == "impulse") return RendererKind::kImpulse;
  if (name == "train") return RendererKind::kTrain;
  throw Error("unknown renderer '" + name + "'; valid renderers: penalty, impulse, train");
}

const char* RendererName(RendererKind kind) {
  switch (kind) {
    case RendererKind::kPenalty:
      return "penalty";
    case RendererKind::kImpulse:
      return "impulse";
    case RendererKind::kTrain:
      return "train";
  }
  return "unknown";
}

Coupling ParseCoupling(const std::string& name) {
  if (name == "none") return Coupling::kNone;
  if (name == "direct") return Coupling::kDirect;
  if (name == "virtual") return Coupling::kVirtual;
  throw Error("unknown coupling '" + name + "'; valid couplings: none, direct, virtual");
}

void ApplyConfigFile(const std::string& path, LoadOptions& options) {
  std::ifstream in(path);
  if (!in) throw Error("config file '" + path + "' cannot be opened");
  json root;
  try {
    root = json::parse(in);
  } catch (const json::parse_error& e) {
    throw Error("config file '" + path + "' is not valid JSON: " + e.what());
  }
  ContactParams& c = options.contact;
  RenderParams& r = options.render;
  DeviceParams& d = options.device;
  const std::map<std::string, Setter> contact = {
      {"stiffness_N_per_m", Number(c.stiffness_N_per_m)},
      {"damping_Ns_per_m", Number(c.damping_Ns_per_m)},
      {"scene_stiffness_N_per_m", Number(c.scene_stiffness_N_per_m)},
      {"scene_damping_Ns_per_m", Number(c.scene_damping_Ns_per_m)},
      {"friction_static", Number(c.friction_static)},
      {"friction_kinetic", Number(c.friction_kinetic)},
      {"tangential_ratio", Number(c.tangential_ratio)},
      {"onset_speed_mps", Number(c.onset_speed_mps)},
  };
  const std::map<std::string, Setter> render = {
      {"renderer", [&r](const json& v) { r.renderer = ParseRenderer(v.get<std::string>()); }},
      {"restitution", Number(r.restitution)},
      {"t_collision_s", Number(r.t_collision_s)},
      {"frequency_hz", Number(r.frequency_hz)},
      {"reference_solver", [&r](const json& v) { r.reference_solver = v.get<bool>(); }},
  };
  const std::map<std::string, Setter> device = {
      {"coupling", [&d](const json& v) { d.coupling = ParseCoupling(v.get<std::string>()); }},
      {"max_force_N", Number(d.max_force_N)},
      {"coupling_stiffness_N_per_m", Number(d.coupling_stiffness_N_per_m)},
      {"coupling_damping_Ns_per_m", Number(d.coupling_damping_Ns_per_m)},
  };
  double timestep = 0.0;
  const std::map<std::string, Setter> top = {
      {"tool", [&options](const json& v) { options.tool_name = v.get<std::string>(); }},
      {"timestep_s",
       [&](const json& v) {
         Number(timestep)(v);
         options.timestep_s = timestep;
       }},
      {"contact", [&](const json& v) { ApplySection(path, "contact", v, contact); }},
      {"render", [&](const json& v) { ApplySection(path, "render", v, render); }},
      {"device", [&](const json& v) { ApplySection(path, "device", v, device); }},
  };
  ApplySection(path, "(top level)", root, top);
}

}  // namespace rigidtouch::io
