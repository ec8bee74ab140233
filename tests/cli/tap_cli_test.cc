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
  // --compare-walls is the set penalty,wall0,wall1,wall2
  ASSERT_EQ(j["renderers"].size(), 4u);
  const char* names[] = {"penalty", "wall0", "wall1", "wall2"};
  for (int i = 0; i < 4; ++i) {
    const auto& e = j["renderers"][i];
    EXPECT_EQ(e["name"], names[i]);
    EXPECT_EQ(e["taps"].size(), 1u);
    EXPECT_GT(fs::file_size(e["trace"].get<std::string>()), 0u);
  }
  // impulse counts are checked on an ideal device in tap_experiment_test; here the Touch clips
  // and its encoder makes taps bounce, so only the structure is fixed
  const auto& wall1 = j["renderers"][2];
  EXPECT_GE(wall1["taps"][0]["impulses"].size(), 1u);
  EXPECT_EQ(wall1["frequency_hz"], 250.0);
  EXPECT_EQ(wall1["impulses_per_window"], 25);
  EXPECT_EQ(j["renderers"][3]["impulses_per_window"], 5);
  EXPECT_EQ(j["renderers"][0]["taps"][0]["impulses"].size(), 0u);
  // the table labels each column with its statistic over the taps
  const std::string table = ReadAll(dir / "walls.md");
  EXPECT_NE(table.find("bounces, sum over taps"), std::string::npos) << table;
  EXPECT_NE(table.find("rate hardness [N/m], mean/tap"), std::string::npos) << table;
  EXPECT_EQ(table.find("Means over"), std::string::npos) << table;
  // the figures: non-empty PNGs (the signature's first bytes), one per renderer and the set's
  for (const char* png :
       {"walls.png", "penalty_tap.png", "wall0_tap.png", "wall1_tap.png", "wall2_tap.png"}) {
    ASSERT_TRUE(fs::exists(dir / png)) << png << "\n" << r.err;
    EXPECT_GT(fs::file_size(dir / png), 1000u) << png;
    EXPECT_EQ(ReadAll(dir / png).substr(1, 3), "PNG") << png;
  }
  fs::remove_all(dir);
}

