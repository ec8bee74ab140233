#include "io/trace_csv.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include "rigidtouch/types.h"

namespace rigidtouch::io {
namespace {

namespace fs = std::filesystem;

// a fresh directory per test, removed afterwards
class TraceCsvTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("rigidtouch_trace_csv_test_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::vector<std::string> DirectoryEntries() const {
    std::vector<std::string> names;
    for (const auto& entry : fs::directory_iterator(dir_)) {
      names.push_back(entry.path().filename().string());
    }
    return names;
  }

  fs::path dir_;
};

std::vector<TraceSample> TraceSamples() {
  std::vector<TraceSample> samples(5);
  for (int k = 0; k < 5; ++k) {
    TraceSample& s = samples[static_cast<std::size_t>(k)];
    s.step = 1234567890123LL + k;
    s.tap = k - 1;
    s.time_s = 0.001 * k + 1.0 / 3.0;
    s.tool_position_m = Vec3(0.1 / 7.0, -2.5e-7 * k, 1e-300);
    s.tool_velocity_mps = Vec3(-0.2, 1e-17, 3.0 * k);
    s.penalty_force_N = Vec3(0.0, -0.0, 2.0 / 3.0);
    s.impulsive_force_N = Vec3(1e5, 1.0 / 9.0, -4.4);
    s.device_force_N = Vec3(3.3, 0.0, 0.1 + 0.2);
    s.hand_force_N = Vec3(-1.0, 2.0, -3.0) / 11.0;
    s.wall_normal = Vec3(0.0, 0.6, 0.8);
    s.penetration_m = 1.5e-4 * k;
    s.tool_contacts = k % 3;
    s.impulses = k == 2 ? 1 : 0;
    s.kinetic_energy_before_J = 0.0123 / (k + 1);
    s.kinetic_energy_after_J = 0.0;
    s.clipped = k == 3;
  }
  return samples;
}

TEST_F(TraceCsvTest, RoundTripIsExact) {
  const std::string path = (dir_ / "trace.csv").string();
  const std::vector<TraceSample> written = TraceSamples();
  WriteTraceCsv(path, written);
  const std::vector<TraceSample> read = ReadTraceCsv(path);
  ASSERT_EQ(read.size(), written.size());
  for (std::size_t k = 0; k < read.size(); ++k) {
    // shortest round-trip formatting: every double comes back bit for bit
    EXPECT_EQ(read[k].step, written[k].step);
    EXPECT_EQ(read[k].tap, written[k].tap);
    EXPECT_EQ(read[k].time_s, written[k].time_s);
    EXPECT_EQ(read[k].tool_position_m, written[k].tool_position_m);
    EXPECT_EQ(read[k].tool_velocity_mps, written[k].tool_velocity_mps);
    EXPECT_EQ(read[k].penalty_force_N, written[k].penalty_force_N);
    EXPECT_EQ(read[k].impulsive_force_N, written[k].impulsive_force_N);
    EXPECT_EQ(read[k].device_force_N, written[k].device_force_N);
    EXPECT_EQ(read[k].hand_force_N, written[k].hand_force_N);
    EXPECT_EQ(read[k].wall_normal, written[k].wall_normal);
    EXPECT_EQ(read[k].penetration_m, written[k].penetration_m);
    EXPECT_EQ(read[k].tool_contacts, written[k].tool_contacts);
    EXPECT_EQ(read[k].impulses, written[k].impulses);
    EXPECT_EQ(read[k].kinetic_energy_before_J, written[k].kinetic_energy_before_J);
    EXPECT_EQ(read[k].kinetic_energy_after_J, written[k].kinetic_energy_after_J);
    EXPECT_EQ(read[k].clipped, written[k].clipped);
  }
  // only the trace itself is left: the temporary file was renamed
  EXPECT_EQ(DirectoryEntries(), std::vector<std::string>{"trace.csv"});
}

TEST_F(TraceCsvTest, HeaderNamesColumnsWithUnits) {
  const std::string path = (dir_ / "trace.csv").string();
  WriteTraceCsv(path, TraceSamples());
  std::ifstream in(path);
  std::string header;
  std::getline(in, header);
  EXPECT_EQ(header,
            "time_s,tool_x_m,tool_y_m,tool_z_m,tool_vx_mps,tool_vy_mps,tool_vz_mps,"
            "penalty_fx_N,penalty_fy_N,penalty_fz_N,impulsive_fx_N,impulsive_fy_N,"
            "impulsive_fz_N,device_fx_N,device_fy_N,device_fz_N,hand_fx_N,hand_fy_N,hand_fz_N,"
            "wall_nx,wall_ny,wall_nz,penetration_m,tool_contacts,impulses,"
            "kinetic_energy_before_J,kinetic_energy_after_J,clipped,tap,step");
  EXPECT_EQ(TraceColumns().size(), 30u);
  int rows = 0;
  for (std::string line; std::getline(in, line);) ++rows;
  EXPECT_EQ(rows, 5);
}

TEST_F(TraceCsvTest, OverwritesAnExistingTrace) {
  const std::string path = (dir_ / "trace.csv").string();
  WriteTraceCsv(path, TraceSamples());
  WriteTraceCsv(path, std::vector<TraceSample>(2));
  EXPECT_EQ(ReadTraceCsv(path).size(), 2u);
}

TEST_F(TraceCsvTest, MissingDirectoryNamesThePathAndLeavesNothing) {
  const fs::path missing_dir = dir_ / "no_such_dir";
  const std::string path = (missing_dir / "trace.csv").string();
  try {
    WriteTraceCsv(path, TraceSamples());
    FAIL() << "expected rigidtouch::Error";
  } catch (const Error& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("'" + path + "'"), std::string::npos) << message;
    EXPECT_NE(message.find("No such file or directory"), std::string::npos) << message;
  }
  EXPECT_FALSE(fs::exists(missing_dir));
  EXPECT_TRUE(DirectoryEntries().empty());
}

