#include "io/trace_csv.h"

#include <array>
#include <cerrno>
#include <charconv>
#include <cstring>
#include <fstream>
#include <string>
#include <system_error>

#include "base/text.h"
#include "io/output_file.h"
#include "rigidtouch/types.h"

namespace rigidtouch::io {

namespace {

constexpr std::size_t kColumnCount = 30;

constexpr std::array<std::string_view, kColumnCount> kTraceColumns = {"time_s",
                                                                      "tool_x_m",
                                                                      "tool_y_m",
                                                                      "tool_z_m",
                                                                      "tool_vx_mps",
                                                                      "tool_vy_mps",
                                                                      "tool_vz_mps",
                                                                      "penalty_fx_N",
                                                                      "penalty_fy_N",
                                                                      "penalty_fz_N",
                                                                      "impulsive_fx_N",
                                                                      "impulsive_fy_N",
                                                                      "impulsive_fz_N",
                                                                      "device_fx_N",
                                                                      "device_fy_N",
                                                                      "device_fz_N",
                                                                      "hand_fx_N",
                                                                      "hand_fy_N",
                                                                      "hand_fz_N",
                                                                      "wall_nx",
                                                                      "wall_ny",
                                                                      "wall_nz",
                                                                      "penetration_m",
                                                                      "tool_contacts",
                                                                      "impulses",
                                                                      "kinetic_energy_before_J",
                                                                      "kinetic_energy_after_J",
                                                                      "clipped",
                                                                      "tap",
                                                                      "step"};

// integer columns: tool_contacts, impulses, clipped, tap, step
constexpr bool IsIntegerColumn(std::size_t k) {
  return k == 23 || k == 24 || k == 27 || k == 28 || k == 29;
}

std::string SystemReason(int error_number) {
  return std::generic_category().message(error_number);
}

void AppendVec(std::string& out, const Vec3& v) {
  for (int i = 0; i < 3; ++i) {
    out += ',';
    text::AppendShortest(out, v[i]);
  }
}

void AppendRow(std::string& out, const TraceSample& s) {
  text::AppendShortest(out, s.time_s);
  AppendVec(out, s.tool_position_m);
  AppendVec(out, s.tool_velocity_mps);
  AppendVec(out, s.penalty_force_N);
  AppendVec(out, s.impulsive_force_N);
  AppendVec(out, s.device_force_N);
  AppendVec(out, s.hand_force_N);
  AppendVec(out, s.wall_normal);
  out += ',';
  text::AppendShortest(out, s.penetration_m);
  out += ',';
  text::AppendInteger(out, s.tool_contacts);
  out += ',';
  text::AppendInteger(out, s.impulses);
  out += ',';
  text::AppendShortest(out, s.kinetic_energy_before_J);
  out += ',';
  text::AppendShortest(out, s.kinetic_energy_after_J);
  out += ',';
  out += s.clipped ? '1' : '0';
  out += ',';
  text::AppendInteger(out, s.tap);
  out += ',';
  text::AppendInteger(out, s.step);
  out += '\n';
}

std::string_view TrimSpaces(std::string_view s) {
  while (!s.empty() && (s.back() == '\r' || s.back() == ' ')) s.remove_suffix(1);
  while (!s.empty() && s.front() == ' ') s.remove_prefix(1);
  return s;
}

std::vector<std::string_view> SplitCommas(std::string_view line) {
  std::vector<std::string_view> fields;
  std::size_t begin = 0;
  while (true) {
    const std::size_t comma = line.find(',', begin);
    if (comma == std::string_view::npos) {
      fields.push_back(TrimSpaces(line.substr(begin)));
      return fields;
    }
    fields.push_back(TrimSpaces(line.substr(begin, comma - begin)));
    begin = comma + 1;
  }
}

}  // namespace

std::span<const std::string_view> TraceColumns() {
  return kTraceColumns;
}

void WriteTraceCsv(const std::string& path, std::span<const TraceSample> samples) {
  std::string text;
  text.reserve(64 + samples.size() * 400);
  for (std::size_t i = 0; i < kColumnCount; ++i) {
    if (i > 0) text += ',';
    text += kTraceColumns[i];
  }
  text += '\n';
  for (const TraceSample& s : samples) AppendRow(text, s);

  WriteFileAtomically(path, text, "trace file");
}

std::vector<TraceSample> ReadTraceCsv(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw Error("cannot read trace file '" + path + "': " + SystemReason(errno));
  std::string line;
  if (!std::getline(in, line)) throw Error("trace file '" + path + "' is empty (no header row)");

  // column index in the file of each known column
  std::array<int, kColumnCount> index;
  index.fill(-1);
  const std::vector<std::string_view> header = SplitCommas(line);
  for (std::size_t c = 0; c < header.size(); ++c) {
    for (std::size_t k = 0; k < kColumnCount; ++k) {
      if (header[c] == kTraceColumns[k]) index[k] = static_cast<int>(c);
    }
  }
  std::string missing;
  for (std::size_t k = 0; k < kColumnCount; ++k) {
    if (index[k] < 0) missing += (missing.empty() ? "" : ", ") + std::string(kTraceColumns[k]);
  }
  if (!missing.empty()) {
    throw Error("trace file '" + path + "' line 1: missing columns: " + missing);
  }

  std::vector<TraceSample> samples;
  int line_number = 1;
  std::array<double, kColumnCount> values{};
  std::array<long long, kColumnCount> integers{};
  while (std::getline(in, line)) {
    ++line_number;
    if (TrimSpaces(line).empty()) continue;
    const std::vector<std::string_view> fields = SplitCommas(line);
    for (std::size_t k = 0; k < kColumnCount; ++k) {
      const std::size_t c = static_cast<std::size_t>(index[k]);
      const std::string_view field = c < fields.size() ? fields[c] : std::string_view();
      const char* first = field.data();
      const char* last = field.data() + field.size();
      const std::from_chars_result result = IsIntegerColumn(k)
                                                ? std::from_chars(first, last, integers[k])
                                                : std::from_chars(first, last, values[k]);
      if (field.empty() || result.ec != std::errc() || result.ptr != last) {
        throw Error("trace file '" + path + "' line " + std::to_string(line_number) + ": column '" +
                    std::string(kTraceColumns[k]) + "' value '" + std::string(field) + "' is not " +
                    (IsIntegerColumn(k) ? "an integer" : "a number"));
      }
    }
    TraceSample s;
    std::size_t k = 0;
    const auto vec = [&](Vec3& v) {
      v = Vec3(values[k], values[k + 1], values[k + 2]);
      k += 3;
    };
    s.time_s = values[k++];
    vec(s.tool_position_m);
    vec(s.tool_velocity_mps);
    vec(s.penalty_force_N);
    vec(s.impulsive_force_N);
    vec(s.device_force_N);
    vec(s.hand_force_N);
    vec(s.wall_normal);
    s.penetration_m = values[k++];
    s.tool_contacts = static_cast<int>(integers[k++]);
    s.impulses = static_cast<int>(integers[k++]);
    s.kinetic_energy_before_J = values[k++];
    s.kinetic_energy_after_J = values[k++];
    s.clipped = integers[k++] != 0;
    s.tap = static_cast<int>(integers[k++]);
    s.step = static_cast<std::int64_t>(integers[k++]);
    samples.push_back(s);
  }
  return samples;
}

}  // namespace rigidtouch::io
