// End-to-end tests of `rigidtouch tap` (issue: simulated hand and device, the main job).
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "cli/cli_util.h"

namespace rigidtouch::test {
namespace {

namespace fs = std::filesystem;

TEST(TapCliTest, CompareWallsWritesTableTracesAndFigures) {
  const fs::path dir = TempDir("walls");
  const CliResult r = RunCli("tap --compare-walls --taps 1 --json --out-dir " + dir.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  for (const char* key : {"penalty", "wall0", "wall1", "wall2"}) {
    ASSERT_TRUE(j.contains(key)) << key;
    EXPECT_EQ(j[key]["taps"].size(), 1u);
    EXPECT_GT(fs::file_size(j[key]["trace"].get<std::string>()), 0u);
  }
  // impulse counts are checked on an ideal device in tap_experiment_test; here the Touch clips
  // and its encoder makes taps bounce, so only the structure is fixed
  EXPECT_GE(j["wall1"]["taps"][0]["impulses"].size(), 1u);
  EXPECT_EQ(j["wall1"]["frequency_hz"], 250.0);
  EXPECT_EQ(j["wall1"]["impulses_per_window"], 25);
  EXPECT_EQ(j["wall2"]["impulses_per_window"], 5);
  EXPECT_EQ(j["penalty"]["taps"][0]["impulses"].size(), 0u);
  EXPECT_GT(fs::file_size(dir / "walls.md"), 0u);
  // the figures: non-empty PNGs (the signature's first bytes)
  for (const char* png : {"walls.png", "wall0_tap.png", "wall1_tap.png", "wall2_tap.png"}) {
    ASSERT_TRUE(fs::exists(dir / png)) << png << "\n" << r.err;
    EXPECT_GT(fs::file_size(dir / png), 1000u) << png;
    EXPECT_EQ(ReadAll(dir / png).substr(1, 3), "PNG") << png;
  }
  fs::remove_all(dir);
}

TEST(TapCliTest, JsonHasThePerTapFields) {
  const CliResult r = RunCli("tap --wall 2 --taps 2 --device omni --speed 0.15 --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  for (const char* key : {"renderer", "frequency_hz", "t_collision_s", "timestep_s", "device"}) {
    EXPECT_TRUE(j.contains(key)) << key;
  }
  EXPECT_EQ(j["device"], "omni");
  ASSERT_EQ(j["taps"].size(), 2u);
  for (const char* key :
       {"impulses", "peak_force_N", "rate_hardness_N_per_m", "extended_rate_hardness_N_per_m",
        "max_penetration_m", "bounces", "energy_to_user_J", "dominant_frequency_hz",
        "band_energy_fraction", "force_clipped"}) {
    EXPECT_TRUE(j["taps"][0].contains(key)) << key;
  }
  EXPECT_GE(j["taps"][0]["impulses"].size(), 1u);
  EXPECT_EQ(j["impulses_per_window"], 5);
  EXPECT_EQ(j["taps"][0]["band_energy_fraction"].size(), 4u);
}

// without matplotlib the command says so and still writes the trace
TEST(TapCliTest, MissingMatplotlibStillWritesTheTrace) {
  const fs::path dir = TempDir("nompl");
  fs::create_directories(dir / "fake" / "matplotlib");
  std::ofstream(dir / "fake" / "matplotlib" / "__init__.py")
      << "raise ImportError('matplotlib hidden by the test')\n";
  const fs::path trace = dir / "tap.csv", plot = dir / "tap.png";
  const CliResult r =
      RunCli("tap --wall 1 --taps 1 --trace " + trace.string() + " --plot " + plot.string(),
             "PYTHONPATH=" + (dir / "fake").string());
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("matplotlib is missing"), std::string::npos) << r.err;
  EXPECT_GT(fs::file_size(trace), 0u);
  EXPECT_FALSE(fs::exists(plot));
  fs::remove_all(dir);
}

TEST(TapCliTest, BadInputGetsAClearError) {
  CliResult r = RunCli("tap --device phantom");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("touch, omni, falcon, omega3, generic"), std::string::npos) << r.err;
  r = RunCli("tap --renderer springy");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("penalty"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("train"), std::string::npos) << r.err;
  r = RunCli("tap --speed 3");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("--speed"), std::string::npos) << r.err;
  r = RunCli("tap --rate 50");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("--rate"), std::string::npos) << r.err;
  // a trace path that cannot be written: named, and nothing half-written left behind
  const fs::path dir = TempDir("badtrace");
  const fs::path bad = dir / "no_such_folder" / "t.csv";
  r = RunCli("tap --taps 1 --trace " + bad.string());
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find(bad.string()), std::string::npos) << r.err;
  EXPECT_TRUE(fs::is_empty(dir));
  fs::remove_all(dir);
}

}  // namespace
}  // namespace rigidtouch::test
