#include "io/config.h"

#include <utility>
#include <vector>

#include "io/strict_json.h"
#include "io/text.h"

namespace rigidtouch::io {
namespace {

const std::vector<std::string> kRendererNames = {"penalty", "impulse", "train"};
const std::vector<std::string> kCouplingNames = {"none", "direct", "virtual"};

using NumberFields = std::vector<std::pair<std::string, double*>>;

// the field names of a section: its number fields, then the others
std::vector<std::string> Names(const NumberFields& numbers, std::vector<std::string> others) {
  std::vector<std::string> names;
  for (const auto& [name, unused] : numbers) names.push_back(name);
  names.insert(names.end(), others.begin(), others.end());
  return names;
}

void ReadNumbers(const StrictObject& in, const NumberFields& numbers) {
  for (const auto& [name, out] : numbers) in.Read(name, *out);
}

}  // namespace

RendererKind ParseRenderer(const std::string& name) {
  if (name == "penalty") return RendererKind::kPenalty;
  if (name == "impulse") return RendererKind::kImpulse;
  if (name == "train") return RendererKind::kTrain;
  throw Error("unknown renderer " + Quote(name) + "; valid renderers: " + Join(kRendererNames));
}

const std::vector<std::string>& RendererNames() {
  return kRendererNames;
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
  throw Error("unknown coupling " + Quote(name) + "; valid couplings: " + Join(kCouplingNames));
}

void ApplyConfigFile(const std::string& path, LoadOptions& options) {
  const nlohmann::json root = ReadJsonFile(path, "config file");
  const JsonSource source(path);
  const StrictObject top(source, root, "", {"tool", "timestep_s", "contact", "render", "device"},
                         "a config object");
  top.Read("tool", options.tool_name);
  if (auto h = top.Number("timestep_s")) options.timestep_s = *h;

  ContactParams& c = options.contact;
  const NumberFields contact = {
      {"stiffness_N_per_m", &c.stiffness_N_per_m},
      {"damping_Ns_per_m", &c.damping_Ns_per_m},
      {"scene_stiffness_N_per_m", &c.scene_stiffness_N_per_m},
      {"scene_damping_Ns_per_m", &c.scene_damping_Ns_per_m},
      {"friction_static", &c.friction_static},
      {"friction_kinetic", &c.friction_kinetic},
      {"tangential_ratio", &c.tangential_ratio},
      {"onset_speed_mps", &c.onset_speed_mps},
  };
  if (top.Has("contact")) {
    ReadNumbers(top.Object("contact", Names(contact, {}), "the contact section"), contact);
  }

  RenderParams& r = options.render;
  const NumberFields render = {
      {"restitution", &r.restitution},
      {"t_collision_s", &r.t_collision_s},
      {"frequency_hz", &r.frequency_hz},
  };
  if (top.Has("render")) {
    const StrictObject in =
        top.Object("render", Names(render, {"renderer", "reference_solver"}), "the render section");
    if (auto name = in.OneOf("renderer", kRendererNames, "renderer")) {
      r.renderer = ParseRenderer(*name);
    }
    ReadNumbers(in, render);
    in.Read("reference_solver", r.reference_solver);
  }

  DeviceParams& d = options.device;
  const NumberFields device = {
      {"max_force_N", &d.max_force_N},
      {"coupling_stiffness_N_per_m", &d.coupling_stiffness_N_per_m},
      {"coupling_damping_Ns_per_m", &d.coupling_damping_Ns_per_m},
  };
  if (top.Has("device")) {
    const StrictObject in = top.Object("device", Names(device, {"coupling"}), "the device section");
    if (auto name = in.OneOf("coupling", kCouplingNames, "coupling")) {
      d.coupling = ParseCoupling(*name);
    }
    ReadNumbers(in, device);
  }
}

}  // namespace rigidtouch::io
