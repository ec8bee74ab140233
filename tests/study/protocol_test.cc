#include "study/protocol.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "base/limits.h"
#include "rigidtouch/types.h"
#include "study/test_files.h"

namespace rigidtouch::study {
namespace {

using nlohmann::json;
using testing::kWalls;

json Minimal() {
  return json::parse(R"({
    "name": "mini",
    "conditions": {
      "a": {"renderer": "impulse"},
      "b": {"renderer": "train", "frequency_hz": 250}
    },
    "tests": [{"name": "t", "conditions": ["a", "b"]}]
  })");
}

// the error message of parsing `document`, or "" if it parsed
std::string ProtocolErrorOf(const json& document) {
  try {
    ParseProtocol(document, "p.json");
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(ProtocolTest, ShippedWallsStudyIsTheMethodsStudy) {
  const Protocol p = LoadProtocol(kWalls);
  EXPECT_EQ(p.name, "walls");
  ASSERT_EQ(p.conditions.size(), 3u);
  ASSERT_EQ(p.tests.size(), 2u);
  // conditions are kept in label order
  const Condition& wall0 = p.conditions[0];
  const Condition& wall1 = p.conditions[1];
  const Condition& wall2 = p.conditions[2];
  EXPECT_EQ(wall0.label, "wall 0");
  EXPECT_EQ(wall0.renderer, RendererKind::kImpulse);
  EXPECT_EQ(wall0.restitution, 0.0);
  EXPECT_EQ(wall1.renderer, RendererKind::kTrain);
  EXPECT_EQ(wall1.frequency_hz, 250.0);
  EXPECT_EQ(wall1.t_collision_s, 0.1);
  EXPECT_EQ(wall2.renderer, RendererKind::kTrain);
  EXPECT_EQ(wall2.frequency_hz, 50.0);
  EXPECT_EQ(wall2.t_collision_s, 0.1);
  const StudyTest& t1 = p.tests[0];
  const StudyTest& t2 = p.tests[1];
  EXPECT_EQ(p.conditions[t1.conditions[0]].label, "wall 0");
  EXPECT_EQ(p.conditions[t1.conditions[1]].label, "wall 1");
  EXPECT_EQ(p.conditions[t2.conditions[0]].label, "wall 1");
  EXPECT_EQ(p.conditions[t2.conditions[1]].label, "wall 2");
  for (const StudyTest& t : p.tests) {
    EXPECT_EQ(t.familiarization_taps, 3);
    EXPECT_EQ(t.series, 20);
    EXPECT_EQ(t.taps_per_series, 3);
  }
  EXPECT_EQ(t1.keys[0], "0");
  EXPECT_EQ(t2.keys[1], "2");
  EXPECT_FALSE(p.instructions.empty());
}

TEST(ProtocolTest, DefaultsApply) {
  const Protocol p = ParseProtocol(Minimal(), "p.json");
  const StudyTest& t = p.tests[0];
  EXPECT_EQ(t.familiarization_taps, 3);
  EXPECT_EQ(t.series, 20);
  EXPECT_EQ(t.taps_per_series, 3);
  EXPECT_EQ(t.keys[0], "1");
  EXPECT_EQ(t.keys[1], "2");
  EXPECT_EQ(p.randomization.series_order, SeriesOrder::kBalanced);
  EXPECT_EQ(p.randomization.test_order, TestOrder::kFixed);
  EXPECT_FALSE(p.randomization.seed.has_value());
  EXPECT_EQ(p.conditions[1].t_collision_s, 0.1);
}

TEST(ProtocolTest, HashIgnoresFormattingAndWhereDefaultsComeFrom) {
  const Protocol a = ParseProtocol(Minimal(), "a.json");
  json explicit_defaults = Minimal();
  explicit_defaults["series"] = 20;
  explicit_defaults["tests"][0]["taps_per_series"] = 3;
  explicit_defaults["tests"][0]["keys"] = {"1", "2"};
  explicit_defaults["conditions"]["b"]["t_collision_s"] = 0.1;
  explicit_defaults["conditions"]["a"]["restitution"] = 0;
  const Protocol b = ParseProtocol(json::parse(explicit_defaults.dump(2)), "b.json");
  EXPECT_EQ(ProtocolHash(a), ProtocolHash(b));
  EXPECT_EQ(a.ToJson(), b.ToJson());

  json changed = Minimal();
  changed["conditions"]["b"]["frequency_hz"] = 251;
  EXPECT_NE(ProtocolHash(a), ProtocolHash(ParseProtocol(changed, "c.json")));
  EXPECT_EQ(ProtocolHash(a).rfind("fnv1a64:", 0), 0u);
  EXPECT_EQ(ProtocolHash(a).size(), 8u + 16u);
}

TEST(ProtocolTest, CanonicalJsonParsesBackToTheSameProtocol) {
  const Protocol p = LoadProtocol(kWalls);
  const Protocol q = ParseProtocol(p.ToJson(), "canonical");
  EXPECT_EQ(ProtocolHash(p), ProtocolHash(q));
}

TEST(ProtocolTest, Fnv1a64TestVectors) {
  // published FNV-1a 64 vectors
  EXPECT_EQ(Fnv1a64(""), 0xcbf29ce484222325ULL);
  EXPECT_EQ(Fnv1a64("a"), 0xaf63dc4c8601ec8cULL);
  EXPECT_EQ(Fnv1a64("foobar"), 0x85944171f73967e8ULL);
}

// the walls study's hash, computed before conditions could name a material or passivity control
// and tests more than two conditions: its canonical JSON (and so logs of it) must not change
TEST(ProtocolTest, WallsStudyHashIsUnchanged) {
  EXPECT_EQ(ProtocolHash(LoadProtocol(kWalls)), "fnv1a64:0e4f65817691a9d1");
}

// the event renderer plays a material's transient: without one it is refused when the protocol
// loads, with the reason
TEST(ProtocolTest, EventRendererWithoutAMaterialIsRefusedWithTheReason) {
  json d = Minimal();
  d["conditions"]["b"] = {{"renderer", "event"}};
  const std::string e = ProtocolErrorOf(d);
  EXPECT_NE(e.find("p.json: conditions[\"b\"]"), std::string::npos) << e;
  EXPECT_NE(e.find("missing required field \"material\" for renderer event"), std::string::npos)
      << e;
  EXPECT_NE(e.find("rubber, wood, aluminium"), std::string::npos) << e;
}

TEST(ProtocolTest, AnyRendererWithAMaterialAndPassivityControl) {
  json d = Minimal();
  d["conditions"]["e"] = {{"renderer", "event"}, {"material", "wood"}};
  d["conditions"]["m"] = {{"renderer", "train"}, {"material", "aluminium"}};
  d["conditions"]["p"] = {{"renderer", "penalty"}, {"passivity_control", true}};
  const Protocol p = ParseProtocol(d, "p.json");
  const Condition& e = p.conditions[2];
  ASSERT_EQ(e.label, "e");
  EXPECT_EQ(e.renderer, RendererKind::kEvent);
  ASSERT_TRUE(e.material.has_value());
  EXPECT_EQ(e.material->name, "wood");
  EXPECT_FALSE(e.passivity_control);
  // the render parameters are --material's: the event transient, a material train's f and t_c
  const RenderParams re = e.ToRenderParams();
  EXPECT_EQ(re.material.name, "wood");
  EXPECT_EQ(re.material.frequency_hz, 100.0);
  const RenderParams rm = p.conditions[3].ToRenderParams();
  EXPECT_EQ(rm.material.name, "aluminium");
  EXPECT_EQ(rm.frequency_hz, 300.0);
  EXPECT_NEAR(rm.t_collision_s, std::log(20.0) / 90.0, 1e-12);  // ln 20 / B, B = 90 1/s
  EXPECT_TRUE(p.conditions[4].passivity_control);
  EXPECT_TRUE(p.conditions[4].ToRenderParams().passivity_control);
  // the canonical JSON carries them, so the hash covers them
  const json c = p.ToJson()["conditions"];
  EXPECT_EQ(c["e"], json::parse(R"({"renderer": "event", "material": "wood"})"));
  EXPECT_EQ(c["m"], json::parse(R"({"renderer": "train", "restitution": 0.0,
                                    "material": "aluminium"})"));
  EXPECT_EQ(c["p"], json::parse(R"({"renderer": "penalty", "passivity_control": true})"));
  json other = d;
  other["conditions"]["e"]["material"] = "rubber";
  EXPECT_NE(ProtocolHash(p), ProtocolHash(ParseProtocol(other, "q.json")));
  other = d;
  other["conditions"]["e"]["passivity_control"] = true;
  EXPECT_NE(ProtocolHash(p), ProtocolHash(ParseProtocol(other, "q.json")));
  EXPECT_EQ(ProtocolHash(p), ProtocolHash(ParseProtocol(p.ToJson(), "canonical")));
}

TEST(ProtocolTest, MaterialAndPassivityErrorsNameTheField) {
  const auto with = [](const json& condition) {
    json d = Minimal();
    d["conditions"]["b"] = condition;
    return ProtocolErrorOf(d);
  };
  std::string e = with({{"renderer", "impulse"}, {"material", "wood"}});
  EXPECT_NE(e.find("conditions[\"b\"]: parameter \"material\" does not apply to renderer impulse"),
            std::string::npos)
      << e;
  e = with({{"renderer", "penalty"}, {"material", "wood"}});
  EXPECT_NE(e.find("\"material\" does not apply to renderer penalty"), std::string::npos) << e;
  e = with({{"renderer", "event"}, {"material", "wood"}, {"restitution", 0}});
  EXPECT_NE(e.find("\"restitution\" does not apply to renderer event"), std::string::npos) << e;
  e = with({{"renderer", "event"}, {"material", "glass"}});
  EXPECT_NE(e.find("conditions[\"b\"].material: unknown material 'glass'"), std::string::npos) << e;
  e = with({{"renderer", "event"}, {"material", 3}});
  EXPECT_NE(e.find("conditions[\"b\"].material: expected a material name or file"),
            std::string::npos)
      << e;
  e = with({{"renderer", "event"},
            {"material", {{"name", "x"}, {"decay_per_s", 50}, {"frequency_hz", 80}}}});
  EXPECT_NE(e.find("conditions[\"b\"].material.amplitude_Ns_per_m: missing"), std::string::npos)
      << e;
  e = with({{"renderer", "event"},
            {"material",
             {{"amplitude_Ns_per_m", 1}, {"decay_per_s", 50}, {"frequency_hz", 80}, {"f", 1}}}});
  EXPECT_NE(e.find("conditions[\"b\"].material"), std::string::npos) << e;
  EXPECT_NE(e.find("\"f\""), std::string::npos) << e;
  e = with({{"renderer", "event"}, {"material", "/nonexistent/m.json"}});
  EXPECT_NE(e.find("conditions[\"b\"].material: /nonexistent/m.json"), std::string::npos) << e;
  e = with({{"renderer", "train"}, {"material", "wood"}, {"frequency_hz", 100}});
  EXPECT_NE(e.find("conditions[\"b\"].frequency_hz: a material train takes f and t_c"),
            std::string::npos)
      << e;
  e = with({{"renderer", "penalty"}, {"passivity_control", "yes"}});
  EXPECT_NE(e.find("conditions[\"b\"].passivity_control"), std::string::npos) << e;
}

// a JSON material file, as --material takes one; the canonical JSON holds the material's own
// fields, so the hash covers what is rendered and a log's embedded protocol parses without the
// file (as `study analyze` on another machine needs)
TEST(ProtocolTest, MaterialFileIsReadAsTheCliReadsIt) {
  json canonical;
  std::string hash;
  {
    const testing::ScratchDir dir;
    const std::string path = dir.File("glass.json");
    testing::WriteFile(path,
                       R"({"amplitude_Ns_per_m": 20, "decay_per_s": 80, "frequency_hz": 200})");
    json d = Minimal();
    d["conditions"]["b"] = {{"renderer", "event"}, {"material", path}};
    const Protocol p = ParseProtocol(d, "p.json");
    const RenderParams r = p.conditions[1].ToRenderParams();
    EXPECT_EQ(r.material.name, "glass");
    EXPECT_EQ(r.material.amplitude_Ns_per_m, 20.0);
    EXPECT_EQ(r.material.decay_per_s, 80.0);
    EXPECT_EQ(r.material.frequency_hz, 200.0);
    canonical = p.ToJson();
    hash = ProtocolHash(p);
    EXPECT_EQ(canonical["conditions"]["b"]["material"],
              json::parse(R"({"name": "glass", "amplitude_Ns_per_m": 20.0, "decay_per_s": 80.0,
                              "frequency_hz": 200.0})"));
    // another content under the same path is another protocol
    testing::WriteFile(path,
                       R"({"amplitude_Ns_per_m": 21, "decay_per_s": 80, "frequency_hz": 200})");
    EXPECT_NE(ProtocolHash(ParseProtocol(d, "p.json")), hash);
  }
  // the file is gone: the canonical protocol still parses, to the same hash and material
  const Protocol q = ParseProtocol(canonical, "embedded");
  EXPECT_EQ(ProtocolHash(q), hash);
  EXPECT_EQ(q.conditions[1].ToRenderParams().material.amplitude_Ns_per_m, 20.0);
}

json ThreeWayJson() {
  return json::parse(R"({
    "name": "three",
    "conditions": {
      "rubber": {"renderer": "event", "material": "rubber"},
      "wood": {"renderer": "event", "material": "wood"},
      "aluminium": {"renderer": "event", "material": "aluminium"}
    },
    "tests": [{"name": "t", "conditions": ["rubber", "wood", "aluminium"],
               "keys": ["r", "w", "a"]}]
  })");
}

TEST(ProtocolTest, TestOfThreeConditionsRoundTrips) {
  const Protocol p = ParseProtocol(ThreeWayJson(), "three.json");
  ASSERT_EQ(p.tests.size(), 1u);
  ASSERT_EQ(p.tests[0].conditions.size(), 3u);
  // conditions are stored by label order (a JSON object); the test keeps its own order
  EXPECT_EQ(p.conditions[p.tests[0].conditions[0]].label, "rubber");
  EXPECT_EQ(p.conditions[p.tests[0].conditions[1]].label, "wood");
  EXPECT_EQ(p.conditions[p.tests[0].conditions[2]].label, "aluminium");
  EXPECT_EQ(p.tests[0].keys, (std::vector<std::string>{"r", "w", "a"}));
  const json canonical = p.ToJson();
  EXPECT_EQ(canonical["tests"][0]["conditions"], json({"rubber", "wood", "aluminium"}));
  EXPECT_EQ(canonical["tests"][0]["keys"], json({"r", "w", "a"}));
  const Protocol q = ParseProtocol(json::parse(canonical.dump()), "canonical");
  EXPECT_EQ(q.tests[0].conditions, p.tests[0].conditions);
  EXPECT_EQ(q.tests[0].keys, p.tests[0].keys);
  EXPECT_EQ(ProtocolHash(p), ProtocolHash(q));
  // default keys: one per condition
  json d = ThreeWayJson();
  d["tests"][0].erase("keys");
  EXPECT_EQ(ParseProtocol(d, "d.json").tests[0].keys, (std::vector<std::string>{"1", "2", "3"}));
  // the order of the conditions is part of the test (keys follow it): another hash
  d = ThreeWayJson();
  d["tests"][0]["conditions"] = {"wood", "rubber", "aluminium"};
  EXPECT_NE(ProtocolHash(p), ProtocolHash(ParseProtocol(d, "d.json")));
}

TEST(ProtocolTest, TestsOfMoreConditionsAreCheckedAsTwo) {
  json d = ThreeWayJson();
  d["tests"][0]["conditions"] = {"rubber", "wood", "rubber"};
  std::string e = ProtocolErrorOf(d);
  EXPECT_NE(e.find("tests[0].conditions: condition \"rubber\" is listed twice"), std::string::npos)
      << e;
  d = ThreeWayJson();
  d["tests"][0]["keys"] = {"r", "w"};
  e = ProtocolErrorOf(d);
  EXPECT_NE(e.find("tests[0].keys: expected an array of 3 answer keys"), std::string::npos) << e;
  d = ThreeWayJson();
  d["tests"][0]["keys"] = {"r", "w", "R"};
  e = ProtocolErrorOf(d);
  EXPECT_NE(e.find("tests[0].keys: keys \"r\" and \"R\" must differ"), std::string::npos) << e;
  d = ThreeWayJson();
  d["tests"][0]["keys"] = {"wood", "w", "a"};
  e = ProtocolErrorOf(d);
  EXPECT_NE(e.find("tests[0].keys[0]: key \"wood\" is the label of another condition"),
            std::string::npos)
      << e;
  d = ThreeWayJson();
  for (const char* label : {"c0", "c1", "c2", "c3", "c4", "c5", "c6", "c7", "c8"}) {
    d["conditions"][label] = {{"renderer", "penalty"}};
    d["tests"][0]["conditions"].push_back(label);
  }
  d["tests"][0].erase("keys");
  e = ProtocolErrorOf(d);
  EXPECT_NE(e.find("tests[0].conditions: expected an array of 2 to 8 condition labels"),
            std::string::npos)
      << e;
  // eight is the most
  d["tests"][0]["conditions"] = {"rubber", "wood", "aluminium", "c0", "c1", "c2", "c3", "c4"};
  EXPECT_EQ(ProtocolErrorOf(d), "");
}

// an articulated scene's condition: its joint-limit renderer and the taps' aim reach the render
// parameters and the tap's configuration, stand in the canonical JSON (so the hash covers them),
// round-trip, and are absent from a protocol that does not give them (its hash unchanged)
TEST(ProtocolTest, JointLimitRendererAndWallAimOfAnArticulatedScene) {
  json doc = Minimal();
  const std::string before = ProtocolHash(ParseProtocol(doc, "p.json"));
  json& b = doc["conditions"]["b"];
  b["scene"] = "scenes/door.xml";
  b["joint_limit_renderer"] = "penalty";
  b["wall_point_m"] = {0.6, -0.02, 1.0};
  b["wall_normal"] = {0, -1, 0};
  const Protocol p = ParseProtocol(doc, "p.json");
  const Condition& c = p.conditions[1];
  ASSERT_TRUE(c.joint_limit_renderer.has_value());
  EXPECT_EQ(*c.joint_limit_renderer, RendererKind::kPenalty);
  EXPECT_EQ(c.ToRenderParams().joint_limit_renderer, RendererKind::kPenalty);
  EXPECT_EQ(p.conditions[0].ToRenderParams().joint_limit_renderer,
            RenderParams{}.joint_limit_renderer);
  EXPECT_EQ(*c.wall_point_m, Vec3(0.6, -0.02, 1.0));
  EXPECT_EQ(*c.wall_normal, Vec3(0.0, -1.0, 0.0));
  EXPECT_EQ(c.ToJson()["joint_limit_renderer"], "penalty");
  EXPECT_EQ(c.ToJson()["wall_normal"], json({0.0, -1.0, 0.0}));
  EXPECT_FALSE(p.conditions[0].ToJson().contains("joint_limit_renderer"));
  EXPECT_NE(ProtocolHash(p), before);
  EXPECT_EQ(ProtocolHash(ParseProtocol(p.ToJson(), "again.json")), ProtocolHash(p));
  doc["conditions"]["b"]["joint_limit_renderer"] = "train";
  EXPECT_NE(ProtocolHash(ParseProtocol(doc, "p.json")), ProtocolHash(p));
}

TEST(ProtocolTest, JointLimitRendererAndWallAimErrorsNameTheField) {
  const struct {
    json fields;
    std::string message;
  } cases[] = {
      {{{"joint_limit_renderer", "event"}},
       "conditions[\"b\"].joint_limit_renderer: \"event\" is not a joint-limit renderer"},
      {{{"joint_limit_renderer", "springy"}}, "conditions[\"b\"].joint_limit_renderer"},
      {{{"wall_point_m", {0, 0, 1}}}, "\"wall_point_m\" and \"wall_normal\" go together"},
      {{{"wall_point_m", {0, 0}}, {"wall_normal", {0, 0, 1}}},
       "conditions[\"b\"].wall_point_m: expected an array of three numbers"},
      {{{"wall_point_m", {0, 0, 1}}, {"wall_normal", {0, 0, 0}}},
       "conditions[\"b\"].wall_normal: must not be zero"},
      {{{"wall_geom", "panel"}, {"wall_point_m", {0, 0, 1}}, {"wall_normal", {0, 0, 1}}},
       "give \"wall_geom\" or \"wall_point_m\", not both"},
      {{{"wall_geom", ""}}, "conditions[\"b\"].wall_geom: must not be empty"},
  };
  for (const auto& k : cases) {
    json doc = Minimal();
    for (const auto& [key, value] : k.fields.items()) doc["conditions"]["b"][key] = value;
    const std::string e = ProtocolErrorOf(doc);
    EXPECT_NE(e.find(k.message), std::string::npos) << k.fields.dump() << ": " << e;
  }
}

TEST(ProtocolTest, UnknownRendererListsTheValidOnes) {
  json d = Minimal();
  d["conditions"]["b"]["renderer"] = "trian";
  const std::string e = ProtocolErrorOf(d);
  EXPECT_NE(e.find("p.json"), std::string::npos) << e;
  EXPECT_NE(e.find("conditions[\"b\"].renderer"), std::string::npos) << e;
  EXPECT_NE(e.find("\"trian\""), std::string::npos) << e;
  EXPECT_NE(e.find("penalty, impulse, train"), std::string::npos) << e;
}

TEST(ProtocolTest, UnknownParameterListsTheValidOnes) {
  json d = Minimal();
  d["conditions"]["b"]["freq_hz"] = 250;
  const std::string e = ProtocolErrorOf(d);
  EXPECT_NE(e.find("unknown parameter \"freq_hz\""), std::string::npos) << e;
  EXPECT_NE(e.find("frequency_hz"), std::string::npos) << e;
  EXPECT_NE(e.find("t_collision_s"), std::string::npos) << e;
}

TEST(ProtocolTest, ParameterOfAnotherRendererIsAnError) {
  json d = Minimal();
  d["conditions"]["a"]["frequency_hz"] = 250;
  const std::string e = ProtocolErrorOf(d);
  EXPECT_NE(e.find("does not apply to renderer impulse"), std::string::npos) << e;
  EXPECT_NE(e.find("restitution"), std::string::npos) << e;
}

TEST(ProtocolTest, OutOfRangeValuesNameFieldAndRange) {
  struct Case {
    const char* condition;
    const char* field;
    json value;
    const char* expected;
  };
  const Case cases[] = {
      {"b", "frequency_hz", 5, ">= 1 / t_collision_s = 10 Hz"},
      {"b", "t_collision_s", 0.2, "<= 0.1 s"},
      {"b", "restitution", 0.5, "valid: 0"},
      {"a", "restitution", 1.5, "valid: 0 to 1"},
      {"a", "stiffness_N_per_m", -1, "valid: > 0"},
      {"a", "damping_Ns_per_m", -1, "valid: >= 0"},
      {"a", "approach_speed_mps", 0, "valid: > 0"},
      {"a", "restitution", "high", "expected a number"},
  };
  for (const Case& c : cases) {
    json d = Minimal();
    d["conditions"][c.condition][c.field] = c.value;
    const std::string e = ProtocolErrorOf(d);
    EXPECT_NE(e.find(std::string("conditions[\"") + c.condition + "\"]." + c.field),
              std::string::npos)
        << e;
    EXPECT_NE(e.find(c.expected), std::string::npos) << e;
  }
}

TEST(ProtocolTest, MalformedStructureNamesTheField) {
  {
    json d = Minimal();
    d["serie"] = 20;
    const std::string e = ProtocolErrorOf(d);
    EXPECT_NE(e.find("unknown field \"serie\""), std::string::npos) << e;
    EXPECT_NE(e.find("taps_per_series"), std::string::npos) << e;
  }
  {
    json d = Minimal();
    d["series"] = 0;
    EXPECT_NE(ProtocolErrorOf(d).find("series: 0 is out of range; valid: integers 1 to 1000"),
              std::string::npos)
        << ProtocolErrorOf(d);
  }
  {
    json d = Minimal();
    d["tests"][0]["familiarization_taps"] = 2.5;
    EXPECT_NE(ProtocolErrorOf(d).find("tests[0].familiarization_taps: expected an integer"),
              std::string::npos)
        << ProtocolErrorOf(d);
  }
  {
    json d = Minimal();
    d["tests"][0]["conditions"] = {"a", "c"};
    const std::string e = ProtocolErrorOf(d);
    EXPECT_NE(e.find("tests[0].conditions[1]: unknown condition \"c\""), std::string::npos) << e;
    EXPECT_NE(e.find("\"a\", \"b\""), std::string::npos) << e;
  }
  {
    json d = Minimal();
    d["tests"][0]["conditions"] = {"a"};
    EXPECT_NE(ProtocolErrorOf(d).find(
                  "tests[0].conditions: expected an array of 2 to 8 condition labels"),
              std::string::npos)
        << ProtocolErrorOf(d);
  }
  {
    json d = Minimal();
    d["tests"][0]["keys"] = {"x", "X"};
    EXPECT_NE(ProtocolErrorOf(d).find("tests[0].keys: the two keys must differ"), std::string::npos)
        << ProtocolErrorOf(d);
  }
  {
    json d = Minimal();
    d["tests"][0]["keys"] = {"b", "2"};
    EXPECT_NE(ProtocolErrorOf(d).find("label of the other condition"), std::string::npos)
        << ProtocolErrorOf(d);
  }
  {
    json d = Minimal();
    d["randomization"] = {{"series_order", "random"}};
    const std::string e = ProtocolErrorOf(d);
    EXPECT_NE(e.find("randomization.series_order"), std::string::npos) << e;
    EXPECT_NE(e.find("unknown series order \"random\"; valid series orders: balanced, independent"),
              std::string::npos)
        << e;
  }
  {
    json d = Minimal();
    d.erase("name");
    EXPECT_NE(ProtocolErrorOf(d).find("missing required field \"name\""), std::string::npos);
  }
  {
    json d = Minimal();
    d["conditions"]["B"] = {{"renderer", "penalty"}};
    EXPECT_NE(ProtocolErrorOf(d).find("only in case"), std::string::npos) << ProtocolErrorOf(d);
  }
  {
    json d = Minimal();
    d["conditions"]["Quit"] = {{"renderer", "penalty"}};
    EXPECT_NE(ProtocolErrorOf(d).find("reserved"), std::string::npos) << ProtocolErrorOf(d);
  }
  {
    json d = Minimal();
    d["conditions"]["b"].erase("frequency_hz");
    EXPECT_NE(ProtocolErrorOf(d).find("missing required field \"frequency_hz\""),
              std::string::npos);
  }
}

TEST(ProtocolTest, UnreadableOrNonJsonFileNamesTheFile) {
  try {
    LoadProtocol("no-such-protocol.json");
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("no-such-protocol.json: cannot open"), std::string::npos);
  }
  try {
    ParseProtocol(json::array(), "list.json");
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("list.json: expected a protocol"), std::string::npos);
  }
}