TEST_F(TraceCsvTest, FailedRenameRemovesTheTemporaryFile) {
  // the target is an existing non-empty directory: the temporary file is written, the rename
  // fails, and the temporary file must be removed again
  const fs::path target = dir_ / "occupied";
  fs::create_directories(target / "child");
  try {
    WriteTraceCsv(target.string(), TraceSamples());
    FAIL() << "expected rigidtouch::Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(target.string()), std::string::npos) << e.what();
  }
  EXPECT_EQ(DirectoryEntries(), std::vector<std::string>{"occupied"});
  EXPECT_TRUE(fs::is_directory(target / "child"));
}

TEST_F(TraceCsvTest, ReadErrorsNameFileLineAndColumn) {
  const std::string missing = (dir_ / "absent.csv").string();
  try {
    ReadTraceCsv(missing);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(missing), std::string::npos) << e.what();
  }

  const std::string path = (dir_ / "bad.csv").string();
  WriteTraceCsv(path, TraceSamples());
  std::string text;
  {
    std::ifstream in(path);
    std::getline(in, text);
  }
  {
    // header without the penetration column
    std::ofstream out(path);
    out << "time_s,tool_x_m\n0,0\n";
  }
  try {
    ReadTraceCsv(path);
    FAIL();
  } catch (const Error& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("missing columns"), std::string::npos) << message;
    EXPECT_NE(message.find("penetration_m"), std::string::npos) << message;
  }
  {
    // full header, a bad value on line 3, column time_s
    std::ofstream out(path);
    out << text << "\n";
    std::string row;
    for (std::size_t i = 0; i < TraceColumns().size(); ++i) row += i ? ",0" : "0";
    out << row << "\n";
    out << "abc" << row.substr(1) << "\n";
  }
  try {
    ReadTraceCsv(path);
    FAIL();
  } catch (const Error& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("line 3"), std::string::npos) << message;
    EXPECT_NE(message.find("'time_s'"), std::string::npos) << message;
    EXPECT_NE(message.find("'abc'"), std::string::npos) << message;
  }
}

TEST_F(TraceCsvTest, NonFiniteValuesRoundTrip) {
  const std::string path = (dir_ / "trace.csv").string();
  std::vector<TraceSample> samples(1);
  samples[0].kinetic_energy_before_J = std::numeric_limits<double>::infinity();
  samples[0].penetration_m = std::numeric_limits<double>::quiet_NaN();
  WriteTraceCsv(path, samples);
  const std::vector<TraceSample> read = ReadTraceCsv(path);
  ASSERT_EQ(read.size(), 1u);
  EXPECT_EQ(read[0].kinetic_energy_before_J, std::numeric_limits<double>::infinity());
  EXPECT_TRUE(std::isnan(read[0].penetration_m));
}

}  // namespace
}  // namespace rigidtouch::io
