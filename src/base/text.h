// Small text helpers for messages and answers, shared by the file readers and the study code.
#pragma once

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <string_view>
#include <vector>

namespace rigidtouch::text {

/// `s` in double quotes, as error messages show names and values.
inline std::string Quote(std::string_view s) {
  // built with append: GCC 12 reports a false -Wrestrict on "literal" + std::string
  std::string out;
  out.reserve(s.size() + 2);
  out.push_back('"');
  out.append(s);
  out.push_back('"');
  return out;
}

/// ASCII lower case (answers and labels are compared without case).
inline std::string Lower(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

/// `s` without leading and trailing white space.
inline std::string_view Trim(std::string_view s) {
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front()))) s.remove_prefix(1);
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.remove_suffix(1);
  return s;
}

/// The items separated by ", ".
inline std::string Join(const std::vector<std::string>& items) {
  std::string out;
  for (std::size_t i = 0; i < items.size(); ++i) {
    if (i > 0) out += ", ";
    out += items[i];
  }
  return out;
}

/// The index of `name` in `names`, or -1 (tables of names in enum order map names to enums).
inline int IndexOf(const std::vector<std::string>& names, std::string_view name) {
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (names[i] == name) return static_cast<int>(i);
  }
  return -1;
}

/// A number as messages print it: six significant digits (%.6g).
inline std::string FormatNumber(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.6g", value);
  return buffer;
}

/// A number for people: `decimals` digits after the point, and never "-0" (a rounding residue
/// such as -1e-20 prints as 0); "nan", "inf" or "-inf" when not finite.
inline std::string Fixed(double value, int decimals) {
  char buffer[64];
  if (!std::isfinite(value)) return std::isnan(value) ? "nan" : value > 0 ? "inf" : "-inf";
  if (std::fabs(value) >= 1e15) {
    std::snprintf(buffer, sizeof buffer, "%.3g", value);
    return buffer;
  }
  std::snprintf(buffer, sizeof buffer, "%.*f", decimals, value);
  std::string s = buffer;
  if (s[0] == '-' && s.find_first_not_of("-0.") == std::string::npos) s.erase(0, 1);
  return s;
}

/// A number for people: `digits` significant digits (3-4 are what a measurement means here),
/// without an exponent from 1e-4 up to 1e7 (so 16570 prints whole, 0.000796 as it is), with one
/// beyond; "nan", "inf" or "-inf" when not finite.
inline std::string Significant(double value, int digits = 4) {
  if (!std::isfinite(value) || value == 0.0) return Fixed(value, 0);
  // the exponent after rounding to `digits` (99.996 to 4 digits is 100.0, not 100.00)
  char buffer[40];
  std::snprintf(buffer, sizeof buffer, "%.*e", digits - 1, value);
  const int exponent = std::atoi(std::strchr(buffer, 'e') + 1);
  if (exponent < -4 || exponent >= 7) return buffer;
  return Fixed(value, std::max(0, digits - 1 - exponent));
}

/// A fraction as a percentage to 0.1 ("94.4%").
inline std::string Percent(double fraction) {
  return Fixed(100.0 * fraction, 1) + "%";
}

/// Appends `value` in the shortest form that reads back to the same double (the record and trace
/// files keep every bit).
inline void AppendShortest(std::string& out, double value) {
  char buffer[32];  // the longest shortest form of a double is 24 characters
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
  out.append(buffer, result.ptr);
}

/// Appends an integer in decimal.
template <typename Int>
void AppendInteger(std::string& out, Int value) {
  char buffer[24];  // 20 digits and a sign hold any 64-bit integer
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
  out.append(buffer, result.ptr);
}

}  // namespace rigidtouch::text