TEST(ProtocolTest, FileProblemsNameTheFileAndTheField) {
  testing::ScratchDir dir;
  const std::string path = dir.File("p.json");
  auto error = [&](const std::string& text) {
    testing::WriteFile(path, text);
    try {
      LoadProtocol(path);
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  std::string e = error("");
  EXPECT_NE(e.find("p.json: the protocol file is empty"), std::string::npos) << e;
  e = error(R"({"name": "x", "conditions": {"a": {"renderer": "impulse", "restitution": 1e999}}})");
  EXPECT_NE(e.find("p.json: conditions.a.restitution: 1e999 is not a finite number"),
            std::string::npos)
      << e;
  e = error(R"({"name": "x", "name": "y"})");
  EXPECT_NE(e.find("p.json: name: the field is given twice"), std::string::npos) << e;
  e = error("{\n\"name\": x}");
  EXPECT_NE(e.find("p.json: not valid JSON at line 2, column 9 (reading field name)"),
            std::string::npos)
      << e;
}

TEST(ProtocolTest, RenderLimitsAreTheEngines) {
  // the protocol accepts exactly the window the engine accepts
  json d = Minimal();
  d["conditions"]["b"]["t_collision_s"] = limits::kMaxCollisionWindow_s;
  EXPECT_EQ(ProtocolErrorOf(d), "");
  d["conditions"]["b"]["t_collision_s"] = limits::kMaxCollisionWindow_s * 1.001;
  EXPECT_NE(ProtocolErrorOf(d).find("valid: > 0 and <= 0.1 s"), std::string::npos)
      << ProtocolErrorOf(d);
  d = Minimal();
  d["conditions"]["b"]["t_collision_s"] = 0.1;
  d["conditions"]["b"]["frequency_hz"] = 10;  // f t_c = 1 up to rounding: one impulse
  EXPECT_EQ(ProtocolErrorOf(d), "");
}

}  // namespace
}  // namespace rigidtouch::study
