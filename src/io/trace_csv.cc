#include "io/trace_csv.h"

#include <cerrno>
#include <charconv>
#include <cstring>
#include <fstream>
#include <string>
#include <system_error>
#include <type_traits>
#include <vector>

#include "base/text.h"
#include "io/output_file.h"
#include "io/record_fields.h"
#include "rigidtouch/types.h"

namespace rigidtouch::io {

namespace {

const ColumnNames& TraceColumnNames() {
  static const ColumnNames columns = MakeColumnNames<TraceSample>(
      [](const TraceSample& s, auto&& visit) { VisitTraceFields(s, visit); });
  return columns;
}

std::string SystemReason(int error_number) {
  return std::generic_category().message(error_number);
}

// one field's columns, each preceded by a comma
template <class T>
void AppendField(std::string& out, const T& v) {
  if constexpr (std::is_same_v<T, Vec3>) {
    for (int i = 0; i < 3; ++i) AppendField(out, v[i]);
  } else {
    out += ',';
    if constexpr (std::is_same_v<T, bool>) {
      out += v ? '1' : '0';
    } else if constexpr (std::is_integral_v<T>) {
      text::AppendInteger(out, v);
    } else {
      static_assert(std::is_same_v<T, double>);
      text::AppendShortest(out, v);
    }
  }
}

void AppendRow(std::string& out, const TraceSample& s) {
  const std::size_t begin = out.size();
  VisitTraceFields(s, [&out](const RecordField&, const auto& value) { AppendField(out, value); });
  out.erase(begin, 1);  // the first field's comma
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
  return TraceColumnNames().views;
}

void WriteTraceCsv(const std::string& path, std::span<const TraceSample> samples) {
  std::string text;
  text.reserve(64 + samples.size() * 400);
  const std::span<const std::string_view> columns = TraceColumns();
  for (std::size_t i = 0; i < columns.size(); ++i) {
    if (i > 0) text += ',';
    text += columns[i];
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
  const std::span<const std::string_view> columns = TraceColumns();
  std::vector<int> index(columns.size(), -1);
  const std::vector<std::string_view> header = SplitCommas(line);
  for (std::size_t c = 0; c < header.size(); ++c) {
    for (std::size_t k = 0; k < columns.size(); ++k) {
      if (header[c] == columns[k]) index[k] = static_cast<int>(c);
    }
  }
  std::string missing;
  for (std::size_t k = 0; k < columns.size(); ++k) {
    if (index[k] < 0) missing += (missing.empty() ? "" : ", ") + std::string(columns[k]);
  }
  if (!missing.empty()) {
    throw Error("trace file '" + path + "' line 1: missing columns: " + missing);
  }

  std::vector<TraceSample> samples;
  int line_number = 1;
  while (std::getline(in, line)) {
    ++line_number;
    if (TrimSpaces(line).empty()) continue;
    const std::vector<std::string_view> fields = SplitCommas(line);
    std::size_t k = 0;  // the next column of the table
    // the table's column k parsed into v (a flag is any integer, non-zero for true)
    const auto parse = [&](auto& v) {
      using T = std::remove_reference_t<decltype(v)>;
      const std::size_t c = static_cast<std::size_t>(index[k]);
      const std::string_view field = c < fields.size() ? fields[c] : std::string_view();
      const char* first = field.data();
      const char* last = field.data() + field.size();
      std::from_chars_result result{};
      if constexpr (std::is_same_v<T, bool>) {
        long long flag = 0;
        result = std::from_chars(first, last, flag);
        v = flag != 0;
      } else {
        result = std::from_chars(first, last, v);
      }
      if (field.empty() || result.ec != std::errc() || result.ptr != last) {
        throw Error("trace file '" + path + "' line " + std::to_string(line_number) + ": column '" +
                    std::string(columns[k]) + "' value '" + std::string(field) + "' is not " +
                    (std::is_integral_v<T> ? "an integer" : "a number"));
      }
      ++k;
    };
    TraceSample s;
    VisitTraceFields(s, [&parse](const RecordField&, auto& value) {
      if constexpr (std::is_same_v<std::remove_reference_t<decltype(value)>, Vec3>) {
        for (int i = 0; i < 3; ++i) parse(value[i]);
      } else {
        parse(value);
      }
    });
    samples.push_back(s);
  }
  return samples;
}

}  // namespace rigidtouch::io
