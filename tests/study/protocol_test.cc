#include "study/protocol.h"

#include <gtest/gtest.h>

#include <string>

#include "render/limits.h"
#include "rigidtouch/types.h"
#include "study/test_files.h"

namespace rigidtouch::study {
namespace {

using nlohmann::json;

const std::string kWalls = std::string(RIGIDTOUCH_SOURCE_DIR) + "/studies/walls.json";

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
std::string ErrorOf(const json& document) {
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

// the event renderer needs a material a condition cannot name: refused when the protocol loads
TEST(ProtocolTest, EventRendererIsRefusedWithTheReason) {
  json d = Minimal();
  d["conditions"]["b"] = {{"renderer", "event"}};
  const std::string e = ErrorOf(d);
  EXPECT_NE(e.find("conditions[\"b\"].renderer"), std::string::npos) << e;
  EXPECT_NE(e.find("needs a material"), std::string::npos) << e;
}

TEST(ProtocolTest, UnknownRendererListsTheValidOnes) {
  json d = Minimal();
  d["conditions"]["b"]["renderer"] = "trian";
  const std::string e = ErrorOf(d);
  EXPECT_NE(e.find("p.json"), std::string::npos) << e;
  EXPECT_NE(e.find("conditions[\"b\"].renderer"), std::string::npos) << e;
  EXPECT_NE(e.find("\"trian\""), std::string::npos) << e;
  EXPECT_NE(e.find("penalty, impulse, train"), std::string::npos) << e;
}

TEST(ProtocolTest, UnknownParameterListsTheValidOnes) {
  json d = Minimal();
  d["conditions"]["b"]["freq_hz"] = 250;
  const std::string e = ErrorOf(d);
  EXPECT_NE(e.find("unknown parameter \"freq_hz\""), std::string::npos) << e;
  EXPECT_NE(e.find("frequency_hz"), std::string::npos) << e;
  EXPECT_NE(e.find("t_collision_s"), std::string::npos) << e;
}

TEST(ProtocolTest, ParameterOfAnotherRendererIsAnError) {
  json d = Minimal();
  d["conditions"]["a"]["frequency_hz"] = 250;
  const std::string e = ErrorOf(d);
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
    const std::string e = ErrorOf(d);
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
    const std::string e = ErrorOf(d);
    EXPECT_NE(e.find("unknown field \"serie\""), std::string::npos) << e;
    EXPECT_NE(e.find("taps_per_series"), std::string::npos) << e;
  }
  {
    json d = Minimal();
    d["series"] = 0;
    EXPECT_NE(ErrorOf(d).find("series: 0 is out of range; valid: integers 1 to 1000"),
              std::string::npos)
        << ErrorOf(d);
  }
  {
    json d = Minimal();
    d["tests"][0]["familiarization_taps"] = 2.5;
    EXPECT_NE(ErrorOf(d).find("tests[0].familiarization_taps: expected an integer"),
              std::string::npos)
        << ErrorOf(d);
  }
  {
    json d = Minimal();
    d["tests"][0]["conditions"] = {"a", "c"};
    const std::string e = ErrorOf(d);
    EXPECT_NE(e.find("tests[0].conditions[1]: unknown condition \"c\""), std::string::npos) << e;
    EXPECT_NE(e.find("\"a\", \"b\""), std::string::npos) << e;
  }
  {
    json d = Minimal();
    d["tests"][0]["conditions"] = {"a"};
    EXPECT_NE(ErrorOf(d).find("exactly two"), std::string::npos) << ErrorOf(d);
  }
  {
    json d = Minimal();
    d["tests"][0]["keys"] = {"x", "X"};
    EXPECT_NE(ErrorOf(d).find("tests[0].keys: the two keys must differ"), std::string::npos)
        << ErrorOf(d);
  }
  {
    json d = Minimal();
    d["tests"][0]["keys"] = {"b", "2"};
    EXPECT_NE(ErrorOf(d).find("label of the other condition"), std::string::npos) << ErrorOf(d);
  }
  {
    json d = Minimal();
    d["randomization"] = {{"series_order", "random"}};
    const std::string e = ErrorOf(d);
    EXPECT_NE(e.find("randomization.series_order"), std::string::npos) << e;
    EXPECT_NE(e.find("unknown series order \"random\"; valid series orders: balanced, independent"),
              std::string::npos)
        << e;
  }
  {
    json d = Minimal();
    d.erase("name");
    EXPECT_NE(ErrorOf(d).find("missing required field \"name\""), std::string::npos);
  }
  {
    json d = Minimal();
    d["conditions"]["B"] = {{"renderer", "penalty"}};
    EXPECT_NE(ErrorOf(d).find("only in case"), std::string::npos) << ErrorOf(d);
  }
  {
    json d = Minimal();
    d["conditions"]["Quit"] = {{"renderer", "penalty"}};
    EXPECT_NE(ErrorOf(d).find("reserved"), std::string::npos) << ErrorOf(d);
  }
  {
    json d = Minimal();
    d["conditions"]["b"].erase("frequency_hz");
    EXPECT_NE(ErrorOf(d).find("missing required field \"frequency_hz\""), std::string::npos);
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
  d["conditions"]["b"]["t_collision_s"] = render::kMaxCollisionWindow_s;
  EXPECT_EQ(ErrorOf(d), "");
  d["conditions"]["b"]["t_collision_s"] = render::kMaxCollisionWindow_s * 1.001;
  EXPECT_NE(ErrorOf(d).find("valid: > 0 and <= 0.1 s"), std::string::npos) << ErrorOf(d);
  d = Minimal();
  d["conditions"]["b"]["t_collision_s"] = 0.1;
  d["conditions"]["b"]["frequency_hz"] = 10;  // f t_c = 1 up to rounding: one impulse
  EXPECT_EQ(ErrorOf(d), "");
}

}  // namespace
}  // namespace rigidtouch::study
