#include "io/config.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <vector>

#include "io/materials.h"
#include "rigidtouch/rigidtouch.h"
#include "test_util.h"

namespace rigidtouch::io {
namespace {

using test::WriteTempFile;

// the error of applying a config file with `text`, or "" if it applied
std::string ConfigErrorOf(const std::string& text, const std::string& name = "config.json") {
  LoadOptions options;
  try {
    ApplyConfigFile(WriteTempFile(name, text), options);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

bool Has(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

TEST(ConfigTest, EverySectionsFieldsAreRead) {
  const std::string path = WriteTempFile("all.json", R"({
    "tool": "probe",
    "timestep_s": 0.0005,
    "contact": {
      "stiffness_N_per_m": 1500, "damping_Ns_per_m": 3.5,
      "scene_stiffness_N_per_m": 1e5, "scene_damping_Ns_per_m": 50,
      "friction_static": 0.6, "friction_kinetic": 0.4,
      "tangential_ratio": 0.5, "onset_speed_mps": 0.002
    },
    "render": {
      "renderer": "impulse", "restitution": 0.3, "t_collision_s": 0.05,
      "frequency_hz": 500, "reference_solver": true
    },
    "device": {
      "coupling": "virtual", "max_force_N": 7.5,
      "coupling_stiffness_N_per_m": 800, "coupling_damping_Ns_per_m": 4,
      "plausible_radius_m": 0.3, "plausible_speed_mps": 2.5,
      "plausible_angular_speed_radps": 40
    }
  })");
  LoadOptions o;
  ApplyConfigFile(path, o);
  EXPECT_EQ(o.tool_name, "probe");
  ASSERT_TRUE(o.timestep_s.has_value());
  EXPECT_EQ(*o.timestep_s, 0.0005);
  EXPECT_EQ(o.contact.stiffness_N_per_m, 1500.0);
  EXPECT_EQ(o.contact.damping_Ns_per_m, 3.5);
  EXPECT_EQ(o.contact.scene_stiffness_N_per_m, 1e5);
  EXPECT_EQ(o.contact.scene_damping_Ns_per_m, 50.0);
  EXPECT_EQ(o.contact.friction_static, 0.6);
  EXPECT_EQ(o.contact.friction_kinetic, 0.4);
  EXPECT_EQ(o.contact.tangential_ratio, 0.5);
  EXPECT_EQ(o.contact.onset_speed_mps, 0.002);
  EXPECT_EQ(o.render.renderer, RendererKind::kImpulse);
  EXPECT_EQ(o.render.restitution, 0.3);
  EXPECT_EQ(o.render.t_collision_s, 0.05);
  EXPECT_EQ(o.render.frequency_hz, 500.0);
  EXPECT_TRUE(o.render.reference_solver);
  EXPECT_EQ(o.device.coupling, Coupling::kVirtual);
  EXPECT_EQ(o.device.limits.max_force_N, 7.5);
  EXPECT_EQ(o.device.coupling_stiffness_N_per_m, 800.0);
  EXPECT_EQ(o.device.coupling_damping_Ns_per_m, 4.0);
  EXPECT_EQ(o.device.plausible_radius_m, 0.3);
  EXPECT_EQ(o.device.plausible_speed_mps, 2.5);
  EXPECT_EQ(o.device.plausible_angular_speed_radps, 40.0);
}

// render.material: a preset's name, or a material file relative to the config file's folder,
// read as --material reads it; a bad one names the config file and the field
TEST(ConfigTest, TheMaterialIsAPresetOrAFileBesideTheConfig) {
  LoadOptions preset;
  ApplyConfigFile(WriteTempFile("m1.json", R"({"render": {"material": "wood"}})"), preset);
  EXPECT_EQ(preset.render.material.name, ParseMaterial("wood").name);
  EXPECT_EQ(preset.render.material.frequency_hz, ParseMaterial("wood").frequency_hz);
  EXPECT_GT(preset.render.material.frequency_hz, 0.0);

  const std::filesystem::path dir =
      std::filesystem::path(WriteTempFile("m2.json", "{}")).parent_path() / "cfgmat";
  std::filesystem::create_directories(dir);
  {
    std::ofstream(dir / "soft.json")
        << R"({"name": "soft", "amplitude_Ns_per_m": 2.5, "decay_per_s": 60, "frequency_hz": 150})";
    std::ofstream(dir / "config.json") << R"({"render": {"material": "soft.json"}})";
  }
  LoadOptions file;
  ApplyConfigFile((dir / "config.json").string(), file);
  EXPECT_EQ(file.render.material.amplitude_Ns_per_m, 2.5);
  EXPECT_EQ(file.render.material.decay_per_s, 60.0);
  EXPECT_EQ(file.render.material.frequency_hz, 150.0);

  const std::string bad = ConfigErrorOf(R"({"render": {"material": "marshmallow"}})", "m3.json");
  EXPECT_TRUE(Has(bad, "m3.json: render.material: ")) << bad;
  EXPECT_TRUE(Has(bad, "marshmallow")) << bad;
  std::filesystem::remove_all(dir);
}

// device.connect: a connection, checked by the reader; a relative replay log is beside the config
TEST(ConfigTest, TheConnectionIsCheckedAndAReplayLogIsBesideTheConfig) {
  for (const std::string connection : {"sim", "udp://127.0.0.1:5005", "replay:/srv/s.csv"}) {
    LoadOptions o;
    std::optional<std::string> connect;
    const std::string path =
        WriteTempFile("conn.json", R"({"device": {"connect": ")" + connection + R"("}})");
    const std::vector<std::string> given = ApplyConfigFile(path, o, &connect);
    EXPECT_EQ(connect, connection);
    EXPECT_NE(std::find(given.begin(), given.end(), "device.connect"), given.end());
  }
  LoadOptions o;
  std::optional<std::string> connect;
  const std::string path = WriteTempFile("conn.json", R"({"device": {"connect": "replay:s.csv"}})");
  ApplyConfigFile(path, o, &connect);
  EXPECT_EQ(connect, "replay:" + (std::filesystem::path(path).parent_path() / "s.csv").string());
  for (const char* bad : {"tcp://host:1", "udp://", "replay:", "touch", ""}) {
    const std::string error =
        ConfigErrorOf(std::string(R"({"device": {"connect": ")") + bad + R"("}})", "conn_bad.json");
    EXPECT_TRUE(Has(error, "conn_bad.json: device.connect: ")) << error;
  }
  const std::string wrong_type = ConfigErrorOf(R"({"device": {"connect": 5}})", "conn5.json");
  EXPECT_TRUE(Has(wrong_type, "device.connect")) << wrong_type;
}

TEST(ConfigTest, AbsentFieldsKeepTheirValues) {
  LoadOptions o;
  o.contact.damping_Ns_per_m = 9.0;
  o.render.renderer = RendererKind::kPenalty;
  ApplyConfigFile(WriteTempFile("some.json", R"({"contact": {"stiffness_N_per_m": 10}})"), o);
  EXPECT_EQ(o.contact.stiffness_N_per_m, 10.0);
  EXPECT_EQ(o.contact.damping_Ns_per_m, 9.0);
  EXPECT_EQ(o.render.renderer, RendererKind::kPenalty);
  EXPECT_FALSE(o.timestep_s.has_value());
  EXPECT_EQ(o.tool_name, "tool");
  EXPECT_EQ(ConfigErrorOf("{}"), "");
}

TEST(ConfigTest, UnknownFieldsAreRejectedListingTheValidOnes) {
  struct Case {
    const char* text;
    const char* where;
    const char* field;
    const char* valid;
  };
  const Case cases[] = {
      {R"({"contacts": {}})", "config.json: unknown field", "\"contacts\"", "contact, render"},
      {R"({"contact": {"stifness_N_per_m": 1}})", "config.json: contact: unknown field",
       "\"stifness_N_per_m\"", "stiffness_N_per_m"},
      {R"({"render": {"freq": 1}})", "config.json: render: unknown field", "\"freq\"",
       "frequency_hz"},
      {R"({"device": {"force": 1}})", "config.json: device: unknown field", "\"force\"",
       "max_force_N"},
  };
  for (const Case& c : cases) {
    const std::string e = ConfigErrorOf(c.text);
    EXPECT_TRUE(Has(e, c.where)) << e;
    EXPECT_TRUE(Has(e, c.field)) << e;
    EXPECT_TRUE(Has(e, std::string("valid fields: ")) && Has(e, c.valid)) << e;
  }
}

TEST(ConfigTest, WrongTypesNameTheFieldAndTheValue) {
  struct Case {
    const char* text;
    const char* expected;
  };
  const Case cases[] = {
      {R"({"contact": {"stiffness_N_per_m": "hard"}})",
       "config.json: contact.stiffness_N_per_m: expected a number, got a string \"hard\""},
      {R"({"render": {"reference_solver": 1}})",
       "config.json: render.reference_solver: expected true or false, got a number 1"},
      {R"({"render": {"renderer": 2}})", "config.json: render.renderer: expected a string"},
      {R"({"render": {"renderer": "trian"}})",
       "config.json: render.renderer: unknown renderer \"trian\"; valid renderers: penalty, "
       "impulse, train"},
      {R"({"device": {"coupling": "loose"}})",
       "config.json: device.coupling: unknown coupling \"loose\"; valid couplings: none, direct, "
       "virtual"},
      {R"({"tool": 3})", "config.json: tool: expected a string, got a number 3"},
      {R"({"timestep_s": null})", "config.json: timestep_s: expected a number, got null"},
      {R"({"device": [1, 2]})",
       "config.json: device: expected the device section (a JSON object), got an array [1,2]"},
      {R"([1])", "config.json: expected a config object (a JSON object), got an array"},
  };
  for (const Case& c : cases) {
    const std::string e = ConfigErrorOf(c.text);
    EXPECT_TRUE(Has(e, c.expected)) << e;
  }
}

TEST(ConfigTest, NonFiniteNumbersNameTheField) {
  // 1e309 overflows a double: an error naming the field, not nlohmann's out_of_range
  std::string e = ConfigErrorOf(R"({"contact": {"stiffness_N_per_m": 1e309}})");
  EXPECT_TRUE(Has(e, "config.json: contact.stiffness_N_per_m: 1e309 is not a finite number")) << e;
  e = ConfigErrorOf(R"({"render": {"frequency_hz": -1e400}})");
  EXPECT_TRUE(Has(e, "config.json: render.frequency_hz: -1e400 is not a finite number")) << e;
  // JSON has no NaN: a syntax error with the position and the field being read
  e = ConfigErrorOf(R"({"device": {"max_force_N": NaN}})");
  EXPECT_TRUE(Has(e, "config.json: not valid JSON at line 1, column 28")) << e;
  EXPECT_TRUE(Has(e, "(reading field device.max_force_N)")) << e;
}

TEST(ConfigTest, MissingEmptyAndMalformedFilesNameTheFile) {
  LoadOptions o;
  try {
    ApplyConfigFile("no-such-config.json", o);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()), "no-such-config.json: cannot open the config file");
  }
  EXPECT_TRUE(Has(ConfigErrorOf("", "empty.json"), "empty.json: the config file is empty"));
  EXPECT_TRUE(Has(ConfigErrorOf(" \n\t", "blank.json"), "blank.json: the config file is empty"));
  const std::string e =
      ConfigErrorOf("{\n  \"contact\": {\n    \"stiffness_N_per_m\": 10,\n  }\n}");
  EXPECT_TRUE(Has(e, "config.json: not valid JSON at line 4, column 3")) << e;
}

TEST(ConfigTest, AFolderGivenAsTheConfigIsNamed) {
  const std::string dir = test::TempDir().string();
  std::filesystem::create_directories(dir);
  LoadOptions o;
  try {
    ApplyConfigFile(dir, o);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()), dir + ": is a directory, not a config file");
  }
  // a number too large for a double at the top level, too
  const std::string e = ConfigErrorOf(R"({"timestep_s": 1e309})");
  EXPECT_TRUE(Has(e, "config.json: timestep_s: 1e309 is not a finite number")) << e;
}

TEST(ConfigTest, AFieldGivenTwiceIsAnError) {
  const std::string e =
      ConfigErrorOf(R"({"contact": {"damping_Ns_per_m": 1, "damping_Ns_per_m": 2}})");
  EXPECT_TRUE(Has(e, "config.json: contact.damping_Ns_per_m: the field is given twice")) << e;
}

TEST(ConfigTest, RendererAndCouplingNamesRoundTrip) {
  for (RendererKind k : {RendererKind::kPenalty, RendererKind::kImpulse, RendererKind::kTrain,
                         RendererKind::kEvent}) {
    EXPECT_EQ(ParseRenderer(text::RendererName(k)), k);
  }
  EXPECT_EQ(text::RendererNames(),
            (std::vector<std::string>{"penalty", "impulse", "train", "event"}));
  EXPECT_EQ(ParseCoupling("none"), Coupling::kNone);
  EXPECT_EQ(ParseCoupling("direct"), Coupling::kDirect);
  EXPECT_EQ(ParseCoupling("virtual"), Coupling::kVirtual);
  EXPECT_THROW(ParseRenderer("spring"), Error);
  EXPECT_THROW(ParseCoupling("loose"), Error);
}

}  // namespace
}  // namespace rigidtouch::io