// --compare LIST: one entry per spec, in order, with the per-tap fields of `tap --json`; the
// renderers keep the flags' parameters (here the train's frequency)
TEST(TapCliTest, CompareRunsAnySetOfRenderers) {
  const fs::path dir = TempDir("compare");
  const CliResult one = RunCli("tap --renderer train --frequency 100 --taps 1 --json");
  ASSERT_EQ(one.exit_code, 0) << one.err;
  const auto single = nlohmann::json::parse(one.out);
  CliResult r = RunCli("tap --compare impulse,train --frequency 100 --taps 1 --json --out-dir " +
                       dir.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  ASSERT_EQ(j["renderers"].size(), 2u);
  EXPECT_EQ(j["renderers"][0]["name"], "impulse");
  EXPECT_EQ(j["renderers"][0]["renderer"], "impulse");
  const auto& train = j["renderers"][1];
  EXPECT_EQ(train["name"], "train");
  EXPECT_EQ(train["frequency_hz"], 100.0);
  // the same metrics as the single run, key for key and value for value
  ASSERT_EQ(train["taps"].size(), 1u);
  for (const auto& [key, value] : single["taps"][0].items()) {
    EXPECT_EQ(train["taps"][0][key], value) << key;
  }
  EXPECT_TRUE(fs::exists(dir / "compare.md"));
  EXPECT_TRUE(fs::exists(dir / "compare.png"));
  EXPECT_TRUE(fs::exists(dir / "train.csv"));
  EXPECT_TRUE(fs::exists(dir / "impulse_tap.png"));
  // bad specs: exit 2 with the reason, before any run
  r = RunCli("tap --compare penalty,springy --out-dir " + (dir / "bad").string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("rigidtouch: error: unknown renderer 'springy'"), std::string::npos)
      << r.err;
  r = RunCli("tap --compare penalty,train:balsa --out-dir " + (dir / "bad").string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("unknown material 'balsa'"), std::string::npos) << r.err;
  r = RunCli("tap --compare penalty --compare-walls --out-dir " + (dir / "bad").string());
  EXPECT_EQ(r.exit_code, 2);
  // a wall fixes f: a frequency the user wrote is refused, not dropped
  r = RunCli("tap --compare train,wall1 --frequency 100 --out-dir " + (dir / "bad").string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("render.frequency_hz (set by --frequency) has no effect here"),
            std::string::npos)
      << r.err;
  EXPECT_FALSE(fs::exists(dir / "bad"));
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
       {"impulses", "peak_force_N", "peak_requested_force_N", "rate_hardness_N_per_m",
        "extended_rate_hardness_N_per_m", "max_penetration_m", "bounces", "energy_to_user_J",
        "band_energy_fraction", "spectrum_window_s", "spectrum_resolution_hz",
        "transient_repetition_hz", "transient_periodicity", "transient_peak_to_mean",
        "transient_band_energy_fraction", "transient_power_ratio", "force_clipped"}) {
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
  // an output folder that cannot be created (in /proc) is an error naming it, not an internal
  // one, found before the run (/proc takes no new file)
  r = RunCli("tap --compare-walls --taps 1 --out-dir /proc/nope");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("rigidtouch: error: cannot write output folder (--out-dir) '/proc/nope': "
                       "folder '/proc' takes no new file"),
            std::string::npos)
      << r.err;
  // --out-dir without a comparison would be ignored: refused
  r = RunCli("tap --taps 1 --out-dir " + (dir / "o").string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--out-dir is the output folder of --compare"), std::string::npos) << r.err;
  // a figure in a missing folder: the figure is named, not the temporary trace beside it
  const fs::path figure = dir / "no_such_folder" / "t.png";
  r = RunCli("tap --taps 1 --plot " + figure.string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("rigidtouch: error: cannot write figure '" + figure.string() + "'"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(r.err.find(".trace.csv"), std::string::npos) << r.err;
  EXPECT_TRUE(fs::is_empty(dir));
  fs::remove_all(dir);
}

// --seed takes 0 to 2^64 - 1 in decimal: a negative or larger seed was wrapped or saturated
// tap's device is simulated: a wall stiffer or more damped than the preset can display is
// rendered (a Z-width map explores past the limits), and said so, where serve refuses it
TEST(TapCliTest, AWallTheDeviceCannotDisplayIsRunAndSaidSo) {
  const CliResult stiff = RunCli("tap --taps 1 --stiffness 1e5 --json");
  ASSERT_EQ(stiff.exit_code, 0) << stiff.err;
  const auto j = nlohmann::json::parse(stiff.out);
  EXPECT_EQ(j["stiffness_N_per_m"].get<double>(), 1e5);
  EXPECT_FALSE(j["displayable"].get<bool>());
  const CliResult damped = RunCli("tap --taps 1 --damping 100");
  ASSERT_EQ(damped.exit_code, 0) << damped.err;
  EXPECT_NE(damped.out.find("note: the rendered stiffness or damping is above what the touch "
                            "can display"),
            std::string::npos)
      << damped.out;
  const CliResult fine = RunCli("tap --taps 1 --json");
  ASSERT_EQ(fine.exit_code, 0) << fine.err;
  EXPECT_TRUE(nlohmann::json::parse(fine.out)["displayable"].get<bool>());
  const CliResult served = RunCli("serve --duration 0.01 --stiffness 1e5");
  EXPECT_EQ(served.exit_code, 2) << served.err;
  EXPECT_NE(served.err.find("is above what the device can display"), std::string::npos)
      << served.err;
}

// a figure format matplotlib cannot write is refused before the run (it failed after it, with
// a Python traceback); the extension's case does not matter
TEST(TapCliTest, APlotFormatMatplotlibCannotWriteIsRefusedBeforeTheRun) {
  const std::filesystem::path dir = TempDir("plotformat");
  const std::string txt = (dir / "q.txt").string();
  const CliResult r = RunCli("tap --taps 1 --plot " + txt);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("rigidtouch: error: --plot '" + txt +
                       "': the figure's format comes from its extension"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(r.err.find("Traceback"), std::string::npos) << r.err;
  EXPECT_TRUE(std::filesystem::is_empty(dir)) << "no trace or figure written";
}

TEST(TapCliTest, SeedsOutsideTheirRangeAreRefused) {
  // out of range, and (a hexadecimal or octal reading is not guessed) not decimal digits
  const std::pair<const char*, const char*> refused[] = {
      {"-1", "is out of range"},
      {"18446744073709551616", "is out of range"},
      {"99999999999999999999999", "is out of range"},
      {"0x10", "is not a whole number"},
      {"1.5", "is not a whole number"},
      {"seven", "is not a whole number"}};
  for (const auto& [seed, why] : refused) {
    const CliResult r = RunCli(std::string("tap --taps 1 --seed ") + seed);
    EXPECT_EQ(r.exit_code, 2) << seed << "\n" << r.err;
    EXPECT_NE(r.err.find(std::string("rigidtouch: error: --seed: ") + seed + " " + why +
                         ": valid 0 to 18446744073709551615"),
              std::string::npos)
        << seed << "\n"
        << r.err;
  }
  // the ends of the range run, and a seed is the same seed however it is written
  for (const std::string seed : {"0", "18446744073709551615"}) {
    const CliResult r = RunCli("tap --taps 1 --spread 0.2 --json --seed " + seed);
    EXPECT_EQ(r.exit_code, 0) << seed << "\n" << r.err;
  }
  const CliResult ten = RunCli("tap --taps 2 --spread 0.2 --json --seed 10");
  const CliResult padded = RunCli("tap --taps 2 --spread 0.2 --json --seed 010");
  ASSERT_EQ(ten.exit_code, 0) << ten.err;
  ASSERT_EQ(padded.exit_code, 0) << padded.err;
  EXPECT_TRUE(ten.out == padded.out) << "--seed 010 did not run as --seed 10";
}

}  // namespace
}  // namespace rigidtouch::test
