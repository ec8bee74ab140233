#include "io/device_record.h"

#include <stdlib.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>

#include "base/text.h"
#include "io/output_file.h"

namespace rigidtouch::io {
namespace {

constexpr std::array<std::string_view, 38> kRecordColumns = {"tick",
                                                             "tap",
                                                             "sequence",
                                                             "time_s",
                                                             "valid",
                                                             "fresh",
                                                             "buttons",
                                                             "x_m",
                                                             "y_m",
                                                             "z_m",
                                                             "qw",
                                                             "qx",
                                                             "qy",
                                                             "qz",
                                                             "vx_mps",
                                                             "vy_mps",
                                                             "vz_mps",
                                                             "wx_radps",
                                                             "wy_radps",
                                                             "wz_radps",
                                                             "command_sequence",
                                                             "fx_N",
                                                             "fy_N",
                                                             "fz_N",
                                                             "tx_Nm",
                                                             "ty_Nm",
                                                             "tz_Nm",
                                                             "penalty_fx_N",
                                                             "penalty_fy_N",
                                                             "penalty_fz_N",
                                                             "impulsive_fx_N",
                                                             "impulsive_fy_N",
                                                             "impulsive_fz_N",
                                                             "clipped",
                                                             "safe_fallback",
                                                             "hand_fx_N",
                                                             "hand_fy_N",
                                                             "hand_fz_N"};

constexpr std::string_view kRecordWhat = "record file";

void Put(std::string& line, double v) {
  text::AppendShortest(line, v);
  line.push_back(',');
}

template <typename Int>
void PutInt(std::string& line, Int v) {
  text::AppendInteger(line, v);
  line.push_back(',');
}

void Put(std::string& line, const Vec3& v) {
  for (int i = 0; i < 3; ++i) Put(line, v[i]);
}

std::string RateLine(double rate_hz) {
  std::string line = "# rate_hz ";
  Put(line, rate_hz);
  line.back() = '\n';
  return line;
}

}  // namespace

std::span<const std::string_view> RecordColumns() {
  return kRecordColumns;
}

RecordFileWriter::RecordFileWriter(const std::string& path, double rate_hz) : path_(path) {
  CheckOutputPath(path, kRecordWhat);
  temp_path_ = path + ".tmp.XXXXXX";
  const int fd = ::mkstemp(temp_path_.data());
  if (fd < 0) {
    throw Error("cannot write record file '" + path + "': " + WriteFailureReason(errno));
  }
  file_ = ::fdopen(fd, "w");
  if (file_ == nullptr) {
    const int e = errno;
    ::close(fd);
    ::unlink(temp_path_.c_str());
    throw Error("cannot write record file '" + path + "': " + WriteFailureReason(e));
  }
  std::string head(kRecordMagic);
  head += '\n';
  head += RateLine(rate_hz);
  for (const std::string_view c : kRecordColumns) {
    head += c;
    head += ',';
  }
  head.back() = '\n';
  if (std::fwrite(head.data(), 1, head.size(), file_) != head.size()) Fail(errno);
  line_.reserve(1024);
}

RecordFileWriter::~RecordFileWriter() {
  if (file_ != nullptr) std::fclose(file_);
  if (!committed_) ::unlink(temp_path_.c_str());
}

void RecordFileWriter::Fail(int error_number) {
  if (file_ != nullptr) std::fclose(file_);
  file_ = nullptr;
  ::unlink(temp_path_.c_str());
  throw OutputError("cannot write record file '" + path_ +
                    "': " + WriteFailureReason(error_number));
}

void RecordFileWriter::Append(std::span<const RecordSample> samples) {
  if (file_ == nullptr) throw OutputError("record file '" + path_ + "' is closed");
  for (const RecordSample& r : samples) {
    line_.clear();
    const DeviceState& s = r.state;
    const DeviceCommand& c = r.command;
    PutInt(line_, r.tick);
    PutInt(line_, r.tap);
    PutInt(line_, s.sequence);
    Put(line_, s.time_s);
    PutInt(line_, s.valid ? 1 : 0);
    PutInt(line_, s.fresh ? 1 : 0);
    PutInt(line_, s.buttons);
    Put(line_, s.position_m);
    Put(line_, s.orientation.w());
    Put(line_, s.orientation.x());
    Put(line_, s.orientation.y());
    Put(line_, s.orientation.z());
    Put(line_, s.velocity_mps);
    Put(line_, s.angular_velocity_radps);
    PutInt(line_, c.sequence);
    Put(line_, c.force_N);
    Put(line_, c.torque_Nm);
    Put(line_, c.penalty_force_N);
    Put(line_, c.impulsive_force_N);
    PutInt(line_, c.clipped ? 1 : 0);
    PutInt(line_, c.safe_fallback ? 1 : 0);
    Put(line_, r.hand_force_N);
    line_.back() = '\n';
    if (std::fwrite(line_.data(), 1, line_.size(), file_) != line_.size()) Fail(errno);
  }
}

void RecordFileWriter::Commit() {
  if (file_ == nullptr) throw OutputError("record file '" + path_ + "' is closed");
  if (std::fflush(file_) != 0) Fail(errno);
  if (::fsync(::fileno(file_)) != 0) Fail(errno);
  const int closed = std::fclose(file_);
  file_ = nullptr;
  if (closed != 0) Fail(errno);
  // mkstemp creates 0600; give the file the usual permissions (subject to umask)
  const mode_t mask = ::umask(0);
  ::umask(mask);
  ::chmod(temp_path_.c_str(), 0666 & ~mask);
  if (::rename(temp_path_.c_str(), path_.c_str()) != 0) Fail(errno);
  committed_ = true;
}

namespace {

// splits a row at commas into `fields` (views into `line`)
void Split(std::string_view line, std::vector<std::string_view>& fields) {
  fields.clear();
  std::size_t start = 0;
  for (;;) {
    const std::size_t comma = line.find(',', start);
    fields.push_back(
        line.substr(start, comma == std::string_view::npos ? line.npos : comma - start));
    if (comma == std::string_view::npos) return;
    start = comma + 1;
  }
}

class RowParser {
 public:
  RowParser(const std::string& path, std::size_t line_number,
            const std::vector<std::string_view>& fields)
      : path_(path), line_(line_number), fields_(fields) {}

