// `rigidtouch material fit` and `material synth` end to end: a synthetic recording fitted into a
// material file that `tap --renderer event|train --material FILE` and a study protocol render;
// bad recordings refused with "rigidtouch: error: FILE:LINE: ...", exit 2 and no material file.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cli/cli_util.h"

namespace rigidtouch::test {
namespace {

namespace fs = std::filesystem;

// wood, acceleration, five speeds at SNR 20 dB
fs::path WoodRecording(const fs::path& dir) {
  const fs::path csv = dir / "wood_taps.csv";
  const CliResult r = RunCli("material synth wood --out " + csv.string() + " --seed 3");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  return csv;
}

TEST(MaterialCliTest, FitsASyntheticRecordingIntoAMaterialTheRenderersTake) {
  const fs::path dir = TempDir("material_fit");
  const fs::path csv = WoodRecording(dir);
  EXPECT_NE(ReadAll(csv).find("# SYNTHETIC"), std::string::npos);
  const fs::path out = dir / "my_wood.json";
  const CliResult r = RunCli("material fit " + csv.string() + " --out " + out.string() + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  const nlohmann::json m = nlohmann::json::parse(ReadAll(out));
  EXPECT_EQ(j["material"], m);
  EXPECT_EQ(m["name"], "my_wood");
  // the preset wood: 15 N/(m/s), 60 1/s, 100 Hz; recovered within 2 %
  EXPECT_NEAR(m["amplitude_Ns_per_m"].get<double>(), 15.0, 0.3);
  EXPECT_NEAR(m["decay_per_s"].get<double>(), 60.0, 1.2);
  EXPECT_NEAR(m["frequency_hz"].get<double>(), 100.0, 2.0);
  EXPECT_EQ(m["fit"]["taps"], 5);
  EXPECT_EQ(m["fit"]["per_tap"].size(), 5u);
  // text output: a table and the line
  const CliResult text = RunCli("material fit " + csv.string() + " --out " + out.string());
  EXPECT_EQ(text.exit_code, 0) << text.err;
  EXPECT_NE(text.out.find("A(v) ="), std::string::npos) << text.out;
  // the figure, when matplotlib is there (the material is written either way)
  const fs::path png = dir / "fit.png";
  const CliResult plot =
      RunCli("material fit " + csv.string() + " --out " + out.string() + " --plot " + png.string());
  EXPECT_EQ(plot.exit_code, 0) << plot.err;
  if (plot.err.find("matplotlib is missing") == std::string::npos) {
    EXPECT_GT(fs::file_size(png), 10000u);
  }
  for (const std::string renderer : {"event", "train"}) {
    const CliResult tap =
        RunCli("tap --renderer " + renderer + " --material " + out.string() + " --taps 1 --json");
    ASSERT_EQ(tap.exit_code, 0) << renderer << ": " << tap.err;
    EXPECT_EQ(nlohmann::json::parse(tap.out)["material"], "my_wood") << renderer;
  }
}

TEST(MaterialCliTest, AStudyProtocolRendersTheFittedMaterial) {
  const fs::path dir = TempDir("material_study");
  const fs::path out = dir / "fitted.json";
  ASSERT_EQ(
      RunCli("material fit " + WoodRecording(dir).string() + " --out " + out.string()).exit_code,
      0);
  const nlohmann::json protocol = {
      {"format", "rigidtouch-study-protocol"},
      {"format_version", 1},
      {"name", "fitted"},
      {"familiarization_taps", 1},
      {"series", 2},
      {"taps_per_series", 1},
      {"conditions",
       {{"event:fitted", {{"renderer", "event"}, {"material", out.string()}}},
        {"train:fitted", {{"renderer", "train"}, {"material", out.string()}}}}},
      {"tests",
       {{{"name", "fitted"},
         {"conditions", {"event:fitted", "train:fitted"}},
         {"keys", {"e", "t"}}}}}};
  std::ofstream(dir / "protocol.json") << protocol.dump(2);
  const CliResult r =
      RunCli("study simulate --protocol " + (dir / "protocol.json").string() +
             " --participants 1 --seed 1 --log-dir " + (dir / "logs").string() + " --json");
  EXPECT_EQ(r.exit_code, 0) << r.err;
}

// each bad recording: exit 2, one line "rigidtouch: error: FILE:LINE: ...", and no material
// file, not even a partial one (an existing file is left as it was)
TEST(MaterialCliTest, BadRecordingsExitTwoNamingFileAndLineAndWriteNoMaterial) {
  const fs::path dir = TempDir("material_bad");
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"empty", ""},
      {"no_header", "0,1\n0.001,2\n"},
      {"wrong_units", "time_ms,force_N\n0,1\n1,2\n"},
      {"not_monotonic", "time_s,force_N\n0,1\n0.002,1\n0.001,1\n"},
      {"nan", "time_s,force_N\n0,1\n0.001,NaN\n"},
      {"one_sample", "time_s,force_N,velocity_mps\n0,1,0.1\n"},
  };
  std::vector<std::pair<std::string, std::string>> all = cases;
  // no tap: noise only, no transient
  std::string flat = "time_s,acceleration_mps2,velocity_mps\n";
  unsigned s = 7;
  for (int i = 0; i < 400; ++i) {
    s = s * 1103515245u + 12345u;
    flat += std::to_string(i * 1e-4) + "," + std::to_string(((s >> 16) % 1000) * 1e-3) + ",-0.2\n";
  }
  all.push_back({"no_tap", flat});
  const std::vector<std::string> expected_line = {
      ":1: ", ":1: ", ":1: ", ":4: ", ":3: ", ":2: ", ":2: "};
  for (std::size_t i = 0; i < all.size(); ++i) {
    const auto& [name, text] = all[i];
    const fs::path csv = dir / (name + ".csv");
    std::ofstream(csv) << text;
    const fs::path out = dir / (name + ".json");
    const CliResult r = RunCli("material fit " + csv.string() + " --out " + out.string());
    EXPECT_EQ(r.exit_code, 2) << name << ": " << r.err;
    EXPECT_EQ(r.err.rfind("rigidtouch: error: " + csv.string() + expected_line[i], 0), 0u)
        << name << ": " << r.err;
    EXPECT_FALSE(fs::exists(out)) << name;
  }
  // an existing material file is not replaced by a failed fit, and no temporary file is left
  const fs::path kept = dir / "kept.json";
  std::ofstream(kept) << "{}";
  EXPECT_EQ(
      RunCli("material fit " + (dir / "nan.csv").string() + " --out " + kept.string()).exit_code,
      2);
  EXPECT_EQ(ReadAll(kept), "{}");
  int files = 0;
  for (const auto& e : fs::directory_iterator(dir)) files += e.path().extension() == ".json";
  EXPECT_EQ(files, 1);
}

TEST(MaterialCliTest, AClippedRecordingIsRefusedWithTheReason) {
  const fs::path dir = TempDir("material_clip");
  const fs::path csv = dir / "clipped.csv";
  ASSERT_EQ(RunCli("material synth aluminium --clip-fraction 0.01 --out " + csv.string()).exit_code,
            0);
  const fs::path out = dir / "m.json";
  const CliResult r = RunCli("material fit " + csv.string() + " --out " + out.string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("tap 0: clipped (saturated)"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out));
}

TEST(MaterialCliTest, WarnsWhenTheDeviceCannotDisplayTheFrequency) {
  const fs::path dir = TempDir("material_warn");
  const fs::path csv = dir / "alu.csv";
  ASSERT_EQ(RunCli("material synth aluminium --out " + csv.string()).exit_code, 0);
  const CliResult r = RunCli("material fit " + csv.string() + " --out " +
                             (dir / "alu.json").string() + " --device omni --rate 500");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("rigidtouch: warning: the fitted frequency"), std::string::npos) << r.err;
  const CliResult ok = RunCli("material fit " + csv.string() + " --out " +
                              (dir / "alu.json").string() + " --device omni --rate 1000");
  EXPECT_EQ(ok.err.find("the fitted frequency"), std::string::npos) << ok.err;
}

