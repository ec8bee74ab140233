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
#include "io/record_fields.h"

namespace rigidtouch::io {
namespace {

// a record's row: the loop's tick and tap, the state's and the command's tables, the hand's force
template <class Sample, class Visit>
void VisitRecordFields(Sample& r, Visit&& visit) {
  visit(RecordField{"tick", ""}, r.tick);
  visit(RecordField{"tap", ""}, r.tap);
  VisitStateFields(r.state, visit);
  VisitCommandFields(r.command, visit);
  visit(RecordField{"hand_f", "N"}, r.hand_force_N);
}

const ColumnNames& RecordColumnNames() {
  static const ColumnNames columns = MakeColumnNames<RecordSample>(
      [](const RecordSample& r, auto&& visit) { VisitRecordFields(r, visit); });
  return columns;
}

constexpr std::string_view kRecordWhat = "record file";

void Put(std::string& line, double v) {
  text::AppendShortest(line, v);
  line.push_back(',');
}

// one field's columns, each followed by a comma
template <class T>
void PutField(std::string& line, const T& v) {
  if constexpr (std::is_same_v<T, bool>) {
    line += v ? "1," : "0,";
  } else if constexpr (std::is_integral_v<T>) {
    text::AppendInteger(line, v);
    line.push_back(',');
  } else if constexpr (std::is_same_v<T, double>) {
    Put(line, v);
  } else if constexpr (std::is_same_v<T, Vec3>) {
    for (int i = 0; i < 3; ++i) Put(line, v[i]);
  } else {
    static_assert(std::is_same_v<T, Quat>);
    for (const double q : {v.w(), v.x(), v.y(), v.z()}) Put(line, q);
  }
}

std::string RateLine(double rate_hz) {
  std::string line = "# rate_hz ";
  Put(line, rate_hz);
  line.back() = '\n';
  return line;
}

}  // namespace

std::span<const std::string_view> RecordColumns() {
  return RecordColumnNames().views;
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
  for (const std::string_view c : RecordColumns()) {
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
    VisitRecordFields(r, [this](const RecordField&, const auto& value) { PutField(line_, value); });
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
  // one field's columns into `v`
  template <class T>
  void Read(T& v) {
    if constexpr (std::is_same_v<T, bool>) {
      v = Flag();
    } else if constexpr (std::is_integral_v<T>) {
      v = Integer<T>();
    } else if constexpr (std::is_same_v<T, double>) {
      v = Real();
    } else if constexpr (std::is_same_v<T, Vec3>) {
      v = Vector();
    } else {
      static_assert(std::is_same_v<T, Quat>);
      const double w = Real(), x = Real(), y = Real(), z = Real();
      v = Quat(w, x, y, z);
    }
  }

 private:
  std::string_view Next() { return fields_[column_++]; }
  [[noreturn]] void Bad(std::string_view value, const char* expected) const {
    std::ostringstream m;
    m << "record file '" << path_ << "': line " << line_ << ", column "
      << RecordColumns()[column_ - 1] << ": '" << value << "' is not " << expected;
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
  const std::span<const std::string_view> columns = RecordColumns();
  if (fields.size() != columns.size() ||
      !std::equal(fields.begin(), fields.end(), columns.begin())) {
    std::string expected;
    for (const std::string_view c : columns) (expected += c) += ',';
    expected.pop_back();
    fail(3, "the header row is not '" + expected + "'");
  }
  std::size_t n = 3;
  while (std::getline(in, line)) {
    ++n;
    if (line.empty()) continue;
    Split(line, fields);
    if (fields.size() != RecordColumns().size()) {
      fail(n, std::to_string(fields.size()) + " fields, expected " +
                  std::to_string(RecordColumns().size()));
    }
    RowParser p(path, n, fields);
    RecordSample r;
    VisitRecordFields(r, [&p](const RecordField&, auto& value) { p.Read(value); });
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