  double Real() {
    const std::string_view f = Next();
    double v = 0.0;
    const auto r = std::from_chars(f.data(), f.data() + f.size(), v);
    if (r.ec != std::errc() || r.ptr != f.data() + f.size()) Bad(f, "a number");
    return v;
  }
  Vec3 Vector() {
    Vec3 v;
    for (int i = 0; i < 3; ++i) v[i] = Real();
    return v;
  }
  template <typename Int>
  Int Integer() {
    const std::string_view f = Next();
    Int v = 0;
    const auto r = std::from_chars(f.data(), f.data() + f.size(), v);
    if (r.ec != std::errc() || r.ptr != f.data() + f.size()) Bad(f, "an integer in range");
    return v;
  }
  bool Flag() {
    const std::string_view f = Next();
    if (f == "0") return false;
    if (f == "1") return true;
    Bad(f, "0 or 1");
  }

 private:
  std::string_view Next() { return fields_[column_++]; }
  [[noreturn]] void Bad(std::string_view value, const char* expected) const {
    std::ostringstream m;
    m << "record file '" << path_ << "': line " << line_ << ", column "
      << kRecordColumns[column_ - 1] << ": '" << value << "' is not " << expected;
    throw Error(m.str());
  }

  const std::string& path_;
  std::size_t line_;
  const std::vector<std::string_view>& fields_;
  std::size_t column_ = 0;
};

}  // namespace

Record ReadRecord(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw Error("cannot read record file '" + path + "': no such file or not readable");
  const auto fail = [&path](std::size_t line, const std::string& why) {
    throw Error("record file '" + path + "': line " + std::to_string(line) + ": " + why);
  };
  std::string line;
  if (!std::getline(in, line) || line != kRecordMagic) {
    fail(1, "the first line is not '" + std::string(kRecordMagic) + "' (not a record file?)");
  }
  Record record;
  constexpr std::string_view kRate = "# rate_hz ";
  if (!std::getline(in, line) || !line.starts_with(kRate)) fail(2, "expected '# rate_hz HZ'");
  {
    const std::string_view v = std::string_view(line).substr(kRate.size());
    const auto r = std::from_chars(v.data(), v.data() + v.size(), record.rate_hz);
    if (r.ec != std::errc() || r.ptr != v.data() + v.size() || !(record.rate_hz > 0.0) ||
        !std::isfinite(record.rate_hz)) {
      fail(2, "rate '" + std::string(v) + "' is not a positive finite number of Hz");
    }
  }
  std::vector<std::string_view> fields;
  if (!std::getline(in, line)) fail(3, "no header row");
  Split(line, fields);
  if (fields.size() != kRecordColumns.size() ||
      !std::equal(fields.begin(), fields.end(), kRecordColumns.begin())) {
    std::string expected;
    for (const std::string_view c : kRecordColumns) (expected += c) += ',';
    expected.pop_back();
    fail(3, "the header row is not '" + expected + "'");
  }
  std::size_t n = 3;
  while (std::getline(in, line)) {
    ++n;
    if (line.empty()) continue;
    Split(line, fields);
    if (fields.size() != kRecordColumns.size()) {
      fail(n, std::to_string(fields.size()) + " fields, expected " +
                  std::to_string(kRecordColumns.size()));
    }
    RowParser p(path, n, fields);
    RecordSample r;
    DeviceState& s = r.state;
    DeviceCommand& c = r.command;
    r.tick = p.Integer<std::int64_t>();
    r.tap = p.Integer<int>();
    s.sequence = p.Integer<std::uint64_t>();
    s.time_s = p.Real();
    s.valid = p.Flag();
    s.fresh = p.Flag();
    s.buttons = p.Integer<std::uint32_t>();
    s.position_m = p.Vector();
    const double qw = p.Real(), qx = p.Real(), qy = p.Real(), qz = p.Real();
    s.orientation = Quat(qw, qx, qy, qz);
    s.velocity_mps = p.Vector();
    s.angular_velocity_radps = p.Vector();
    c.sequence = p.Integer<std::uint64_t>();
    c.force_N = p.Vector();
    c.torque_Nm = p.Vector();
    c.penalty_force_N = p.Vector();
    c.impulsive_force_N = p.Vector();
    c.clipped = p.Flag();
    c.safe_fallback = p.Flag();
    r.hand_force_N = p.Vector();
    const std::int64_t expected_tick = static_cast<std::int64_t>(record.samples.size());
    if (r.tick != expected_tick) {
      fail(n, "tick " + std::to_string(r.tick) + ", expected " + std::to_string(expected_tick) +
                  " (ticks count up by one from 0)");
    }
    record.samples.push_back(r);
  }
  if (in.bad()) fail(n, "read error");
  return record;
}

}  // namespace rigidtouch::io
