// The study log: append-only JSON lines, one record per event. Each record is written with one
// write(2) on a descriptor opened with O_APPEND; answers (and session start/resume/end) are
// followed by fsync, so an acknowledged answer survives a crash. A crash can at worst leave an
// unterminated last line (a "torn tail"), which reading reports and resuming truncates. Anything
// else that is not a rigidtouch study log is refused and left byte-for-byte untouched.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "study/plan.h"
#include "study/protocol.h"

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

/// One answer record of a validated log.
struct LoggedAnswer {
  int step = 0;       ///< index in the plan
  int test = 0;       ///< index into Protocol::tests
  int series = 0;     ///< series number within the test
  int condition = 0;  ///< 0 to k - 1: the condition rendered (k: the test's conditions)
  int answer = 0;     ///< 0 to k - 1: the condition named
};

/// What a log that passed ValidateLog holds.
struct ValidLog {
  Protocol protocol;          ///< embedded in session_start, its hash checked
  std::string protocol_hash;  ///< ProtocolHash(protocol)
  std::string participant;
  std::string mode;  ///< "person" or "simulated"
  std::uint64_t seed = 0;
  std::vector<Step> plan;             ///< MakePlan(protocol, seed)
  int next_step = 0;                  ///< steps [0, next_step) are done
  bool ended = false;                 ///< a session_end record exists
  std::vector<LoggedAnswer> answers;  ///< in log order
};

/// The one check of a log's records, used by `study run --resume` (before continuing it) and
/// `study analyze` (before counting it), so that both accept and refuse the same logs with the
/// same message. Valid: the first record is this format's session_start with a valid participant
/// ID, mode, unsigned seed and an embedded protocol matching its hash; there is no second
/// session_start; every familiarization, series and answer record matches the step of the plan
/// its seed implies (answers 0 to k - 1 for a test of k conditions, at most one per step); the done
/// steps are a prefix of the plan. `source` names the log in errors. Throws rigidtouch::Error
/// "<source>: ..." otherwise.
ValidLog ValidateLog(const std::vector<nlohmann::json>& records, std::string_view source);

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
  /// untouched, if it is not a regular writable file (a symbolic link, FIFO or device is refused,
  /// io::CheckOutputPath), is locked by another session or is not a study log.
  static std::unique_ptr<LogFile> Open(const std::string& path);
  ~LogFile() override;
  LogFile(const LogFile&) = delete;
  LogFile& operator=(const LogFile&) = delete;

  /// The records found when the file was opened.
  const LogContents& contents() const { return contents_; }
  /// Truncates a torn tail (if any) so that the next record starts on a new line; fsyncs.
  void DropTornTail();
  /// Appends `record` as one line with a single write(2); fsyncs when `durable`. A failed write
  /// (disk full, file size limit) throws io::OutputError after taking back any partial line; if
  /// it was the first record of a log this Open created, the file is removed.
  void Append(const nlohmann::json& record, bool durable) override;
  /// The path the log was opened with.
  const std::string& path() const { return path_; }

 private:
  LogFile(int fd, std::string path, LogContents contents, std::size_t size_bytes);
  int fd_;
  std::string path_;
  LogContents contents_;
  std::size_t size_bytes_;
  bool created_ = false;  // this Open created the file (removed if its first record fails)
};

/// Serialises one record the way logs store it (compact JSON, invalid UTF-8 replaced).
std::string RecordLine(const nlohmann::json& record);

}  // namespace rigidtouch::study
