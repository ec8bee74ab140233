// The one strict JSON reader of rigidtouch's input files (config, study protocols, observer
// parameters). Every problem is thrown as rigidtouch::Error with one prefix,
//   "<file>: <field path>: <what is wrong>"   (no field path for the whole document),
// naming the bad value, so a user can fix the file without guessing.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

namespace rigidtouch::io {

/// Where a JSON document came from (usually the file path); builds and throws the errors.
class JsonSource {
 public:
  explicit JsonSource(std::string_view name) : name_(name) {}

  const std::string& name() const { return name_; }

  /// Throws Error "<name>: <path>: <message>", or "<name>: <message>" for an empty path.
  [[noreturn]] void Fail(std::string_view path, std::string_view message) const;

 private:
  std::string name_;
};

/// The deepest nesting of arrays and objects a JSON input may have (rigidtouch's own files nest
/// at most 5 deep). Deeper text is refused before it is parsed, whatever reads it.
inline constexpr int kMaxJsonDepth = 64;

/// The largest JSON file rigidtouch reads (64 MiB; its own are a few kilobytes). A larger file,
/// or an endless one (a device, a pipe), is refused after reading one byte more than this.
inline constexpr std::size_t kMaxJsonFileBytes = std::size_t{64} << 20;

/// The byte offset at which `text` opens its (kMaxJsonDepth + 1)-th nested array or object, or
/// std::string_view::npos when it nests no deeper than kMaxJsonDepth. Brackets inside strings do
/// not count. Linear in the text and without recursion, so any input is safe to give it.
std::size_t JsonDepthExceededAt(std::string_view text);

/// "line L, column C" of byte `byte` of `text` (1-based), as errors give positions.
std::string JsonLineColumn(std::string_view text, std::size_t byte);

/// Parses JSON text. Errors name the source; text nested deeper than kMaxJsonDepth is refused with
/// its line and column; malformed text gives the line and column (and the
/// field being read, when known), a number too large for a double names its field, and a field
/// given twice in one object is an error (a strict reader does not pick one of them).
nlohmann::json ParseJsonText(std::string_view text, const JsonSource& source);

/// Reads and parses the file at `path`. `what` names the kind of file in errors ("config file").
/// Errors: the file cannot be opened or read, is larger than kMaxJsonFileBytes, is empty (or only
/// white space), or ParseJsonText's.
nlohmann::json ReadJsonFile(const std::string& path, std::string_view what);

/// The type of a JSON value as messages say it: "null", "a boolean", "a number", "a string",
/// "an array", "an object".
std::string JsonTypeName(const nlohmann::json& value);

/// A strict view of one JSON object: construction rejects a non-object and any field not in
/// `valid_fields` (the message lists them); the getters check the type and name the field's path
/// and the bad value. Absent fields read as std::nullopt (or the fallback). The source and the
/// value are referenced, not copied: both must outlive the reader.
class StrictObject {
 public:
  /// `path` is the object's field path ("" for the document); `what` describes it in the error
  /// for a non-object ("a protocol", "the contact section").
  StrictObject(const JsonSource& source, const nlohmann::json& value, std::string path,
               std::vector<std::string> valid_fields, std::string_view what = "an object");

  /// A field that must itself be an object, read strictly with its own valid fields.
  StrictObject Object(const std::string& key, std::vector<std::string> valid_fields,
                      std::string_view what) const;

  bool Has(const std::string& key) const { return value_.contains(key); }
  /// The raw value of a present field (for structures the getters do not cover).
  const nlohmann::json& Get(const std::string& key) const { return value_.at(key); }
  /// The path of a field: "contact.stiffness_N_per_m", or "name" at the top level.
  std::string Path(const std::string& key) const;
  const std::string& path() const { return path_; }
  const JsonSource& source() const { return source_; }
  const std::vector<std::string>& valid_fields() const { return valid_fields_; }

  /// Throws at this object's path.
  [[noreturn]] void Fail(std::string_view message) const;
  /// Throws at the path of `key`.
  [[noreturn]] void FailAt(const std::string& key, std::string_view message) const;

  /// A string field.
  std::optional<std::string> String(const std::string& key) const;
  /// A string field that must be present and not empty.
  std::string RequiredString(const std::string& key) const;
  /// A string field that must be one of `valid`; `noun` names them in the error
  /// ("unknown renderer "x"; valid renderers: penalty, impulse, train").
  std::optional<std::string> OneOf(const std::string& key, const std::vector<std::string>& valid,
                                   std::string_view noun) const;
  /// A boolean field.
  std::optional<bool> Bool(const std::string& key) const;
  /// A number field; it must be finite.
  std::optional<double> Number(const std::string& key) const;
  /// An integer field in [lo, hi]; `fallback` when absent.
  int Integer(const std::string& key, int fallback, int lo, int hi) const;
  /// A non-negative integer field below 2^64.
  std::optional<std::uint64_t> Unsigned(const std::string& key) const;

  /// Assign a present field to `out` (absent: `out` is left as it is).
  void Read(const std::string& key, double& out) const;
  void Read(const std::string& key, bool& out) const;
  void Read(const std::string& key, std::string& out) const;

 private:
  const JsonSource& source_;
  const nlohmann::json& value_;
  std::string path_;
  std::vector<std::string> valid_fields_;
};

}  // namespace rigidtouch::io
