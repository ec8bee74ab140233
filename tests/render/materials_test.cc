// Materials of the event renderer: presets and JSON files whose mistakes name the field.
#include "render/materials.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "rigidtouch/types.h"

namespace rigidtouch::render {
namespace {

std::string Write(const std::string& text) {
  const auto path = std::filesystem::temp_directory_path() /
                    ("rigidtouch_material_" + std::to_string(::getpid()) + ".json");
  std::ofstream(path) << text;
  return path.string();
}

std::string ErrorOf(const std::string& text) {
  try {
    ParseMaterial(text);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(MaterialsTest, PresetsAndFiles) {
  ASSERT_EQ(MaterialPresets().size(), 3u);
  EXPECT_EQ(ParseMaterial("wood").frequency_hz, 100.0);
  // f rises and the decay quickens from rubber to wood to aluminium
  EXPECT_LT(ParseMaterial("rubber").frequency_hz, ParseMaterial("wood").frequency_hz);
  EXPECT_LT(ParseMaterial("wood").frequency_hz, ParseMaterial("aluminium").frequency_hz);
  EXPECT_LT(ParseMaterial("rubber").decay_per_s, ParseMaterial("aluminium").decay_per_s);
  const std::string path = Write(R"({"name": "steel", "amplitude_Ns_per_m": 30, "decay_per_s": 120,
                "frequency_hz": 400})");
  const Material m = ParseMaterial(path);
  EXPECT_EQ(m.name, "steel");
  EXPECT_EQ(m.amplitude_Ns_per_m, 30.0);
  EXPECT_EQ(m.decay_per_s, 120.0);
  EXPECT_EQ(m.frequency_hz, 400.0);
  std::filesystem::remove(path);
}

TEST(MaterialsTest, BadMaterialsNameTheField) {
  const std::pair<std::string, std::string> cases[] = {
      {R"({"amplitude_Ns_per_m": -1, "decay_per_s": 60, "frequency_hz": 100})",
       "amplitude_Ns_per_m"},
      {R"({"amplitude_Ns_per_m": 10, "frequency_hz": 100})", "decay_per_s"},
      {R"({"amplitude_Ns_per_m": 10, "decay_per_s": 60, "frequency_hz": "high"})", "frequency_hz"},
      {R"({"amplitude_Ns_per_m": 10, "decay_per_s": 60, "frequency_hz": 100, "q": 1})", "q"},
  };
  for (const auto& [text, field] : cases) {
    const std::string path = Write(text);
    const std::string e = ErrorOf(path);
    EXPECT_NE(e.find(path), std::string::npos) << e;
    EXPECT_NE(e.find(field), std::string::npos) << text << ": " << e;
    std::filesystem::remove(path);
  }
  const std::string e = ErrorOf("glass");
  EXPECT_NE(e.find("'glass'"), std::string::npos) << e;
  EXPECT_NE(e.find("aluminium"), std::string::npos) << e;
}

}  // namespace
}  // namespace rigidtouch::render
