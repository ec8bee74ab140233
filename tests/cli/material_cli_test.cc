// `rigidtouch material fit` and `material synth` end to end: a synthetic recording fitted into a
// material file that `tap --renderer event|train --material FILE` and a study protocol render;
// bad recordings refused with "rigidtouch: error: FILE:LINE: ...", exit 2 and no material file.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "base/text.h"
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

// a device spec like the ideal device (no force limit, a 1 um encoder, no delay) with the
// apparent mass `mass_kg`
fs::path DeviceWithMass(const fs::path& dir, const std::string& name, double mass_kg) {
  const fs::path path = dir / (name + ".json");
  std::ofstream(path) << nlohmann::json{
      {"name", name},
      {"max_force_N", 0},
      {"max_stiffness_N_per_m", 0},
      {"max_damping_Ns_per_m", 0},
      {"apparent_mass_kg", mass_kg},
      {"encoder_resolution_m", 1e-6},
      {"velocity_filter_hz", 100},
      {"delay_ticks", 0}}.dump();
  return path;
}

struct EventTapRun {
  CliResult cli;
  nlohmann::json json;
  std::vector<double> transient;  // the impulsive force along the wall's normal from onset [N]
};

// `tap --renderer event --material M --device D --taps 1 --json --trace`, on a wall the tool
// stays on for the whole transient (as tests/render/event_test.cc)
EventTapRun EventTapCli(const fs::path& dir, const std::string& material, const fs::path& device) {
  const fs::path trace = dir / ("trace_" + device.stem().string() + ".csv");
  EventTapRun r;
  r.cli =
      RunCli("tap --renderer event --material " + material + " --device " + device.string() +
             " --stiffness 400 --damping 10 --speed 0.2 --taps 1 --json --trace " + trace.string());
  if (r.cli.exit_code != 0) return r;
  r.json = nlohmann::json::parse(r.cli.out);
  std::istringstream csv(ReadAll(trace));
  std::string line;
  std::getline(csv, line);
  std::vector<std::string> names;
  std::istringstream header(line);
  for (std::string name; std::getline(header, name, ',');) names.push_back(name);
  const auto column = [&](const std::string& name) {
    return static_cast<std::size_t>(std::find(names.begin(), names.end(), name) - names.begin());
  };
  const std::size_t contacts = column("tool_contacts");
  const std::size_t f[3] = {column("impulsive_fx_N"), column("impulsive_fy_N"),
                            column("impulsive_fz_N")};
  const std::size_t n[3] = {column("wall_nx"), column("wall_ny"), column("wall_nz")};
  EXPECT_LT(std::max({contacts, f[0], f[2], n[0], n[2]}), names.size()) << line;
  bool on = false;
  while (std::getline(csv, line)) {
    std::vector<double> v;
    std::istringstream row(line);
    for (std::string cell; std::getline(row, cell, ',');) v.push_back(std::stod(cell));
    if (v.size() != names.size()) break;
    on = on || v[contacts] > 0.0;
    if (!on) continue;
    r.transient.push_back(v[f[0]] * v[n[0]] + v[f[1]] * v[n[1]] + v[f[2]] * v[n[2]]);
  }
  return r;
}

// the transient's first peak: its largest value over the first half period 1 / (2 f)
double FirstPeak(const std::vector<double>& transient, double h, double frequency_hz) {
  double peak = 0.0;
  for (std::size_t k = 0; k < transient.size() && (k + 0.5) * h < 0.5 / frequency_hz; ++k) {
    peak = std::max(peak, transient[k]);
  }
  return peak;
}

