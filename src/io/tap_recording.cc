#include "io/tap_recording.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <map>

#include "base/text.h"
#include "rigidtouch/types.h"

namespace rigidtouch::io {
namespace {

constexpr std::size_t kMaxRecordingBytes = std::size_t{256} << 20;

enum RecordingColumn {
  kColTime,
  kColAcceleration,
  kColForce,
  kColVelocity,
  kColPosition,
  kColTap,
  kColImpactSpeed,
  kColCount
};

[[noreturn]] void RecordingFail(const std::string& path, int line, const std::string& message) {
  throw Error(path + ":" + std::to_string(line) + ": " + message);
}

// the column of a header name; a name that looks like a known quantity in another unit gets a
// message naming the unit rigidtouch expects
int RecordingColumnOf(std::string_view name, const std::string& path, int line) {
  const std::vector<std::string>& names = TapRecordingColumns();
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (names[i] == name) return static_cast<int>(i);
  }
  const std::string lower = text::Lower(name);
  for (const char* stem : {"time", "acceleration", "accel", "force", "velocity", "position", "tap",
                           "impact_speed", "speed"}) {
    if (lower.rfind(stem, 0) == 0) {
      RecordingFail(path, line,
                    "column " + text::Quote(name) +
                        " has a unit rigidtouch does not read (wrong units?); " +
                        "valid columns: " + text::Join(names) + " (docs/materials.md)");
    }
  }
  RecordingFail(path, line,
                "unknown column " + text::Quote(name) + "; valid columns: " + text::Join(names) +
                    " (docs/materials.md)");
}

std::vector<std::string_view> RecordingCells(std::string_view row) {
  std::vector<std::string_view> cells;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = row.find(',', start);
    cells.push_back(text::Trim(row.substr(start, comma - start)));
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
  return cells;
}

// the header's columns: index in the row of each Column, -1 when absent
std::vector<int> RecordingHeader(std::string_view row, const std::string& path, int line) {
  std::vector<int> at(kColCount, -1);
  const std::vector<std::string_view> cells = RecordingCells(row);
  for (std::size_t i = 0; i < cells.size(); ++i) {
    double number = 0.0;
    const std::string_view c = cells[i];
    const auto [end, ec] = std::from_chars(c.data(), c.data() + c.size(), number);
    if (!c.empty() && ec == std::errc() && end == c.data() + c.size()) {
      RecordingFail(path, line,
                    "no header: the first line must name the columns (time_s, acceleration_mps2 or "
                    "force_N, ...), found the number " +
                        std::string(c));
    }
    if (c.empty())
      RecordingFail(path, line, "header column " + std::to_string(i + 1) + " has no name");
    const int col = RecordingColumnOf(c, path, line);
    if (at[col] >= 0) RecordingFail(path, line, "column " + text::Quote(c) + " is given twice");
    at[col] = static_cast<int>(i);
  }
  if (at[kColTime] < 0) RecordingFail(path, line, "no time_s column (time in seconds)");
  if ((at[kColAcceleration] >= 0) == (at[kColForce] >= 0)) {
    RecordingFail(
        path, line,
        "give exactly one signal column: acceleration_mps2 (m/s^2 along the tap normal) or "
        "force_N");
  }
  if (at[kColVelocity] >= 0 && at[kColPosition] >= 0) {
    RecordingFail(path, line, "give velocity_mps or position_m, not both");
  }
  return at;
}

double RecordingNumber(std::string_view cell, const std::string& name, const std::string& path,
                       int line) {
  double value = 0.0;
  const auto [end, ec] = std::from_chars(cell.data(), cell.data() + cell.size(), value);
  if (cell.empty() || ec != std::errc() || end != cell.data() + cell.size()) {
    RecordingFail(path, line, "column " + name + ": " + text::Quote(cell) + " is not a number");
  }
  if (!std::isfinite(value)) {
    RecordingFail(path, line,
                  "column " + name + ": " + std::string(cell) + " is not a finite number");
  }
  return value;
}

void AddRecordingRow(TapRecording& r, const std::vector<int>& at, std::string_view row, int line,
                     std::map<int, int>& seen) {
  const std::vector<std::string_view> cells = RecordingCells(row);
  int columns = 0;
  for (const int a : at) columns += a >= 0 ? 1 : 0;
  if (static_cast<int>(cells.size()) != columns) {
    RecordingFail(r.path, line,
                  "has " + std::to_string(cells.size()) + " values; the header names " +
                      std::to_string(columns) + " columns");
  }
  const std::vector<std::string>& names = TapRecordingColumns();
  auto value = [&](int col) { return RecordingNumber(cells[at[col]], names[col], r.path, line); };
  int tap = 0;
  if (at[kColTap] >= 0) {
    const double t = value(kColTap);
    if (t != std::floor(t) || std::abs(t) > 1e9) {
      RecordingFail(r.path, line,
                    "column tap: " + std::string(cells[at[kColTap]]) + " is not an integer");
    }
    tap = static_cast<int>(t);
  }
  if (r.taps.empty() || r.taps.back().tap != tap) {
    const auto [it, fresh] = seen.emplace(tap, line);
    if (!fresh) {
      RecordingFail(r.path, line,
                    "tap " + std::to_string(tap) +
                        " comes back after other taps (it started on line " +
                        std::to_string(it->second) + "); each tap's rows must be contiguous");
    }
    r.taps.push_back({});
    r.taps.back().tap = tap;
  }
  RecordedTap& t = r.taps.back();
  const double time = value(kColTime);
  if (!t.time_s.empty() && !(time > t.time_s.back())) {
    RecordingFail(r.path, line,
                  "time_s " + text::FormatNumber(time) + " is not after the previous sample's " +
                      text::FormatNumber(t.time_s.back()) + " (time must increase within a tap)");
  }
  t.time_s.push_back(time);
  t.signal.push_back(value(at[kColAcceleration] >= 0 ? kColAcceleration : kColForce));
  if (at[kColVelocity] >= 0) t.velocity_mps.push_back(value(kColVelocity));
  if (at[kColPosition] >= 0) t.position_m.push_back(value(kColPosition));
  if (at[kColImpactSpeed] >= 0) t.impact_speed_mps.push_back(value(kColImpactSpeed));
  t.line.push_back(line);
}

}  // namespace

