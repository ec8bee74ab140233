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
  std::string WriteTrace(const std::string& name, int impulses, int spacing) const {
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
