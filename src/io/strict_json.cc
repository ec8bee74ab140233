#include "io/strict_json.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>

#include "base/text.h"
#include "rigidtouch/types.h"

namespace rigidtouch::io {

namespace {

using nlohmann::json;

// the field path the parser is in, kept from its callback events so that a parse error (which
// nlohmann reports with a byte offset only) can name the field
class PathTracker {
 public:
  bool Event(json::parse_event_t event, const json& parsed) {
    switch (event) {
      case json::parse_event_t::object_start:
        frames_.push_back(Frame{false, {}, 0, {}});
        break;
      case json::parse_event_t::array_start:
        frames_.push_back(Frame{true, {}, 0, {}});
        break;
      case json::parse_event_t::key: {
        Frame& top = frames_.back();
        top.key = parsed.get<std::string>();
        if (!top.keys.insert(top.key).second && duplicate_.empty()) duplicate_ = Path();
        break;
      }
      case json::parse_event_t::value:
        EndValue();
        break;
      case json::parse_event_t::object_end:
      case json::parse_event_t::array_end:
        frames_.pop_back();
        EndValue();
        break;
    }
    return true;  // keep every value
  }

  // e.g. "tests[0].name"; "" at the top level
  std::string Path() const {
    std::string path;
    for (const Frame& f : frames_) {
      // appended piece by piece: GCC 12 reports a false -Wrestrict on "literal" + std::string
      if (f.array) {
        path.append("[").append(std::to_string(f.index)).append("]");
      } else if (!f.key.empty()) {
        path.append(path.empty() ? "" : ".").append(f.key);
      }
    }
    return path;
  }

  // path of the first field given twice in one object, "" if none
  const std::string& duplicate() const { return duplicate_; }

 private:
  struct Frame {
    bool array;
    std::string key;             // object: the field being read
    std::size_t index;           // array: the element being read
    std::set<std::string> keys;  // object: the fields seen so far
  };

  void EndValue() {
    if (!frames_.empty() && frames_.back().array) ++frames_.back().index;
  }

  std::vector<Frame> frames_;
  std::string duplicate_;
};

// 1-based line and column of the byte at 1-based offset `byte` (nlohmann's error position)
std::string LineColumn(std::string_view text, std::size_t byte) {
  const std::size_t end = std::min(byte == 0 ? 0 : byte - 1, text.size());
  std::size_t line = 1;
  std::size_t column = 1;
  for (std::size_t i = 0; i < end; ++i) {
    if (text[i] == '\n') {
      ++line;
      column = 1;
    } else {
      ++column;
    }
  }
  return "line " + std::to_string(line) + ", column " + std::to_string(column);
}

// nlohmann's reason without its "[json.exception...] parse error at line L, column C: " prefix
std::string JsonReason(const std::string& what) {
  const std::size_t column = what.find("column ");
  const std::size_t colon = what.find(": ", column == std::string::npos ? 0 : column);
  return colon == std::string::npos ? what : what.substr(colon + 2);
}

// the token of nlohmann's "number overflow parsing '1e309'"
std::string OverflowToken(const std::string& what) {
  const std::size_t open = what.find('\'');
  const std::size_t close = what.rfind('\'');
  if (open == std::string::npos || close <= open) return "a number";
  return what.substr(open + 1, close - open - 1);
}

// "a string "x"": the type and the value (shortened), as type errors show it
std::string Shown(const json& value) {
  if (value.is_null()) return "null";
  std::string text = value.dump();
  if (text.size() > 60) text = text.substr(0, 57) + "...";
  return JsonTypeName(value) + " " + text;
}

}  // namespace

std::size_t JsonDepthExceededAt(std::string_view text) {
  int depth = 0;
  bool in_string = false;
  bool escaped = false;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (in_string) {
      if (escaped) {
        escaped = false;
      } else if (c == '\\') {
        escaped = true;
      } else if (c == '"') {
        in_string = false;
      }
    } else if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      if (++depth > kMaxJsonDepth) return i;
    } else if (c == ']' || c == '}') {
      --depth;  // unbalanced text is the parser's to report
    }
  }
  return std::string_view::npos;
}

