// The study log: append-only JSON lines, one record per event. Each record is written with one
// write(2) on a descriptor opened with O_APPEND; answers (and session start/resume/end) are
// followed by fsync, so an acknowledged answer survives a crash. A crash can at worst leave an
// unterminated last line (a "torn tail"), which reading reports and resuming truncates. Anything
// else that is not a rigidtouch study log is refused and left byte-for-byte untouched.
#pragma once

#include <cstddef>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

namespace rigidtouch::study {

/// Value of the "format" field of a log's first record.
inline constexpr std::string_view kLogFormat = "rigidtouch-study-log";
/// Value of the "format_version" field of a log's first record.
inline constexpr int kLogFormatVersion = 1;

/// The records of a log as found on disk.
struct LogContents {
  std::vector<nlohmann::json> records;  ///< complete lines, in file order
  std::size_t valid_bytes = 0;          ///< bytes up to and including the last complete line
  std::size_t torn_tail_bytes = 0;      ///< bytes of an unterminated last line (a torn write)
};

/// Parses the bytes of a log. Every complete line must be a JSON object with a string "type";
/// the first must be a "session_start" record of this format. An unterminated last line that
/// starts with '{' and follows at least one complete record is a torn tail; any other
/// unterminated text is an error. `source` names the log in error messages. Throws
/// rigidtouch::Error.
LogContents ParseLog(std::string_view bytes, std::string_view source);

/// Reads a log without modifying it; a missing file is an empty log. Throws rigidtouch::Error if
/// the file cannot be read or is not a study log.
LogContents ReadLog(const std::string& path);

/// Destination of session records.
class RecordSink {
 public:
  virtual ~RecordSink() = default;
  /// Appends one record. `durable` asks for it to be on stable storage before returning.
  /// Throws rigidtouch::Error if the record cannot be written.
  virtual void Append(const nlohmann::json& record, bool durable) = 0;
};

/// Keeps records in memory (simulated cohorts without a log directory, tests).
class MemorySink : public RecordSink {
 public:
  void Append(const nlohmann::json& record, bool durable) override;
  /// Everything appended so far, in order.
  std::vector<nlohmann::json> records;
};

/// A log file held open by one session: created if missing, locked against a second writer
/// (flock), checked, then appended to.
class LogFile : public RecordSink {
 public:
  /// Opens (creating if missing) and reads `path`. Throws rigidtouch::Error, leaving the file
  /// untouched, if it is not a regular file, is locked by another session or is not a study log.
  static std::unique_ptr<LogFile> Open(const std::string& path);
  ~LogFile() override;
  LogFile(const LogFile&) = delete;
  LogFile& operator=(const LogFile&) = delete;

  /// The records found when the file was opened.
  const LogContents& contents() const { return contents_; }
  /// Truncates a torn tail (if any) so that the next record starts on a new line; fsyncs.
  void DropTornTail();
  /// Appends `record` as one line with a single write(2); fsyncs when `durable`.
  void Append(const nlohmann::json& record, bool durable) override;
  /// The path the log was opened with.
  const std::string& path() const { return path_; }

 private:
  LogFile(int fd, std::string path, LogContents contents, std::size_t size_bytes);
  int fd_;
  std::string path_;
  LogContents contents_;
  std::size_t size_bytes_;
};

/// Serialises one record the way logs store it (compact JSON, invalid UTF-8 replaced).
std::string RecordLine(const nlohmann::json& record);

}  // namespace rigidtouch::study