std::string_view TapQuantityUnit(TapQuantity quantity) {
  return quantity == TapQuantity::kAcceleration ? "m/s^2" : "N";
}

std::string_view TapQuantityColumn(TapQuantity quantity) {
  return quantity == TapQuantity::kAcceleration ? "acceleration_mps2" : "force_N";
}

const std::vector<std::string>& TapRecordingColumns() {
  static const std::vector<std::string> names = {"time_s",          "acceleration_mps2", "force_N",
                                                 "velocity_mps",    "position_m",        "tap",
                                                 "impact_speed_mps"};
  return names;
}

TapRecording ParseTapRecording(std::string_view text, const std::string& path) {
  TapRecording r;
  r.path = path;
  std::vector<int> at;
  std::map<int, int> seen;  // tap -> the line it started on
  int line = 0, last_line = 1;
  std::size_t start = 0;
  while (start < text.size()) {
    std::size_t end = text.find('\n', start);
    if (end == std::string_view::npos) end = text.size();
    const std::string_view row = text::Trim(text.substr(start, end - start));
    start = end + 1;
    ++line;
    if (row.empty() || row.front() == '#') continue;
    last_line = line;
    if (at.empty()) {
      at = RecordingHeader(row, path, line);
      r.quantity = at[kColAcceleration] >= 0 ? TapQuantity::kAcceleration : TapQuantity::kForce;
      continue;
    }
    AddRecordingRow(r, at, row, line, seen);
  }
  if (at.empty()) RecordingFail(path, 1, "empty recording: no header and no samples");
  if (r.taps.empty()) RecordingFail(path, last_line, "no samples after the header");
  for (const RecordedTap& t : r.taps) {
    if (t.time_s.size() < 2) {
      RecordingFail(path, t.line.front(),
                    "tap " + std::to_string(t.tap) +
                        " has one sample; a tap needs a pre-contact part " + "and its transient");
    }
  }
  return r;
}

TapRecording ReadTapRecording(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path + ":1: cannot open the recording");
  std::string bytes;
  char chunk[1 << 16];
  while (bytes.size() <= kMaxRecordingBytes && in.read(chunk, sizeof chunk).gcount() > 0) {
    bytes.append(chunk, static_cast<std::size_t>(in.gcount()));
  }
  if (in.bad()) throw Error(path + ":1: cannot read the recording");
  if (bytes.size() > kMaxRecordingBytes) {
    throw Error(path + ":1: larger than 256 MiB; split the recording into files");
  }
  return ParseTapRecording(bytes, path);
}

}  // namespace rigidtouch::io
