#include "analysis/figures.h"

#include <gtest/gtest.h>
#include <stdlib.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "io/trace_csv.h"

namespace rigidtouch::analysis {
namespace {

namespace fs = std::filesystem;

const std::string kPython = std::string(RIGIDTOUCH_SOURCE_DIR) + "/python/";

class FiguresTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("rigidtouch_figures_test_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // one tap at 1 kHz: penalty ramp plus an impulse train of `impulses` impulses every
  // `spacing` ticks from contact onset
  // (device force clipped to `limit_N` when positive)
  std::string WriteTrace(const std::string& name, int impulses, int spacing,
                         double limit_N = 0.0) const {
    std::vector<TraceSample> samples(200);
    for (int k = 0; k < 200; ++k) {
      TraceSample& s = samples[static_cast<std::size_t>(k)];
      s.step = k;
      s.tap = k < 10 || k >= 190 ? -1 : 0;
      s.time_s = 0.001 * k;
      s.tool_position_m = Vec3(0.0, 0.0, 0.002 - 0.0001 * k);
      s.tool_contacts = k >= 20 && k < 150 ? 1 : 0;
      if (s.tool_contacts > 0) {
        s.penalty_force_N.z() = 0.02 * (k - 20);
        const int since = k - 20;
        if (since % spacing == 0 && since / spacing < impulses) {
          s.impulses = 1;
          s.impulsive_force_N.z() = 3.0 / (since / spacing + 1);
        }
      }
      s.device_force_N = s.penalty_force_N + s.impulsive_force_N;
      if (limit_N > 0.0 && s.device_force_N.z() > limit_N) {
        s.device_force_N.z() = limit_N;
        s.clipped = true;
      }
    }
    const std::string path = (dir_ / name).string();
    io::WriteTraceCsv(path, samples);
    return path;
  }

  static bool IsPng(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    char magic[8] = {};
    in.read(magic, 8);
    return in && std::string(magic + 1, 3) == "PNG";
  }

  fs::path dir_;
};

TEST_F(FiguresTest, PlotTapWritesAPng) {
  const std::string trace = WriteTrace("wall1.csv", 25, 4);
  const std::string out = (dir_ / "tap.png").string();
  const FigureResult r =
      RunPlotScript(kPython + "plot_tap.py", {trace, "--out", out, "--tap", "0"});
  ASSERT_EQ(r.status, FigureStatus::kOk) << r.message << "\n" << r.output;
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_TRUE(IsPng(out));
}

TEST_F(FiguresTest, PlotWallsWritesAPng) {
  const std::string w0 = WriteTrace("wall0.csv", 1, 1);
  const std::string w1 = WriteTrace("wall1.csv", 25, 4);
  const std::string w2 = WriteTrace("wall2.csv", 5, 20);
  const std::string out = (dir_ / "walls.png").string();
  const FigureResult r = RunPlotScript(kPython + "plot_walls.py", {w0, w1, w2, "--out", out});
  ASSERT_EQ(r.status, FigureStatus::kOk) << r.message << "\n" << r.output;
  EXPECT_TRUE(IsPng(out));
}

// What the figures draw as "displayed" is the device's force after its limit, not the requested
// one: the scripts dump what they plotted, and on a trace whose 3 N impulse the 2.5 N limit
// clips, the dumped displayed force is the trace's device force (2.5 N at onset), the requested
// force 3 N, and the limit line is the one given.
TEST_F(FiguresTest, FiguresDrawTheDisplayedForceAndTheLimit) {
  const std::string trace = WriteTrace("clipped.csv", 1, 1, 2.5);
  const std::vector<TraceSample> samples = io::ReadTraceCsv(trace);
  for (const char* script : {"plot_walls.py", "plot_tap.py"}) {
    const std::string out = (dir_ / "f.png").string(), dump = (dir_ / "f.json").string();
    const FigureResult r =
        RunPlotScript(kPython + script, {trace, "--out", out, "--limit", "2.5", "--dump", dump});
    ASSERT_EQ(r.status, FigureStatus::kOk) << script << r.message << "\n" << r.output;
    std::ifstream in(dump);
    const nlohmann::json j = nlohmann::json::parse(in);
    EXPECT_EQ(j["limit_N"], 2.5) << script;
    ASSERT_EQ(j["panels"].size(), 1u) << script;
    const nlohmann::json& p = j["panels"][0];
    // the panel's rows: 5 ms before onset (tick 20) to 150 ms after: ticks 15..170
    const auto displayed = p["displayed_N"].get<std::vector<double>>();
    const auto requested = p["requested_N"].get<std::vector<double>>();
    ASSERT_EQ(displayed.size(), 156u) << script;
    for (std::size_t i = 0; i < displayed.size(); ++i) {
      EXPECT_DOUBLE_EQ(displayed[i], samples[15 + i].device_force_N.z()) << script << " " << i;
    }
    EXPECT_DOUBLE_EQ(displayed[5], 2.5) << script;  // onset: clipped
    EXPECT_DOUBLE_EQ(requested[5], 3.0) << script;
    EXPECT_DOUBLE_EQ(p["displayed_peak_N"], 2.5) << script;
    EXPECT_EQ(p["limit_line_N"], 2.5) << script;  // the line drawn
  }
}

// The figure states the tap metrics' spectral figures as rigidtouch passes them (one
// definition: the table and the JSON give the same) and computes none of its own: the dumped
// repetition is the one given, and without one the figure states none
TEST_F(FiguresTest, TheTapFigureStatesTheRepetitionItIsGiven) {
  const std::string trace = WriteTrace("wall1.csv", 25, 4);
  const std::string out = (dir_ / "f.png").string(), dump = (dir_ / "f.json").string();
  FigureResult r = RunPlotScript(
      kPython + "plot_tap.py",
      {trace, "--out", out, "--dump", dump, "--repetition", "250.0 Hz", "--window-ms", "100",
       "--resolution-hz", "10.0", "--parts-label", "event transient, material wood"});
  ASSERT_EQ(r.status, FigureStatus::kOk) << r.message << "\n" << r.output;
  {
    std::ifstream in(dump);
    const nlohmann::json j = nlohmann::json::parse(in);
    EXPECT_EQ(j["panels"][0]["spectrum"]["transient_repetition"], "250.0 Hz");
  }
  r = RunPlotScript(kPython + "plot_tap.py", {trace, "--out", out, "--dump", dump});
  ASSERT_EQ(r.status, FigureStatus::kOk) << r.message << "\n" << r.output;
  std::ifstream in(dump);
  const nlohmann::json j = nlohmann::json::parse(in);
  EXPECT_TRUE(j["panels"][0]["spectrum"]["transient_repetition"].is_null());
}

// a material's renderer: the figure draws the material's model beside the rendered force, as
// given: Q(t) = A v e^(-B t) sin(2 pi f t) from the onset (to 1e-9 N), named; a value that is no
// number is refused with status 2 and no figure
TEST_F(FiguresTest, TheTapFigureDrawsTheMaterialModelItIsGiven) {
  const std::string trace = WriteTrace("event.csv", 0, 4);
  const std::string out = (dir_ / "m.png").string(), dump = (dir_ / "m.json").string();
  const double a = 14.9, b = 60.2, f = 99.9, v = 0.2;
  FigureResult r = RunPlotScript(kPython + "plot_tap.py",
                                 {trace, "--out", out, "--dump", dump, "--material-model", "wood",
                                  "14.9", "60.2", "99.9", "0.2"});
  ASSERT_EQ(r.status, FigureStatus::kOk) << r.message << "\n" << r.output;
  {
    std::ifstream in(dump);
    const nlohmann::json j = nlohmann::json::parse(in);
    const nlohmann::json& model = j["panels"][0]["material_model"];
    ASSERT_TRUE(model.is_object()) << j.dump().substr(0, 400);
    EXPECT_EQ(model["name"], "wood");
    const auto& t = model["t_ms"];
    const auto& q = model["force_N"];
    ASSERT_EQ(t.size(), q.size());
    ASSERT_GT(t.size(), 100u);
    for (std::size_t k = 0; k < t.size(); k += 50) {
      const double s = t[k].get<double>() / 1e3;
      EXPECT_NEAR(q[k].get<double>(),
                  a * v * std::exp(-b * s) * std::sin(2.0 * std::numbers::pi * f * s), 1e-9)
          << "t = " << s;
    }
  }
  fs::remove(out);
  r = RunPlotScript(kPython + "plot_tap.py", {trace, "--out", out, "--material-model", "wood",
                                              "14.9", "fast", "99.9", "0.2"});
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_FALSE(fs::exists(out));
}

TEST_F(FiguresTest, MissingMatplotlibIsReportedDistinctly) {
  // a matplotlib package that fails to import shadows the real one
  const fs::path shim = dir_ / "shim" / "matplotlib";
  fs::create_directories(shim);
  std::ofstream(shim / "__init__.py") << "raise ImportError('simulated: no matplotlib')\n";
  const char* old = ::getenv("PYTHONPATH");
  const std::string saved = old ? old : "";
  ::setenv("PYTHONPATH", (dir_ / "shim").c_str(), 1);
  const std::string trace = WriteTrace("wall1.csv", 25, 4);
  const std::string out = (dir_ / "tap.png").string();
  const FigureResult r = RunPlotScript(kPython + "plot_tap.py", {trace, "--out", out});
  if (old) {
    ::setenv("PYTHONPATH", saved.c_str(), 1);
  } else {
    ::unsetenv("PYTHONPATH");
  }
  EXPECT_EQ(r.status, FigureStatus::kMissingMatplotlib) << r.output;
  EXPECT_EQ(r.exit_code, 3);
  EXPECT_NE(r.message.find("matplotlib"), std::string::npos) << r.message;
  EXPECT_FALSE(fs::exists(out));
}

TEST_F(FiguresTest, OtherFailuresAreReportedAsFailed) {
  const std::string trace = WriteTrace("wall1.csv", 25, 4);
  const std::string out = (dir_ / "tap.png").string();
  // a tap the trace does not have
  FigureResult r = RunPlotScript(kPython + "plot_tap.py", {trace, "--out", out, "--tap", "7"});
  EXPECT_EQ(r.status, FigureStatus::kFailed);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.message.find("no tap 7"), std::string::npos) << r.message;
  // a trace that does not exist
  r = RunPlotScript(kPython + "plot_tap.py", {(dir_ / "absent.csv").string(), "--out", out});
  EXPECT_EQ(r.status, FigureStatus::kFailed);
  EXPECT_NE(r.output.find("absent.csv"), std::string::npos) << r.output;
  // a script that does not exist
  r = RunPlotScript(kPython + "no_such_script.py", {});
  EXPECT_EQ(r.status, FigureStatus::kFailed);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_FALSE(fs::exists(out));
}

}  // namespace
}  // namespace rigidtouch::analysis