std::string JsonLineColumn(std::string_view text, std::size_t byte) {
  return LineColumn(text, byte + 1);
}

void JsonSource::Fail(std::string_view path, std::string_view message) const {
  std::string text = name_ + ": ";
  if (!path.empty()) text.append(path).append(": ");
  text.append(message);
  throw Error(text);
}

nlohmann::json ParseJsonText(std::string_view text, const JsonSource& source) {
  // checked before parsing: the parser and everything that walks its result recurse per level
  if (const std::size_t deep = JsonDepthExceededAt(text); deep != std::string_view::npos) {
    source.Fail("", "arrays and objects nested more than " + std::to_string(kMaxJsonDepth) +
                        " deep at " + JsonLineColumn(text, deep) +
                        " (the limit of every JSON input rigidtouch reads)");
  }
  PathTracker tracker;
  json document;
  try {
    document = json::parse(text.begin(), text.end(),
                           [&tracker](int /*depth*/, json::parse_event_t event, json& parsed) {
                             return tracker.Event(event, parsed);
                           });
  } catch (const json::parse_error& e) {
    const std::string field = tracker.Path();
    source.Fail("", "not valid JSON at " + LineColumn(text, e.byte) +
                        (field.empty() ? "" : " (reading field " + field + ")") + ": " +
                        JsonReason(e.what()));
  } catch (const json::out_of_range& e) {
    // 406: a number beyond the range of a double, which would otherwise become infinity
    source.Fail(tracker.Path(), OverflowToken(e.what()) + " is not a finite number");
  } catch (const json::exception& e) {
    source.Fail("", std::string("not valid JSON: ") + e.what());
  }
  if (!tracker.duplicate().empty()) {
    source.Fail(tracker.duplicate(), "the field is given twice; give it once");
  }
  return document;
}

nlohmann::json ReadJsonFile(const std::string& path, std::string_view what) {
  const std::string kind(what);
  std::error_code error;
  if (std::filesystem::is_directory(path, error)) {
    throw Error(path + ": is a directory, not a " + kind);
  }
  std::ifstream file(path, std::ios::binary);
  if (!file) throw Error(path + ": cannot open the " + kind);
  // read in chunks, and stop one chunk past the limit: a larger file, or an endless one (a
  // device, a pipe), is refused without being read whole
  std::string text;
  std::array<char, 1 << 16> chunk;
  while (file.read(chunk.data(), chunk.size()) || file.gcount() > 0) {
    text.append(chunk.data(), static_cast<std::size_t>(file.gcount()));
    if (text.size() > kMaxJsonFileBytes) {
      throw Error(path + ": the " + kind + " is larger than " +
                  std::to_string(kMaxJsonFileBytes >> 20) +
                  " MiB, the limit of every JSON file rigidtouch reads");
    }
  }
  if (file.bad()) throw Error(path + ": cannot read the " + kind);
  if (text::Trim(text).empty()) throw Error(path + ": the " + kind + " is empty");
  return ParseJsonText(text, JsonSource(path));
}

std::string JsonTypeName(const nlohmann::json& value) {
  if (value.is_null()) return "null";
  if (value.is_boolean()) return "a boolean";
  if (value.is_number()) return "a number";
  if (value.is_string()) return "a string";
  if (value.is_array()) return "an array";
  return "an object";
}

StrictObject::StrictObject(const JsonSource& source, const nlohmann::json& value, std::string path,
                           std::vector<std::string> valid_fields, std::string_view what)
    : source_(source),
      value_(value),
      path_(std::move(path)),
      valid_fields_(std::move(valid_fields)) {
  if (!value_.is_object()) {
    Fail("expected " + std::string(what) + " (a JSON object), got " + Shown(value_));
  }
  for (const auto& [key, unused] : value_.items()) {
    if (std::find(valid_fields_.begin(), valid_fields_.end(), key) == valid_fields_.end()) {
      Fail("unknown field " + text::Quote(key) + "; valid fields: " + text::Join(valid_fields_));
    }
  }
}

