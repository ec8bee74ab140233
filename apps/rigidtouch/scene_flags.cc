#include "scene_flags.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <iostream>
#include <limits>
#include <system_error>

#include "base/limits.h"
#include "base/text.h"
#include "io/config.h"
#include "io/materials.h"
#include "io/output_file.h"
#include "io/resources.h"
#include "loop/loop_json.h"

namespace rigidtouch::cli {

const char kPrecedence[] =
    "Settings: a flag overrides the config file (--config), which overrides the device preset "
    "(force limit, tool stiffness and damping), which overrides the built-in default. A value "
    "you wrote that cannot be used is refused with the reason, never ignored.";

namespace {

// the flag that sets each field (the field paths are the config file's)
const std::map<std::string, std::string>& FlagOf() {
  static const std::map<std::string, std::string> flags = {
      {"tool", "--tool"},
      {"timestep_s", "--timestep"},
      {"render.renderer", "--renderer"},
      {"render.joint_limit_renderer", "--joint-limit-renderer"},
      {"render.restitution", "--restitution"},
      {"render.t_collision_s", "--t-collision"},
      {"render.frequency_hz", "--frequency"},
      {"render.reference_solver", "--reference-solver"},
      {"render.passivity_control", "--passivity-control"},
      {"render.material", "--material"},
      {"contact.stiffness_N_per_m", "--stiffness"},
      {"contact.damping_Ns_per_m", "--damping"},
      {"threads", "--threads"}};
  return flags;
}

std::string Where(const Settings& s, const std::string& field) {
  const auto it = s.origin.find(field);
  if (it == s.origin.end()) return "";
  return it->second.rfind("--", 0) == 0 ? "set by " + it->second
                                        : "set in " + it->second + " as " + field;
}

}  // namespace

CLI::Validator InRange(double lo, double hi, const std::string& unit) {
  const std::string valid =
      std::isinf(hi)
          ? "valid " + text::FormatNumber(lo) + " " + unit + " or more"
          : "valid " + text::FormatNumber(lo) + " to " + text::FormatNumber(hi) + " " + unit;
  return CLI::Validator(
      [lo, hi, valid](std::string& text) -> std::string {
        double value = 0.0;
        if (!CLI::detail::lexical_cast(text, value)) return text + " is not a number";
        if (!(value >= lo && value <= hi)) return text + " is out of range: " + valid;
        return "";
      },
      "[" + text::FormatNumber(lo) + ", " + (std::isinf(hi) ? "inf" : text::FormatNumber(hi)) +
          "]");
}

CLI::Validator SeedRange() {
  const std::string max = std::to_string(std::numeric_limits<std::uint64_t>::max());
  const std::string valid = "valid 0 to " + max;
  return CLI::Validator(
      [valid](std::string& text) -> std::string {
        const bool signed_text = !text.empty() && (text[0] == '-' || text[0] == '+');
        const std::size_t begin = signed_text ? 1 : 0;
        if (begin == text.size() ||
            text.find_first_not_of("0123456789", begin) != std::string::npos) {
          return text + " is not a whole number: " + valid;
        }
        std::uint64_t value = 0;
        const std::from_chars_result r =
            std::from_chars(text.data() + begin, text.data() + text.size(), value);
        if (r.ec == std::errc::result_out_of_range || (text[0] == '-' && value != 0)) {
          return text + " is out of range: " + valid;
        }
        text = std::to_string(value);  // decimal, whatever CLI11 would read 010 as
        return "";
      },
      "[0, " + max + "]");
}

Vec3 ToolForce(const std::vector<double>& xyz) {
  const Vec3 force(xyz.at(0), xyz.at(1), xyz.at(2));
  if (!force.allFinite()) {
    throw Error("--tool-force must be finite, got " + text::FormatNumber(xyz[0]) + " " +
                text::FormatNumber(xyz[1]) + " " + text::FormatNumber(xyz[2]));
  }
  return force;
}

void AddRateFlag(CLI::App* app, double& rate_hz, const std::string& description) {
  app->add_option("--rate", rate_hz, description)
      ->capture_default_str()
      ->check(InRange(limits::kMinRate_hz, limits::kMaxRate_hz, "Hz"));
}

void AddSceneFlags(CLI::App* app, SceneFlags& f, bool scene_required) {
  auto* scene = app->add_option("--scene", f.scene, "MJCF scene file");
  if (scene_required) scene->required();
  app->add_option("--config", f.config,
                  "JSON file with rigidtouch parameters (tool, timestep_s, contact, render, "
                  "device; docs/config.md)");
  app->add_option(
      "--tool", f.tool,
      "name of the free body that is the tool, or none for a scene without a tool (default: the "
      "config's, else tool)");
  app->add_option("--timestep", f.timestep_s, "time step h [s] (default: the MJCF option)");
  app->add_option("--renderer", f.renderer,
                  "penalty | impulse | train | event, or event:MATERIAL and train:MATERIAL (a "
                  "material train) as --compare takes them")
      ->check(CLI::Validator(
          [](const std::string& value) {
            const std::string name = value.substr(0, value.find(':'));
            const std::vector<std::string> names = text::RendererNames();
            if (std::find(names.begin(), names.end(), name) == names.end()) {
              return "'" + name + "' is no renderer; valid: penalty, impulse, train, event";
            }
            if (value.find(':') != std::string::npos && name != "event" && name != "train") {
              return "a material goes with event or train, not with '" + name + "'";
            }
            return std::string();
          },
          "RENDERER[:MATERIAL]"));
  app->add_option("--joint-limit-renderer", f.joint_limit_renderer,
                  "how a hinge's or slide's limit renders: penalty | impulse | train (default: "
                  "the config's, else train)")
      ->check(CLI::IsMember({"penalty", "impulse", "train"}));
  app->add_option("--material", f.material,
                  "the event renderer's or the material train's material: rubber | wood | "
                  "aluminium | FILE.json (docs/renderers.md)");
  app->add_option("--restitution", f.restitution,
                  "restitution e in [0, 1] (impulse renderer; the train's is 0)");
  app->add_option("--t-collision", f.t_collision_s,
                  "collision window t_c [s], at most 0.1 (train renderer)");
  app->add_option("--frequency", f.frequency_hz, "impulse-train frequency f [Hz] (train renderer)");
  app->add_option("--stiffness", f.stiffness_N_per_m, "tool contact stiffness k [N/m]");
  app->add_option("--damping", f.damping_Ns_per_m, "tool contact damping b [N s/m]");
  app->add_flag("--reference-solver", f.reference_solver,
                "use the exact pseudo-inverse of Eq. 5/8 (may pull; allocates; impulse and train "
                "renderers)");
  app->add_flag("--passivity-control", f.passivity_control,
                "passivity observer and controller at the device port (Hannaford and Ryu 2002; "
                "docs/renderers.md)");
  const std::string footer = app->get_footer();
  app->footer(footer.empty() ? kPrecedence : std::string(kPrecedence) + "\n\n" + footer);
}

void AddThreadsFlag(CLI::App* app, SceneFlags& flags) {
  app->add_option("--threads", flags.threads,
                  "threads stepping the scene: 1, or 2 (a worker thread shares collision "
                  "detection, the contacts' classification and forces, and the contact groups' "
                  "solves; the results are the same bit for bit; default 1)")
      ->check(InRange(1, 2, "threads"));
}

Settings ResolveSettings(const SceneFlags& f) {
  Settings s;
  LoadOptions& o = s.load;
  if (!f.config.empty()) {
    for (const std::string& field : io::ApplyConfigFile(f.config, o, &s.connect)) {
      s.origin[field] = f.config;
    }
  }
  auto flag = [&s](const std::string& field, auto& out, const auto& value) {
    if (!value) return;
    out = *value;
    s.origin[field] = FlagOf().at(field);
  };
  flag("tool", o.tool_name, f.tool);
  flag("timestep_s", o.timestep_s, f.timestep_s);
  flag("threads", o.threads, f.threads);
  // --renderer NAME:MATERIAL names the material too (as --compare's entries do)
  std::optional<std::string> material = f.material;
  std::string material_flag = "--material";
  if (f.renderer) {
    const std::size_t colon = f.renderer->find(':');
    o.render.renderer = io::ParseRenderer(f.renderer->substr(0, colon));
    s.origin["render.renderer"] = "--renderer";
    if (colon != std::string::npos) {
      if (f.material) {
        throw Error("--renderer " + *f.renderer + " and --material " + *f.material +
                    " both name the material: give it once");
      }
      material = f.renderer->substr(colon + 1);
      material_flag = "--renderer";
    }
  }
  if (f.joint_limit_renderer) {
    o.render.joint_limit_renderer = io::ParseRenderer(*f.joint_limit_renderer);
    s.origin["render.joint_limit_renderer"] = "--joint-limit-renderer";
  }
  flag("render.restitution", o.render.restitution, f.restitution);
  flag("render.t_collision_s", o.render.t_collision_s, f.t_collision_s);
  flag("render.frequency_hz", o.render.frequency_hz, f.frequency_hz);
  flag("contact.stiffness_N_per_m", o.contact.stiffness_N_per_m, f.stiffness_N_per_m);
  flag("contact.damping_Ns_per_m", o.contact.damping_Ns_per_m, f.damping_Ns_per_m);
  if (f.reference_solver) {
    o.render.reference_solver = true;
    s.origin["render.reference_solver"] = "--reference-solver";
  }
  if (material) {
    o.render.material = io::ParseMaterial(*material);
    s.origin["render.material"] = material_flag;
  }
  if ((material || s.Given("render.material")) && o.render.renderer == RendererKind::kTrain) {
    // a material train: f and the window come from the material, not from a flag as well
    for (const char* field : {"render.frequency_hz", "render.t_collision_s"}) {
      if (s.Given(field)) {
        throw Error(std::string(field) + " (" + Where(s, field) + ") and the material (" +
                    Where(s, "render.material") +
                    ") both set the train; a material train takes f and t_c from the material "
                    "(docs/renderers.md): give one");
      }
    }
    io::ApplyMaterial(o.render, o.render.material);
  }
  if (f.passivity_control) {
    o.render.passivity_control = true;
    s.origin["render.passivity_control"] = "--passivity-control";
  }
  // a scene law the user wrote is kept even when it equals the default (Configure derives the
  // scene's otherwise)
  o.contact.scene_stiffness_given = s.Given("contact.scene_stiffness_N_per_m");
  o.contact.scene_damping_given = s.Given("contact.scene_damping_Ns_per_m");
  o.render.frequency_given = s.Given("render.frequency_hz") || !o.render.material.name.empty();
  return s;
}

void ApplyDevicePreset(Settings& s, const DeviceLimits& preset, double rate_hz) {
  LoadOptions& o = s.load;
  const double h = 1.0 / rate_hz;
  if (s.Given("timestep_s") && o.timestep_s && *o.timestep_s != h) {
    throw Error(
        "timestep_s = " + text::FormatNumber(*o.timestep_s) + " s (" + Where(s, "timestep_s") +
        ") differs from the haptic period 1 / rate = " + text::FormatNumber(h) +
        " s: here the time step is the device's period; drop it " + "or set the rate instead");
  }
  o.timestep_s = h;
  if (!s.Given("contact.stiffness_N_per_m")) {
    o.contact.stiffness_N_per_m =
        device::DefaultWall(preset, h, o.contact.stiffness_N_per_m).stiffness_N_per_m;
  }
  if (!s.Given("contact.damping_Ns_per_m")) {
    o.contact.damping_Ns_per_m = device::DefaultDamping(preset, h, o.contact.stiffness_N_per_m);
  }
  if (s.Given("device.max_force_N")) {
    const double mine = o.device.limits.max_force_N;  // 0: no limit of the user's own
    if (preset.max_force_N > 0.0 && (mine == 0.0 || mine > preset.max_force_N)) {
      throw Error("device.max_force_N = " + text::FormatNumber(mine) + " N (" +
                  Where(s, "device.max_force_N") + ") is above the " + preset.name +
                  " preset's force limit, " + text::FormatNumber(preset.max_force_N) +
                  " N: the device cannot display it; give at most that, or choose another "
                  "device preset");
    }
  } else {
    o.device.limits.max_force_N = preset.max_force_N;
  }
}

void RefuseUnused(const Settings& s, const std::vector<std::string>& fields,
                  const std::string& why) {
  for (const std::string& field : fields) {
    if (s.Given(field)) {
      throw Error(field + " (" + Where(s, field) + ") has no effect here: " + why + "; remove it");
    }
  }
}

namespace {

// "the train renderer", "the impulse and train renderers", "the penalty or impulse renderers"
std::string RendererList(std::vector<RendererKind> kinds, const std::string& conjunction) {
  std::sort(kinds.begin(), kinds.end());
  kinds.erase(std::unique(kinds.begin(), kinds.end()), kinds.end());
  std::string list = "the ";
  for (std::size_t i = 0; i < kinds.size(); ++i) {
    if (i > 0) list += i + 1 == kinds.size() ? " " + conjunction + " " : ", ";
    list += text::RendererName(kinds[i]);
  }
  return list + (kinds.size() == 1 ? " renderer" : " renderers");
}

}  // namespace

void RefuseUnusedRender(const Settings& s, const std::vector<RendererKind>& renderers) {
  using K = RendererKind;
  // the renderers that take each parameter (docs/renderers.md)
  static const std::vector<std::pair<std::string, std::vector<K>>> takers = {
      {"restitution", {K::kImpulse, K::kTrain}},
      {"t_collision_s", {K::kTrain}},
      {"frequency_hz", {K::kTrain}},
      {"reference_solver", {K::kImpulse, K::kTrain}}};
  for (const auto& taker : takers) {
    // named references, not a structured binding: clang 14 cannot capture a binding in a lambda
    const std::string& name = taker.first;
    const std::vector<K>& by = taker.second;
    const std::string field = "render." + name;
    if (field == "render.reference_solver" && !s.load.render.reference_solver) continue;
    const bool used = std::any_of(renderers.begin(), renderers.end(), [&by](K k) {
      return std::find(by.begin(), by.end(), k) != by.end();
    });
    if (!used) {
      RefuseUnused(s, {field},
                   name + " is used only by " + RendererList(by, "and") + ", not by " +
                       RendererList(renderers, "or"));
    }
  }
}

void RefuseDeviceSettings(const Settings& s, const std::string& command) {
  const std::string why =
      command + " has no device (the tool is pushed by the constant --tool-force)";
  if (s.load.device.coupling != Coupling::kNone) RefuseUnused(s, {"device.coupling"}, why);
  RefuseUnused(
      s,
      {"device.max_force_N", "device.coupling_stiffness_N_per_m",
       "device.coupling_damping_Ns_per_m", "device.plausible_radius_m",
       "device.plausible_speed_mps", "device.plausible_angular_speed_radps", "device.connect"},
      why);
}

std::string OriginNote(const Settings& s, const std::string& message) {
  // Configure's messages read "parameter NAME = ..."
  const std::string tag = "parameter ";
  const std::size_t at = message.find(tag);
  if (at == std::string::npos) return "";
  const std::size_t begin = at + tag.size();
  const std::string name = message.substr(begin, message.find(' ', begin) - begin);
  for (const auto& [field, unused] : s.origin) {
    const bool match = field == name || (field.size() > name.size() &&
                                         field.compare(field.size() - name.size() - 1,
                                                       std::string::npos, "." + name) == 0);
    if (match) return " (" + Where(s, field) + ")";
  }
  return "";
}

nlohmann::json WarningsJson(const std::array<WarningStat, static_cast<int>(Warning::kCount)>& w) {
  nlohmann::json j = nlohmann::json::object();
  for (int k = 0; k < static_cast<int>(Warning::kCount); ++k) {
    if (w[k].count > 0) j[WarningName(static_cast<Warning>(k))] = w[k].count;
  }
  return j;
}

namespace {

// what a counted warning (Data's Warning, by its report name) means, for a sentence that ends
// "in N ticks"
std::string WarningMeaning(const std::string& name) {
  static const std::pair<const char*, const char*> kMeanings[] = {
      {"contact_full", "more contacts than the model's max_contacts (the extra ones dropped)"},
      {"group_too_large", "a contact group larger than max_group_bodies (its bodies moved freely)"},
      {"solver_failed", "the impulse solver failed (the impulse skipped)"},
      {"bad_device_state", "an invalid device state (zero force sent)"},
      {"non_finite_state", "a non-finite simulation state (the state reset)"},
      {"force_clipped", "the device's force limit clipped the force"},
      {"impulse_clipped", "the clipped force held an impulse"},
      {"implausible_device_state",
       "a device state beyond the plausible reach or speed (zero force sent)"},
  };
  for (const auto& [key, meaning] : kMeanings) {
    if (name == key) return meaning;
  }
  return name;
}

}  // namespace

void PrintWarnings(const nlohmann::json& warnings, std::ostream& out) {
  // out is the terminal's stderr in use; a stream is taken so tests can read it
  for (const auto& [name, count] : warnings.items()) {
    const int ticks = count.get<int>();
    out << "rigidtouch: warning: " << WarningMeaning(name) << " in " << ticks
        << (ticks == 1 ? " tick" : " ticks") << " (" << name << ")\n";
  }
}

void PrintLoadWarnings(const Model& model) {
  for (const std::string& w : model.load_warnings)
    std::cerr << "rigidtouch: warning: " << w << "\n";
}

void PrintMaterialNote(const std::string& note) {
  if (!note.empty()) std::cerr << "rigidtouch: note: " << note << "\n";
}

analysis::TapExperimentConfig TapConfig(const SceneFlags& f, const std::string& device_preset,
                                        double rate_hz, double speed_mps, int taps) {
  Settings s = ResolveSettings(f);
  ApplyDevicePreset(s, device::ParseDeviceSpec(device_preset).limits, rate_hz);
  analysis::TapExperimentConfig c;
  c.scene_path = f.scene.empty() ? io::ShippedFile("scenes/wall.xml") : f.scene;
  c.load = s.load;
  c.device_preset = device_preset;
  c.rate_hz = rate_hz;
  c.stiffness_N_per_m = s.load.contact.stiffness_N_per_m;
  c.damping_Ns_per_m = s.load.contact.damping_Ns_per_m;
  c.max_force_N = s.load.device.limits.max_force_N;
  if (s.Given("device.coupling_stiffness_N_per_m")) {
    c.coupling_stiffness_N_per_m = s.load.device.coupling_stiffness_N_per_m;
  }
  if (s.Given("device.coupling_damping_Ns_per_m")) {
    c.coupling_damping_Ns_per_m = s.load.device.coupling_damping_Ns_per_m;
  }
  c.script.approach_speed_mps = speed_mps;
  c.script.taps = taps;
  return c;
}

bool IsConnection(const std::string& text) {
  return text == "sim" || text.rfind("udp://", 0) == 0 || text.rfind("replay:", 0) == 0;
}

DeviceChoice ResolveDevice(const std::optional<std::string>& device,
                           const std::optional<std::string>& connect,
                           const std::optional<std::string>& preset) {
  DeviceChoice c;
  if (connect && !IsConnection(*connect)) {
    throw Error("--connect " + *connect +
                ": valid connections: sim (the in-process simulated device), udp://HOST:PORT "
                "(a device through the bridge) or replay:LOG (a recorded session); the device "
                "itself is --device NAME|FILE.json");
  }
  std::optional<std::string> spec = device;
  if (device && IsConnection(*device)) {
    // the old spelling: --device names the connection, --preset the device
    if (connect) {
      throw Error("--device " + *device + " and --connect " + *connect +
                  " both name a connection; give the device with --device " +
                  device::DeviceSpecHelp() + " and the connection with --connect");
    }
    c.connect = *device;
    spec = preset;
  } else {
    if (device && preset) {
      throw Error("--device " + *device + " and --preset " + *preset +
                  " both name the device (--preset is the old spelling of --device); give one");
    }
    if (preset) spec = preset;
    if (connect) c.connect = *connect;
  }
  c.spec_text = spec.value_or("touch");
  c.spec = device::ParseDeviceSpec(c.spec_text);
  return c;
}

RecordOutput OpenRecord(const std::string& path, double rate_hz) {
  RecordOutput r;
  if (path.empty()) return r;
  r.file = std::make_unique<io::RecordFileWriter>(path, rate_hz);
  r.queue = std::make_unique<loop::RecordQueue>(
      1 << 16, [w = r.file.get()](std::span<const io::RecordSample> batch) { w->Append(batch); });
  return r;
}

nlohmann::json FinishRecord(RecordOutput& record, const std::string& path) {
  record.queue->Close();
  const loop::TraceQueueStats st = record.queue->stats();
  if (st.dropped > 0) {
    throw io::OutputError("cannot write record file '" + path + "': " + std::to_string(st.dropped) +
                          " ticks were dropped because the writer fell behind");
  }
  record.file->Commit();
  return loop::ToJson(st);
}

}  // namespace rigidtouch::cli
