// Record files: what is written reads back bit for bit (the replay depends on it), a file that is
// not a record or is damaged is refused naming the line and column, and an uncommitted record
// leaves no file behind.
#include "io/device_record.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numbers>
#include <sstream>
#include <string>
#include <system_error>
#include <vector>

namespace rigidtouch::io {
namespace {

namespace fs = std::filesystem;

// this process's scratch folder, removed when the tests end
fs::path Dir() {
  struct Scratch {
    fs::path path = fs::temp_directory_path() / ("rigidtouch_record_" + std::to_string(::getpid()));
    ~Scratch() {
      std::error_code ignored;
      fs::remove_all(path, ignored);
    }
  };
  static const Scratch scratch;
  fs::create_directories(scratch.path);
  return scratch.path;
}

std::vector<RecordSample> RecordSamples() {
  std::vector<RecordSample> out;
  for (int k = 0; k < 5; ++k) {
    RecordSample r;
    r.tick = k;
    r.tap = k % 2 == 0 ? -1 : 3;
    r.state.sequence = 1000000000000ull + static_cast<std::uint64_t>(k);
    r.state.time_s = 0.1 * k + 1e-17;  // doubles that a fixed number of digits would round
    r.state.valid = k != 2;
    r.state.fresh = k != 3;
    r.state.buttons = 0xffffffffu;
    r.state.position_m = Vec3(1.0 / 3.0, -0.0, 5e-324);  // -0 and a subnormal survive
    r.state.orientation = Quat(std::sqrt(0.5), 0.0, std::sqrt(0.5), 0.0);
    r.state.velocity_mps = Vec3(-1e300, 2.0 / 7.0, std::nextafter(1.0, 2.0));
    r.state.angular_velocity_radps = Vec3(0.1, 0.2, 0.3);
    r.command.sequence = r.state.sequence;
    r.command.force_N = Vec3(0.0, 0.0, 3.3 * k / 7.0);
    r.command.torque_Nm = Vec3(1e-9, 0.0, 0.0);
    r.command.penalty_force_N = Vec3(0.0, 0.0, 1.0 / 9.0);
    r.command.impulsive_force_N = Vec3(0.0, 0.0, 123.456789012345678);
    r.command.clipped = k == 4;
    r.command.safe_fallback = k == 1;
    r.hand_force_N = Vec3(-0.5, 0.25, std::numbers::pi);
    out.push_back(r);
  }
  // a state a faulty device reported: kept as it came, the loop decides it is invalid
  out[2].state.position_m.x() = std::numeric_limits<double>::quiet_NaN();
  out[2].state.velocity_mps.y() = -std::numeric_limits<double>::infinity();
  return out;
}

bool SameBits(double a, double b) {
  if (std::isnan(a)) return std::isnan(b);
  return std::signbit(a) == std::signbit(b) && a == b;
}

void ExpectSameBits(const Vec3& a, const Vec3& b) {
  for (int i = 0; i < 3; ++i) EXPECT_TRUE(SameBits(a[i], b[i])) << a[i] << " vs " << b[i];
}

TEST(DeviceRecord, ReadsBackWhatWasWrittenBitForBit) {
  const std::string path = (Dir() / "rec.csv").string();
  const std::vector<RecordSample> in = RecordSamples();
  {
    RecordFileWriter w(path, 1234.5);
    w.Append(std::span(in).first(2));
    w.Append(std::span(in).subspan(2));
    w.Commit();
  }
  const Record r = ReadRecord(path);
  EXPECT_EQ(r.rate_hz, 1234.5);
  ASSERT_EQ(r.samples.size(), in.size());
  for (std::size_t k = 0; k < in.size(); ++k) {
    const RecordSample& a = in[k];
    const RecordSample& b = r.samples[k];
    EXPECT_EQ(a.tick, b.tick);
    EXPECT_EQ(a.tap, b.tap);
    EXPECT_EQ(a.state.sequence, b.state.sequence);
    EXPECT_TRUE(SameBits(a.state.time_s, b.state.time_s));
    EXPECT_EQ(a.state.valid, b.state.valid);
    EXPECT_EQ(a.state.fresh, b.state.fresh);
    EXPECT_EQ(a.state.buttons, b.state.buttons);
    ExpectSameBits(a.state.position_m, b.state.position_m);
    EXPECT_EQ(a.state.orientation.coeffs(), b.state.orientation.coeffs());
    ExpectSameBits(a.state.velocity_mps, b.state.velocity_mps);
    ExpectSameBits(a.state.angular_velocity_radps, b.state.angular_velocity_radps);
    EXPECT_EQ(a.command.sequence, b.command.sequence);
    ExpectSameBits(a.command.force_N, b.command.force_N);
    ExpectSameBits(a.command.torque_Nm, b.command.torque_Nm);
    ExpectSameBits(a.command.penalty_force_N, b.command.penalty_force_N);
    ExpectSameBits(a.command.impulsive_force_N, b.command.impulsive_force_N);
    EXPECT_EQ(a.command.clipped, b.command.clipped);
    EXPECT_EQ(a.command.safe_fallback, b.command.safe_fallback);
    ExpectSameBits(a.hand_force_N, b.hand_force_N);
  }
  fs::remove(path);
}

TEST(DeviceRecord, UncommittedRecordLeavesNoFile) {
  const fs::path dir = Dir() / "uncommitted";
  fs::remove_all(dir);
  fs::create_directories(dir);
  {
    RecordFileWriter w((dir / "rec.csv").string(), 1000.0);
    const std::vector<RecordSample> in = RecordSamples();
    w.Append(in);
  }  // e.g. the session failed before Commit
  EXPECT_TRUE(fs::is_empty(dir));
  fs::remove_all(dir);
}

TEST(DeviceRecord, BadPathIsRefusedBeforeTheSession) {
  EXPECT_THROW(RecordFileWriter("/nonexistent-folder/rec.csv", 1000.0), Error);
}

std::string Written() {
  const std::string path = (Dir() / "good.csv").string();
  RecordFileWriter w(path, 1000.0);
  w.Append(RecordSamples());
  w.Commit();
  std::ifstream f(path);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

std::string RecordErrorOf(const std::string& text) {
  const std::string path = (Dir() / "bad.csv").string();
  std::ofstream(path) << text;
  try {
    ReadRecord(path);
  } catch (const Error& e) {
    return e.what();
  }
  return "no error";
}

std::string Replace(std::string s, const std::string& from, const std::string& to) {
  const auto at = s.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return s.replace(at, from.size(), to);
}

TEST(DeviceRecord, DamagedFilesAreRefusedNamingLineAndColumn) {
  const std::string good = Written();
  EXPECT_NE(RecordErrorOf("tick,tap\n").find("line 1: the first line is not"), std::string::npos);
  EXPECT_NE(RecordErrorOf(Replace(good, "# rate_hz 1000", "# rate_hz -5")).find("line 2"),
            std::string::npos);
  EXPECT_NE(RecordErrorOf(Replace(good, ",fresh,", ",freshness,")).find("line 3: the header row"),
            std::string::npos);
  // row of tick 1 (line 5): its valid flag (fifth field) is 1; make it 2
  const std::size_t row = good.find("\n1,3,") + 1;
  std::size_t field = row;
  for (int i = 0; i < 4; ++i) field = good.find(',', field) + 1;
  std::string bad_flag = good;
  ASSERT_EQ(bad_flag[field], '1');
  bad_flag[field] = '2';
  EXPECT_NE(RecordErrorOf(bad_flag).find("line 5, column valid: '2' is not 0 or 1"),
            std::string::npos)
      << RecordErrorOf(bad_flag);
  EXPECT_NE(RecordErrorOf(Replace(good, "\n1,3,", "\n7,3,")).find("line 5: tick 7, expected 1"),
            std::string::npos);
  EXPECT_NE(RecordErrorOf(good + "5,-1,1\n").find("line 9: 3 fields, expected 38"),
            std::string::npos);
  EXPECT_NE(RecordErrorOf(Replace(good, "0.1", "0.1x")).find("is not a number"), std::string::npos);
  EXPECT_NE(RecordErrorOf("").find("line 1"), std::string::npos);
  try {
    ReadRecord((Dir() / "missing.csv").string());
    ADD_FAILURE() << "a missing file was read";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("missing.csv"), std::string::npos);
  }
}

}  // namespace
}  // namespace rigidtouch::io