// a material fitted from acceleration on the Touch (0.045 + 0.554 kg) and rendered on a device
// of apparent mass 0.645 kg (effective 1.199 kg, about twice): the force is the recorded
// acceleration times the rendering device's mass, A_acc m v e^(-B t) sin(2 pi f t), not the
// file's force; on a device of the Touch's mass it is the file's own amplitude, and a force
// material is the same on both
TEST(MaterialCliTest, AnAccelerationMaterialRendersWithTheDevicesEffectiveMass) {
  const fs::path dir = TempDir("material_device");
  const fs::path out = dir / "my_wood.json";
  ASSERT_EQ(
      RunCli("material fit " + WoodRecording(dir).string() + " --out " + out.string()).exit_code,
      0);
  const nlohmann::json file = nlohmann::json::parse(ReadAll(out));
  const double a_acc = file["amplitude_mps2_per_mps"].get<double>();
  const double m_fit = file["effective_mass_kg"].get<double>();
  const double decay = file["decay_per_s"].get<double>(), f = file["frequency_hz"].get<double>();
  ASSERT_DOUBLE_EQ(m_fit, 0.045 + 0.554);
  const double m_other = 0.645 + 0.554;
  const fs::path heavy = DeviceWithMass(dir, "heavy", 0.645);
  const fs::path light = DeviceWithMass(dir, "touch_mass", 0.045);

  const EventTapRun other = EventTapCli(dir, out.string(), heavy);
  ASSERT_EQ(other.cli.exit_code, 0) << other.cli.err;
  // the JSON gives the amplitude as rendered and the mass it was converted with
  EXPECT_NEAR(other.json["material_amplitude_Ns_per_m"].get<double>(), a_acc * m_other,
              1e-12 * a_acc * m_other);
  EXPECT_DOUBLE_EQ(other.json["material_effective_mass_kg"].get<double>(), m_other);
  // one note naming the material, both masses and the rendered amplitude
  const std::size_t note = other.cli.err.find("rigidtouch: note:");
  EXPECT_NE(note, std::string::npos) << other.cli.err;
  EXPECT_EQ(other.cli.err.find("rigidtouch: note:", note + 1), std::string::npos) << other.cli.err;
  for (const std::string& part :
       {std::string("rigidtouch: note: material 'my_wood'"), std::string("0.599 kg"),
        std::string("1.199 kg"), text::FormatNumber(a_acc * m_other) + " N/(m/s)"}) {
    EXPECT_NE(other.cli.err.find(part), std::string::npos) << part << "\n" << other.cli.err;
  }
  // the first peak against the closed form at the approach speed the tap metrics report (the
  // device's estimate at onset, the speed the renderer scales by), tick by tick at
  // t = (k + 1/2) h: within 1e-6 relative (measured 1e-13)
  const double h = 0.001;
  const double v = other.json["taps"][0]["approach_speed_mps"].get<double>();
  std::vector<double> closed;
  for (std::size_t k = 0; k < 20; ++k) {
    const double t = (static_cast<double>(k) + 0.5) * h;
    closed.push_back(a_acc * m_other * v * std::exp(-decay * t) *
                     std::sin(2.0 * std::numbers::pi * f * t));
  }
  const double peak_other = FirstPeak(other.transient, h, f);
  EXPECT_NEAR(peak_other, FirstPeak(closed, h, f), 1e-6 * FirstPeak(closed, h, f));

  // on a device of the fit's mass: the file's amplitude to the last bit, no note; the first
  // peak per approach speed is m_other / m_fit times smaller (within 1e-6 relative, measured
  // 2e-13)
  const EventTapRun fit = EventTapCli(dir, out.string(), light);
  ASSERT_EQ(fit.cli.exit_code, 0) << fit.cli.err;
  EXPECT_EQ(fit.json["material_amplitude_Ns_per_m"].get<double>(),
            file["amplitude_Ns_per_m"].get<double>());
  EXPECT_EQ(fit.cli.err.find("note:"), std::string::npos) << fit.cli.err;
  const double ratio = (peak_other / v) / (FirstPeak(fit.transient, h, f) /
                                           fit.json["taps"][0]["approach_speed_mps"].get<double>());
  EXPECT_NEAR(ratio, m_other / m_fit, 1e-6 * m_other / m_fit);

  // a force material with the same numbers: the same amplitude on both devices, no note
  const fs::path force = dir / "force_wood.json";
  std::ofstream(force) << nlohmann::json{
      {"name", "force_wood"},
      {"amplitude_Ns_per_m", file["amplitude_Ns_per_m"]},
      {"decay_per_s", decay},
      {"frequency_hz", f}}.dump();
  for (const fs::path& device : {heavy, light}) {
    const EventTapRun r = EventTapCli(dir, force.string(), device);
    ASSERT_EQ(r.cli.exit_code, 0) << r.cli.err;
    EXPECT_EQ(r.json["material_amplitude_Ns_per_m"].get<double>(),
              file["amplitude_Ns_per_m"].get<double>())
        << device;
    EXPECT_TRUE(r.json["material_effective_mass_kg"].is_null());
    EXPECT_EQ(r.cli.err.find("note:"), std::string::npos) << r.cli.err;
  }
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