// the shipped synthetic recordings are what `material synth` writes (so their documented model is
// the one behind them), and each fits back to its preset within 2 %
TEST(MaterialCliTest, ShippedRecordingsAreTheGeneratorsOutput) {
  const fs::path dir = TempDir("material_shipped");
  const std::vector<std::vector<double>> presets = {{10, 40, 30}, {15, 60, 100}, {25, 90, 300}};
  const std::vector<std::string> names = {"rubber", "wood", "aluminium"};
  for (std::size_t i = 0; i < names.size(); ++i) {
    const fs::path shipped =
        fs::path(RIGIDTOUCH_SOURCE_DIR) / "materials" / "synthetic" / (names[i] + ".csv");
    const fs::path made = dir / (names[i] + ".csv");
    ASSERT_EQ(RunCli("material synth " + names[i] + " --taps-per-speed 3 --out " + made.string())
                  .exit_code,
              0);
    EXPECT_EQ(ReadAll(made), ReadAll(shipped)) << names[i];
    const fs::path out = dir / (names[i] + ".json");
    ASSERT_EQ(RunCli("material fit " + shipped.string() + " --out " + out.string()).exit_code, 0);
    const nlohmann::json m = nlohmann::json::parse(ReadAll(out));
    const std::vector<std::string> keys = {"amplitude_Ns_per_m", "decay_per_s", "frequency_hz"};
    for (std::size_t k = 0; k < keys.size(); ++k) {
      EXPECT_NEAR(m[keys[k]].get<double>(), presets[i][k], 0.02 * presets[i][k])
          << names[i] << " " << keys[k];
    }
  }
}

}  // namespace
}  // namespace rigidtouch::test
