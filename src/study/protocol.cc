#include "study/protocol.h"

#include <algorithm>
#include <cctype>
#include <cstdio>

#include "base/limits.h"
#include "base/text.h"
#include "io/config.h"
#include "io/materials.h"
#include "io/strict_json.h"
#include "rigidtouch/types.h"

namespace rigidtouch::study {

namespace {

using io::JsonSource;
using io::StrictObject;
using nlohmann::json;
using text::FormatNumber;
using text::IndexOf;
using text::Join;
using text::Lower;
using text::Quote;

constexpr std::string_view kFormat = "rigidtouch-study-protocol";
constexpr int kFormatVersion = 1;
constexpr int kMaxTaps = 100;
constexpr int kMaxSeries = 1000;
constexpr int kMaxTests = 100;
constexpr std::size_t kMaxKeyLength = 16;

const std::vector<std::string> kTopKeys = {
    "format",          "format_version",       "name",         "description",
    "instructions",    "conditions",           "tests",        "series",
    "taps_per_series", "familiarization_taps", "randomization"};
const std::vector<std::string> kTestKeys = {"name",           "conditions",           "keys",
                                            "instructions",   "familiarization_taps", "series",
                                            "taps_per_series"};
const std::vector<std::string> kRandomizationKeys = {"series_order", "test_order", "seed"};
const std::vector<std::string> kSeriesOrders = {"balanced", "independent"};  // SeriesOrder
const std::vector<std::string> kTestOrders = {"fixed", "shuffled"};          // TestOrder
// every key a condition may name, in the order error messages list them
const std::vector<std::string> kAllConditionKeys = {"renderer",
                                                    "restitution",
                                                    "t_collision_s",
                                                    "frequency_hz",
                                                    "stiffness_N_per_m",
                                                    "damping_Ns_per_m",
                                                    "scene",
                                                    "device",
                                                    "approach_speed_mps",
                                                    "material",
                                                    "passivity_control",
                                                    "joint_limit_renderer",
                                                    "wall_geom",
                                                    "wall_point_m",
                                                    "wall_normal"};

// whether a condition of `renderer` takes `key`: the event renderer plays its material's
// transient, so it has no restitution; penalty and impulse walls take no material (as the CLI
// refuses --material with them); only a train has a collision window and a rate
bool ConditionKeyApplies(const std::string& key, RendererKind renderer) {
  if (key == "restitution") {
    return renderer == RendererKind::kImpulse || renderer == RendererKind::kTrain;
  }
  if (key == "t_collision_s" || key == "frequency_hz") return renderer == RendererKind::kTrain;
  if (key == "material") {
    return renderer == RendererKind::kTrain || renderer == RendererKind::kEvent;
  }
  return true;
}

std::vector<std::string> ConditionKeysFor(RendererKind renderer) {
  std::vector<std::string> keys;
  for (const std::string& key : kAllConditionKeys) {
    if (ConditionKeyApplies(key, renderer)) keys.push_back(key);
  }
  return keys;
}

bool IsCleanText(std::string_view s) {
  if (s.empty()) return false;
  if (std::isspace(static_cast<unsigned char>(s.front())) ||
      std::isspace(static_cast<unsigned char>(s.back()))) {
    return false;
  }
  return std::none_of(s.begin(), s.end(),
                      [](char c) { return std::iscntrl(static_cast<unsigned char>(c)) != 0; });
}

RendererKind ParseConditionRenderer(const JsonSource& ctx, const json& value,
                                    const std::string& path) {
  const std::vector<std::string>& renderers = text::RendererNames();
  if (!value.contains("renderer")) {
    ctx.Fail(path,
             "missing required field \"renderer\"; valid renderers: " + text::Join(renderers));
  }
  const json& r = value.at("renderer");
  if (!r.is_string()) {
    ctx.Fail(path + ".renderer", "expected a string, got " + io::JsonTypeName(r) +
                                     "; valid renderers: " + text::Join(renderers));
  }
  const std::string name = r.get<std::string>();
  if (std::find(renderers.begin(), renderers.end(), name) == renderers.end()) {
    ctx.Fail(path + ".renderer", "unknown renderer " + text::Quote(name) +
                                     "; valid renderers: " + text::Join(renderers));
  }
  // parameters of another renderer are errors rather than silently ignored settings
  const RendererKind renderer = io::ParseRenderer(name);
  const std::vector<std::string> valid = ConditionKeysFor(renderer);
  for (const auto& [key, unused] : value.items()) {
    if (std::find(valid.begin(), valid.end(), key) != valid.end()) continue;
    const bool known = std::find(kAllConditionKeys.begin(), kAllConditionKeys.end(), key) !=
                       kAllConditionKeys.end();
    ctx.Fail(path, (known ? "parameter " + text::Quote(key) + " does not apply to renderer " + name
                          : "unknown parameter " + text::Quote(key)) +
                       "; valid parameters for renderer " + name + ": " + text::Join(valid));
  }
  return renderer;
}

// the material as --material reads it (io::ParseMaterial: a preset or a JSON file), or its
// fields inline (io::ReadMaterialJson, the file reader), refused here rather than at the first
// tap; a material train takes f and t_c from it, as `tap --renderer train --material`
void ParseConditionMaterial(const JsonSource& ctx, const StrictObject& in, const std::string& path,
                            Condition& c) {
  if (!in.Has("material")) {
    if (c.renderer == RendererKind::kEvent) {
      ctx.Fail(path,
               "missing required field \"material\" for renderer event: the event renderer "
               "plays a material's transient; valid: rubber, wood, aluminium, a JSON material "
               "file, or its fields inline (docs/renderers.md)");
    }
    return;
  }
  const json& value = in.Get("material");
  if (value.is_object()) {
    c.material = io::ReadMaterialJson(ctx, value, in.Path("material"), "");
  } else if (value.is_string()) {
    try {
      c.material = io::ParseMaterial(value.get<std::string>());
    } catch (const Error& e) {
      in.FailAt("material", e.what());
    }
  } else {
    in.FailAt("material",
              "expected a material name or file (a string) or its fields (an "
              "object), got " +
                  io::JsonTypeName(value));
  }
  if (c.renderer == RendererKind::kTrain) {
    for (const char* key : {"t_collision_s", "frequency_hz"}) {
      if (in.Has(key)) {
        in.FailAt(key, "a material train takes f and t_c from its material " +
                           text::Quote(c.material->name) +
                           " (docs/renderers.md): give one or the other");
      }
    }
    const io::MaterialTrainParams t = io::MaterialTrain(*c.material);
    c.t_collision_s = t.t_collision_s;
    c.frequency_hz = t.frequency_hz;
  }
}

void ParseTrainWindow(const JsonSource& ctx, const StrictObject& in, const std::string& path,
                      Condition& c) {
  c.t_collision_s = in.Number("t_collision_s").value_or(limits::kMaxCollisionWindow_s);
  if (!(c.t_collision_s > 0.0 && c.t_collision_s <= limits::kMaxCollisionWindow_s)) {
    in.FailAt("t_collision_s", text::FormatNumber(c.t_collision_s) +
                                   " s is out of range; valid: > 0 and <= " +
                                   text::FormatNumber(limits::kMaxCollisionWindow_s) + " s (II.a)");
  }
  auto f = in.Number("frequency_hz");
  if (!f) {
    ctx.Fail(path,
             "missing required field \"frequency_hz\" for renderer train (or a \"material\", "
             "whose train takes f and t_c from it)");
  }
  c.frequency_hz = *f;
  const double f_min_hz = 1.0 / c.t_collision_s;
  if (!limits::TrainFrequencyFitsWindow(c.frequency_hz, c.t_collision_s)) {
    in.FailAt("frequency_hz", text::FormatNumber(c.frequency_hz) +
                                  " Hz is out of range; valid: >= 1 / t_collision_s = " +
                                  text::FormatNumber(f_min_hz) +
                                  " Hz (II.b; the upper bound 1/h is checked by the "
                                  "engine)");
  }
}

void ParseConditionLaw(const StrictObject& in, Condition& c) {
  if (auto k = in.Number("stiffness_N_per_m")) {
    if (!(*k > 0.0)) in.FailAt("stiffness_N_per_m", text::FormatNumber(*k) + " N/m; valid: > 0");
    c.stiffness_N_per_m = k;
  }
  if (auto b = in.Number("damping_Ns_per_m")) {
    if (*b < 0.0) in.FailAt("damping_Ns_per_m", text::FormatNumber(*b) + " Ns/m; valid: >= 0");
    c.damping_Ns_per_m = b;
  }
  if (auto v = in.Number("approach_speed_mps")) {
    if (!(*v > 0.0)) {
      in.FailAt("approach_speed_mps", text::FormatNumber(*v) + " m/s; valid: > 0");
    }
    c.approach_speed_mps = v;
  }
  for (const char* key : {"scene", "device"}) {
    if (auto s = in.String(key)) {
      if (s->empty()) in.FailAt(key, "must not be empty (omit it for the default)");
      (std::string(key) == "scene" ? c.scene : c.device) = *s;
    }
  }
}

// a finite 3-vector written as an array of three numbers
Vec3 ParseVec3(const StrictObject& in, const char* key) {
  const json& v = in.Get(key);
  if (!v.is_array() || v.size() != 3 ||
      !std::all_of(v.begin(), v.end(), [](const json& x) { return x.is_number(); })) {
    in.FailAt(key, "expected an array of three numbers, got " + v.dump());
  }
  const Vec3 out(v[0].get<double>(), v[1].get<double>(), v[2].get<double>());
  if (!out.allFinite()) in.FailAt(key, "must be finite, got " + v.dump());
  return out;
}

// an articulated scene's joint-limit rendering and where the simulated taps aim
void ParseConditionScene(const StrictObject& in, Condition& c) {
  if (auto r = in.String("joint_limit_renderer")) {
    RendererKind kind = RendererKind::kPenalty;
    try {
      kind = io::ParseRenderer(*r);
    } catch (const Error& e) {
      in.FailAt("joint_limit_renderer", e.what());
    }
    if (kind != RendererKind::kPenalty && kind != RendererKind::kImpulse &&
        kind != RendererKind::kTrain) {
      in.FailAt("joint_limit_renderer",
                text::Quote(*r) + " is not a joint-limit renderer; valid: penalty, impulse, train");
    }
    c.joint_limit_renderer = kind;
  }
  if (auto g = in.String("wall_geom")) {
    if (g->empty()) in.FailAt("wall_geom", "must not be empty (omit it for the default)");
    c.wall_geom = *g;
  }
  if (in.Has("wall_point_m") != in.Has("wall_normal")) {
    in.FailAt(in.Has("wall_point_m") ? "wall_point_m" : "wall_normal",
              "\"wall_point_m\" and \"wall_normal\" go together: give both or neither");
  }
  if (in.Has("wall_point_m")) {
    if (c.wall_geom) in.FailAt("wall_point_m", "give \"wall_geom\" or \"wall_point_m\", not both");
    c.wall_point_m = ParseVec3(in, "wall_point_m");
    c.wall_normal = ParseVec3(in, "wall_normal");
    if (c.wall_normal->norm() < 1e-9) in.FailAt("wall_normal", "must not be zero");
  }
}

Condition ParseCondition(const JsonSource& ctx, const std::string& label, const json& value,
                         const std::string& path) {
  Condition c;
  c.label = label;
  if (!IsCleanText(label)) {
    ctx.Fail(path,
             "a condition label must be non-empty, without control characters or "
             "leading/trailing spaces");
  }
  if (text::Lower(label) == "quit") ctx.Fail(path, "\"quit\" is reserved for stopping a session");
  if (!value.is_object()) {
    ctx.Fail(path,
             "expected a renderer configuration (a JSON object), got " + io::JsonTypeName(value));
  }
  c.renderer = ParseConditionRenderer(ctx, value, path);
  const StrictObject in(ctx, value, path, ConditionKeysFor(c.renderer), "a renderer configuration");

  if (auto e = in.Number("restitution")) {
    if (c.renderer == RendererKind::kTrain && *e != limits::kTrainRestitution) {
      in.FailAt("restitution", text::FormatNumber(*e) +
                                   " is not allowed; a train is only consistent with perfectly "
                                   "plastic collisions (Eq. 8): valid: " +
                                   text::FormatNumber(limits::kTrainRestitution));
    }
    if (*e < limits::kMinRestitution || *e > limits::kMaxRestitution) {
      in.FailAt("restitution", text::FormatNumber(*e) + " is out of range; valid: " +
                                   text::FormatNumber(limits::kMinRestitution) + " to " +
                                   text::FormatNumber(limits::kMaxRestitution) + " (Eq. 4)");
    }
    c.restitution = *e;
  }
  ParseConditionMaterial(ctx, in, path, c);
  if (c.renderer == RendererKind::kTrain && !c.material) ParseTrainWindow(ctx, in, path, c);
  c.passivity_control = in.Bool("passivity_control").value_or(false);
  ParseConditionLaw(in, c);
  ParseConditionScene(in, c);
  return c;
}

int FindCondition(const std::vector<Condition>& conditions, const std::string& label) {
  for (std::size_t i = 0; i < conditions.size(); ++i) {
    if (conditions[i].label == label) return static_cast<int>(i);
  }
  return -1;
}

// the test's conditions: 2 to 8 distinct labels of defined conditions
std::vector<int> ParseTestConditions(const JsonSource& ctx, const StrictObject& in,
                                     const std::string& path,
                                     const std::vector<Condition>& conditions) {
  std::vector<std::string> labels;
  for (const auto& c : conditions) labels.push_back(text::Quote(c.label));
  const std::string range = std::to_string(kMinTestConditions) + " to " +
                            std::to_string(kMaxTestConditions) + " condition labels";
  if (!in.Has("conditions"))
    ctx.Fail(path, "missing required field \"conditions\" (" + range + ")");
  const json& cs = in.Get("conditions");
  if (!cs.is_array() || cs.size() < static_cast<std::size_t>(kMinTestConditions) ||
      cs.size() > static_cast<std::size_t>(kMaxTestConditions)) {
    in.FailAt("conditions", "expected an array of " + range + ", got " + cs.dump());
  }
  std::vector<int> indices;
  for (std::size_t i = 0; i < cs.size(); ++i) {
    const std::string item_path = in.Path("conditions") + "[" + std::to_string(i) + "]";
    if (!cs[i].is_string()) ctx.Fail(item_path, "expected a condition label (a string)");
    const int index = FindCondition(conditions, cs[i].get<std::string>());
    if (index < 0) {
      ctx.Fail(item_path,
               "unknown condition " + cs[i].dump() + "; defined conditions: " + text::Join(labels));
    }
    if (std::find(indices.begin(), indices.end(), index) != indices.end()) {
      in.FailAt("conditions", "condition " + cs[i].dump() +
                                  " is listed twice; the conditions of a test must differ (to "
                                  "test identical walls, define two labels with the same "
                                  "configuration)");
    }
    indices.push_back(index);
  }
  return indices;
}

// one answer key per condition (default "1", "2", ...): distinct without case, not "quit", not
// the label of another condition of the test
std::vector<std::string> ParseTestKeys(const JsonSource& ctx, const StrictObject& in,
                                       const std::vector<Condition>& conditions,
                                       const std::vector<int>& indices) {
  const std::size_t k = indices.size();
  std::vector<std::string> keys;
  for (std::size_t i = 0; i < k; ++i) keys.push_back(std::to_string(i + 1));
  if (in.Has("keys")) {
    const json& ks = in.Get("keys");
    if (!ks.is_array() || ks.size() != k) {
      in.FailAt("keys", "expected an array of " + std::to_string(k) +
                            " answer keys, one per condition, got " + ks.dump());
    }
    for (std::size_t i = 0; i < k; ++i) {
      if (!ks[i].is_string()) {
        ctx.Fail(in.Path("keys") + "[" + std::to_string(i) + "]", "expected a string");
      }
      keys[i] = ks[i].get<std::string>();
    }
  }
  for (std::size_t i = 0; i < k; ++i) {
    const std::string key_path = in.Path("keys") + "[" + std::to_string(i) + "]";
    const std::string& key = keys[i];
    const bool has_space = std::any_of(key.begin(), key.end(), [](char c) {
      return std::isspace(static_cast<unsigned char>(c)) ||
             std::iscntrl(static_cast<unsigned char>(c));
    });
    if (key.empty() || key.size() > kMaxKeyLength || has_space) {
      ctx.Fail(key_path, text::Quote(key) +
                             " is not a valid key; valid: 1 to 16 characters without "
                             "spaces");
    }
    if (text::Lower(key) == "quit")
      ctx.Fail(key_path, "\"quit\" is reserved for stopping a session");
    for (std::size_t j = 0; j < k; ++j) {
      if (j != i && text::Lower(key) == text::Lower(conditions[indices[j]].label)) {
        ctx.Fail(key_path,
                 "key " + text::Quote(key) + " is the label of " +
                     (k == 2 ? std::string("the other condition")
                             : "another condition, " + text::Quote(conditions[indices[j]].label)));
      }
    }
  }
  for (std::size_t i = 0; i < k; ++i) {
    for (std::size_t j = i + 1; j < k; ++j) {
      if (text::Lower(keys[i]) == text::Lower(keys[j])) {
        in.FailAt("keys", k == 2 ? std::string("the two keys must differ (compared without case)")
                                 : "keys " + text::Quote(keys[i]) + " and " + text::Quote(keys[j]) +
                                       " must differ (compared without case)");
      }
    }
  }
  return keys;
}

StudyTest ParseTest(const JsonSource& ctx, const json& value, const std::string& path,
                    const std::vector<Condition>& conditions, const StudyTest& defaults) {
  const StrictObject in(ctx, value, path, kTestKeys, "a test");
  StudyTest t = defaults;
  t.name = in.RequiredString("name");
  if (!IsCleanText(t.name)) in.FailAt("name", "must not start or end with spaces");
  t.instructions = in.String("instructions").value_or("");
  t.familiarization_taps =
      in.Integer("familiarization_taps", defaults.familiarization_taps, 1, kMaxTaps);
  t.series = in.Integer("series", defaults.series, 1, kMaxSeries);
  t.taps_per_series = in.Integer("taps_per_series", defaults.taps_per_series, 1, kMaxTaps);
  t.conditions = ParseTestConditions(ctx, in, path, conditions);
  t.keys = ParseTestKeys(ctx, in, conditions, t.conditions);
  return t;
}

}  // namespace

nlohmann::json Condition::ToJson() const {
  json j = json::object();
  j["renderer"] = text::RendererName(renderer);
  if (renderer == RendererKind::kImpulse || renderer == RendererKind::kTrain) {
    j["restitution"] = restitution;
  }
  // a material train's f and t_c follow from its material: the material stands for them
  if (renderer == RendererKind::kTrain && !material) {
    j["t_collision_s"] = t_collision_s;
    j["frequency_hz"] = frequency_hz;
  }
  if (material) {
    // a preset by its name (as --material takes it); any other material by its own fields
    j["material"] = io::FindPreset(*material) != nullptr
                        ? json(material->name)
                        : json{{"name", material->name},
                               {"amplitude_Ns_per_m", material->amplitude_Ns_per_m},
                               {"decay_per_s", material->decay_per_s},
                               {"frequency_hz", material->frequency_hz}};
    // an acceleration material keeps its form (each device converts it with its own mass); a
    // force material's fields stay as before, so its protocols keep their hash
    if (material->acceleration()) {
      j["material"]["amplitude_quantity"] = "acceleration";
      j["material"]["amplitude_mps2_per_mps"] = material->amplitude_mps2_per_mps;
      j["material"]["effective_mass_kg"] = material->effective_mass_kg;
    }
  }
  // absent when off, so protocols written before the field existed keep their hash
  if (passivity_control) j["passivity_control"] = true;
  if (stiffness_N_per_m) j["stiffness_N_per_m"] = *stiffness_N_per_m;
  if (damping_Ns_per_m) j["damping_Ns_per_m"] = *damping_Ns_per_m;
  if (scene) j["scene"] = *scene;
  if (device) j["device"] = *device;
  if (approach_speed_mps) j["approach_speed_mps"] = *approach_speed_mps;
  // each absent when not given, so older protocols keep their hash
  if (joint_limit_renderer) j["joint_limit_renderer"] = text::RendererName(*joint_limit_renderer);
  if (wall_geom) j["wall_geom"] = *wall_geom;
  const auto array = [](const Vec3& v) { return json::array({v.x(), v.y(), v.z()}); };
  if (wall_point_m) j["wall_point_m"] = array(*wall_point_m);
  if (wall_normal) j["wall_normal"] = array(*wall_normal);
  return j;
}

RenderParams Condition::ToRenderParams() const {
  RenderParams r;
  r.renderer = renderer;
  r.restitution = restitution;
  if (renderer == RendererKind::kTrain) {
    r.t_collision_s = t_collision_s;
    r.frequency_hz = frequency_hz;
  }
  if (material) io::ApplyMaterial(r, *material);
  r.passivity_control = passivity_control;
  if (joint_limit_renderer) r.joint_limit_renderer = *joint_limit_renderer;
  return r;
}

nlohmann::json Protocol::ToJson() const {
  json j = json::object();
  j["format"] = std::string(kFormat);
  j["format_version"] = kFormatVersion;
  j["name"] = name;
  j["description"] = description;
  j["instructions"] = instructions;
  json cs = json::object();
  for (const auto& c : conditions) cs[c.label] = c.ToJson();
  j["conditions"] = cs;
  json r = json::object();
  r["series_order"] = kSeriesOrders[static_cast<int>(randomization.series_order)];
  r["test_order"] = kTestOrders[static_cast<int>(randomization.test_order)];
  if (randomization.seed) r["seed"] = *randomization.seed;
  j["randomization"] = r;
  json ts = json::array();
  for (const auto& t : tests) {
    json tj = json::object();
    tj["name"] = t.name;
    json labels = json::array();
    for (int c : t.conditions) labels.push_back(conditions[c].label);
    tj["conditions"] = labels;
    tj["keys"] = t.keys;
    tj["instructions"] = t.instructions;
    tj["familiarization_taps"] = t.familiarization_taps;
    tj["series"] = t.series;
    tj["taps_per_series"] = t.taps_per_series;
    ts.push_back(tj);
  }
  j["tests"] = ts;
  return j;
}

Protocol ParseProtocol(const nlohmann::json& document, std::string_view source) {
  const JsonSource ctx(source);
  const StrictObject in(ctx, document, "", kTopKeys, "a protocol");
  Protocol p;
  if (auto format = in.String("format"); format && *format != kFormat) {
    ctx.Fail("format",
             text::Quote(*format) + " is not a study protocol; valid: " + text::Quote(kFormat));
  }
  in.Integer("format_version", kFormatVersion, kFormatVersion, kFormatVersion);
  p.name = in.RequiredString("name");
  p.description = in.String("description").value_or("");
  p.instructions = in.String("instructions").value_or("");

  StudyTest defaults;
  defaults.familiarization_taps = in.Integer("familiarization_taps", 3, 1, kMaxTaps);
  defaults.series = in.Integer("series", 20, 1, kMaxSeries);
  defaults.taps_per_series = in.Integer("taps_per_series", 3, 1, kMaxTaps);

  if (in.Has("randomization")) {
    const StrictObject r = in.Object("randomization", kRandomizationKeys, "randomization settings");
    // the names in enum order: the index of the name is the enumerator
    if (auto order = r.OneOf("series_order", kSeriesOrders, "series order")) {
      p.randomization.series_order = static_cast<SeriesOrder>(text::IndexOf(kSeriesOrders, *order));
    }
    if (auto order = r.OneOf("test_order", kTestOrders, "test order")) {
      p.randomization.test_order = static_cast<TestOrder>(text::IndexOf(kTestOrders, *order));
    }
    p.randomization.seed = r.Unsigned("seed");
  }

  if (!in.Has("conditions")) ctx.Fail("", "missing required field \"conditions\"");
  const json& cs = in.Get("conditions");
  if (!cs.is_object() || cs.empty()) {
    ctx.Fail("conditions",
             "expected a non-empty object mapping labels to renderer "
             "configurations");
  }
  for (const auto& [label, value] : cs.items()) {
    const std::string path = "conditions[" + text::Quote(label) + "]";
    Condition c = ParseCondition(ctx, label, value, path);
    for (const auto& other : p.conditions) {
      if (text::Lower(other.label) == text::Lower(label)) {
        ctx.Fail(path, "label differs from " + text::Quote(other.label) +
                           " only in case; answers are matched without case");
      }
    }
    p.conditions.push_back(std::move(c));
  }

  if (!in.Has("tests")) ctx.Fail("", "missing required field \"tests\"");
  const json& ts = in.Get("tests");
  if (!ts.is_array() || ts.empty() || ts.size() > static_cast<std::size_t>(kMaxTests)) {
    ctx.Fail("tests", "expected an array of 1 to 100 tests");
  }
  for (std::size_t i = 0; i < ts.size(); ++i) {
    const std::string path = "tests[" + std::to_string(i) + "]";
    StudyTest t = ParseTest(ctx, ts[i], path, p.conditions, defaults);
    for (const auto& other : p.tests) {
      if (text::Lower(other.name) == text::Lower(t.name)) {
        ctx.Fail(path + ".name", "duplicate test name " + text::Quote(t.name));
      }
    }
    p.tests.push_back(std::move(t));
  }
  return p;
}

Protocol LoadProtocol(const std::string& path) {
  return ParseProtocol(io::ReadJsonFile(path, "protocol file"), path);
}

std::uint64_t Fnv1a64(std::string_view bytes) {
  std::uint64_t h = 0xcbf29ce484222325ULL;  // FNV offset basis
  for (char c : bytes) {
    h ^= static_cast<unsigned char>(c);
    h *= 0x100000001b3ULL;  // FNV prime
  }
  return h;
}

std::string ProtocolHash(const Protocol& protocol) {
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx",
                static_cast<unsigned long long>(Fnv1a64(protocol.ToJson().dump())));
  return std::string("fnv1a64:") + hex;
}

}  // namespace rigidtouch::study