StrictObject StrictObject::Object(const std::string& key, std::vector<std::string> valid_fields,
                                  std::string_view what) const {
  if (!Has(key)) Fail("missing required field " + text::Quote(key));
  return StrictObject(source_, Get(key), Path(key), std::move(valid_fields), what);
}

std::string StrictObject::Path(const std::string& key) const {
  return path_.empty() ? key : path_ + "." + key;
}

void StrictObject::Fail(std::string_view message) const {
  source_.Fail(path_, message);
}

void StrictObject::FailAt(const std::string& key, std::string_view message) const {
  source_.Fail(Path(key), message);
}

std::optional<std::string> StrictObject::String(const std::string& key) const {
  if (!Has(key)) return std::nullopt;
  const json& v = Get(key);
  if (!v.is_string()) FailAt(key, "expected a string, got " + Shown(v));
  return v.get<std::string>();
}

std::string StrictObject::RequiredString(const std::string& key) const {
  std::optional<std::string> s = String(key);
  if (!s) Fail("missing required field " + text::Quote(key));
  if (s->empty()) FailAt(key, "must not be empty");
  return *s;
}

std::optional<std::string> StrictObject::OneOf(const std::string& key,
                                               const std::vector<std::string>& valid,
                                               std::string_view noun) const {
  std::optional<std::string> s = String(key);
  if (s && std::find(valid.begin(), valid.end(), *s) == valid.end()) {
    const std::string n(noun);
    FailAt(key,
           "unknown " + n + " " + text::Quote(*s) + "; valid " + n + "s: " + text::Join(valid));
  }
  return s;
}

std::optional<bool> StrictObject::Bool(const std::string& key) const {
  if (!Has(key)) return std::nullopt;
  const json& v = Get(key);
  if (!v.is_boolean()) FailAt(key, "expected true or false, got " + Shown(v));
  return v.get<bool>();
}

std::optional<double> StrictObject::Number(const std::string& key) const {
  if (!Has(key)) return std::nullopt;
  const json& v = Get(key);
  if (!v.is_number()) FailAt(key, "expected a number, got " + Shown(v));
  const double d = v.get<double>();
  // only a document built in code can hold one: parsing rejects 1e309, and JSON has no NaN
  if (!std::isfinite(d)) FailAt(key, text::FormatNumber(d) + " is not a finite number");
  return d;
}

int StrictObject::Integer(const std::string& key, int fallback, int lo, int hi) const {
  if (!Has(key)) return fallback;
  const json& v = Get(key);
  const std::string range = "valid: integers " + std::to_string(lo) + " to " + std::to_string(hi);
  if (!v.is_number_integer()) FailAt(key, "expected an integer, got " + v.dump() + "; " + range);
  // an unsigned above INT64_MAX would wrap in get<int64_t>
  if (v.is_number_unsigned() && v.get<std::uint64_t>() > static_cast<std::uint64_t>(hi)) {
    FailAt(key, v.dump() + " is out of range; " + range);
  }
  const auto i = v.get<std::int64_t>();
  if (i < lo || i > hi) FailAt(key, std::to_string(i) + " is out of range; " + range);
  return static_cast<int>(i);
}

std::optional<std::uint64_t> StrictObject::Unsigned(const std::string& key) const {
  if (!Has(key)) return std::nullopt;
  const json& v = Get(key);
  if (!v.is_number_unsigned()) {
    FailAt(key, "expected a non-negative integer below 2^64, got " + v.dump());
  }
  return v.get<std::uint64_t>();
}

void StrictObject::Read(const std::string& key, double& out) const {
  if (auto v = Number(key)) out = *v;
}

void StrictObject::Read(const std::string& key, bool& out) const {
  if (auto v = Bool(key)) out = *v;
}

void StrictObject::Read(const std::string& key, std::string& out) const {
  if (auto v = String(key)) out = *v;
}

}  // namespace rigidtouch::io
