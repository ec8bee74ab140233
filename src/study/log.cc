#include "study/log.h"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include <algorithm>
#include <limits>

#include "base/text.h"
#include "io/output_file.h"
#include "io/strict_json.h"
#include "rigidtouch/types.h"
#include "study/session.h"

namespace rigidtouch::study {

namespace {

using nlohmann::json;

std::string SystemError(const std::string& path, const std::string& what) {
  return path + ": " + what + " (" + std::strerror(errno) + ")";
}

// a string field of a record, or "" when it is absent or not a string (json::value throws on
// a present field of another type, and these records come from files a user may have edited)
std::string TextField(const json& record, const char* key) {
  if (!record.is_object()) return "";
  const auto it = record.find(key);
  return it != record.end() && it->is_string() ? it->get<std::string>() : std::string();
}

void CheckFirstRecord(const json& record, std::string_view source) {
  const bool ok = TextField(record, "type") == "session_start" &&
                  TextField(record, "format") == kLogFormat && record.contains("format_version") &&
                  record["format_version"].is_number_integer();
  if (!ok) {
    throw Error(std::string(source) +
                ": line 1 is not the session_start record of a rigidtouch study log; the file "
                "was not modified");
  }
  if (record["format_version"] != kLogFormatVersion) {
    throw Error(std::string(source) + ": log format version " + record["format_version"].dump() +
                " is not supported (this build reads version " + std::to_string(kLogFormatVersion) +
                "); the file was not modified");
  }
}

std::string ReadAll(int fd, const std::string& path) {
  std::string bytes;
  char buffer[1 << 16];
  off_t offset = 0;
  for (;;) {
    const ssize_t n = pread(fd, buffer, sizeof buffer, offset);
    if (n < 0) {
      if (errno == EINTR) continue;
      throw Error(SystemError(path, "cannot read the log"));
    }
    if (n == 0) break;
    bytes.append(buffer, static_cast<std::size_t>(n));
    offset += n;
  }
  return bytes;
}

int GetInt(const json& record, const char* key, const std::string& source, std::size_t i) {
  const bool in_range = record.contains(key) && record[key].is_number_integer() &&
                        record[key] >= std::numeric_limits<int>::min() &&
                        record[key] <= std::numeric_limits<int>::max();
  if (!in_range) {
    throw Error(source + ": record " + std::to_string(i + 1) + " (" + TextField(record, "type") +
                ") has no integer \"" + key + "\" (a number from " +
                std::to_string(std::numeric_limits<int>::min()) + " to " +
                std::to_string(std::numeric_limits<int>::max()) + ")");
  }
  return record[key].get<int>();
}

ValidLog Validate(const std::vector<json>& records, const std::string& src) {
  if (records.empty()) throw Error(src + ": empty log (no session)");
  const json& start = records[0];
  if (!start.is_object() || TextField(start, "type") != "session_start") {
    throw Error(src + ": does not start with a session_start record");
  }
  CheckFirstRecord(start, src);
  for (const char* key : {"protocol_hash", "participant", "mode"}) {
    if (start.contains(key) && !start[key].is_string()) {
      throw Error(src + ": malformed record: the session_start record's \"" + key + "\" is " +
                  start[key].dump() + ", not a string");
    }
  }
  ValidLog log;
  if (!start.contains("protocol")) {
    throw Error(src + ": the session_start record has no embedded protocol");
  }
  log.protocol = ParseProtocol(start["protocol"], src + " (embedded protocol)");
  log.protocol_hash = ProtocolHash(log.protocol);
  const std::string recorded_hash = TextField(start, "protocol_hash");
  if (recorded_hash != log.protocol_hash) {
    throw Error(src + ": the embedded protocol does not match its hash " +
                text::Quote(recorded_hash));
  }
  log.participant = TextField(start, "participant");
  try {
    CheckParticipantId(log.participant);
  } catch (const Error& e) {
    throw Error(src + ": the session_start record's " + e.what());
  }
  log.mode = TextField(start, "mode");
  if (log.mode != "person" && log.mode != "simulated") {
    throw Error(src + ": the session_start record's mode " + text::Quote(log.mode) +
                " is neither \"person\" nor \"simulated\"");
  }
  if (!start.contains("seed") || !start["seed"].is_number_unsigned()) {
    throw Error(src + ": the session_start record has no seed");
  }
  log.seed = start["seed"].get<std::uint64_t>();
  log.plan = MakePlan(log.protocol, log.seed);

  std::vector<bool> done(log.plan.size(), false);
  for (std::size_t i = 1; i < records.size(); ++i) {
    const json& r = records[i];
    const std::string type = TextField(r, "type");
    if (type == "session_start") {
      throw Error(src + ": record " + std::to_string(i + 1) + " starts a second session");
    }
    if (type == "session_end") log.ended = true;
    if (type != "familiarization" && type != "series" && type != "answer") continue;
    const int k = GetInt(r, "step", src, i);
    if (k < 0 || k >= static_cast<int>(log.plan.size())) {
      throw Error(src + ": record " + std::to_string(i + 1) + " refers to step " +
                  std::to_string(k) + ", outside the plan of " + std::to_string(log.plan.size()) +
                  " steps");
    }
    const Step& step = log.plan[k];
    const bool kind_ok = (type == "familiarization") == (step.kind == StepKind::kFamiliarization);
    const bool series_ok =
        step.kind != StepKind::kSeries || GetInt(r, "series", src, i) == step.series;
    if (!kind_ok || GetInt(r, "test", src, i) != step.test ||
        GetInt(r, "condition", src, i) != step.condition || !series_ok) {
      throw Error(src + ": record " + std::to_string(i + 1) + " does not match step " +
                  std::to_string(k) + " of the plan for seed " + std::to_string(log.seed) +
                  "; the log was not written by this protocol's plan");
    }
    if (type == "series") continue;  // presented but maybe unanswered: not done
    if (type == "answer") {
      const int answer = GetInt(r, "answer", src, i);
      const int choices = static_cast<int>(log.protocol.tests[step.test].conditions.size());
      if (answer < 0 || answer >= choices) {
        throw Error(src + ": record " + std::to_string(i + 1) + " has answer " +
                    std::to_string(answer) + "; valid answers: " +
                    (choices == 2 ? std::string("0, 1") : "0 to " + std::to_string(choices - 1)));
      }
      if (done[k]) {
        throw Error(src + ": two answers for step " + std::to_string(k) + " (record " +
                    std::to_string(i + 1) + ")");
      }
      log.answers.push_back({k, step.test, step.series, step.condition, answer});
    }
    done[k] = true;
  }
  // steps are done in order, so the done ones must be a prefix of the plan
  const auto first_open = std::find(done.begin(), done.end(), false);
  log.next_step = static_cast<int>(first_open - done.begin());
  if (std::find(first_open, done.end(), true) != done.end()) {
    throw Error(src + ": steps are recorded out of order (step " + std::to_string(log.next_step) +
                " is missing but later steps are done)");
  }
  return log;
}

}  // namespace

ValidLog ValidateLog(const std::vector<nlohmann::json>& records, std::string_view source) {
  const std::string src(source);
  try {
    return Validate(records, src);
  } catch (const json::exception& e) {
    // a field of the wrong type: the log was edited or written by something else
    throw Error(src + ": malformed record (" + e.what() + ")");
  }
}

LogContents ParseLog(std::string_view bytes, std::string_view source) {
  LogContents contents;
  std::size_t start = 0;
  int line_number = 0;
  while (start < bytes.size()) {
    const std::size_t end = bytes.find('\n', start);
    if (end == std::string_view::npos) break;
    ++line_number;
    const std::string_view line = bytes.substr(start, end - start);
    json record;
    if (const std::size_t deep = io::JsonDepthExceededAt(line); deep != std::string_view::npos) {
      throw Error(std::string(source) + ": line " + std::to_string(line_number) +
                  " nests arrays and objects more than " + std::to_string(io::kMaxJsonDepth) +
                  " deep (at byte " + std::to_string(deep + 1) +
                  " of the line); this is not a study log, so it was not modified");
    }
    try {
      record = json::parse(line);
    } catch (const json::parse_error& e) {
      throw Error(std::string(source) + ": line " + std::to_string(line_number) +
                  " is not JSON (error at byte " + std::to_string(e.byte) +
                  " of the line); this is not a study log (JSON lines), so it was not modified");
    } catch (const json::exception& e) {
      // e.g. 406, a number beyond a double's range (found by the study_log fuzzer)
      throw Error(std::string(source) + ": line " + std::to_string(line_number) +
                  " is not a study record (" + e.what() + "); the file was not modified");
    }
    if (!record.is_object() || !record.contains("type") || !record["type"].is_string()) {
      throw Error(std::string(source) + ": line " + std::to_string(line_number) +
                  " is not a study record (a JSON object with a \"type\"); the file was not "
                  "modified");
    }
    if (line_number == 1) CheckFirstRecord(record, source);
    contents.records.push_back(std::move(record));
    start = end + 1;
  }
  contents.valid_bytes = start;
  const std::size_t tail = bytes.size() - start;
  if (tail > 0) {
    if (contents.records.empty()) {
      throw Error(std::string(source) + ": no complete line (" + std::to_string(tail) +
                  " bytes without a line end); not a study log, or a session that crashed before "
                  "its first record (delete it to start again); the file was not modified");
    }
    if (bytes[start] != '{') {
      throw Error(std::string(source) +
                  ": the last line is neither a record nor the start of one; "
                  "this is not a study log (JSON lines), so it was not modified");
    }
    contents.torn_tail_bytes = tail;
  }
  return contents;
}

LogContents ReadLog(const std::string& path) {
  const int fd = open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) {
    if (errno == ENOENT) return {};
    throw Error(SystemError(path, "cannot open the log"));
  }
  struct stat st {};
  if (fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    close(fd);
    throw Error(path + ": not a regular file");
  }
  std::string bytes;
  try {
    bytes = ReadAll(fd, path);
  } catch (...) {
    close(fd);
    throw;
  }
  close(fd);
  return ParseLog(bytes, path);
}

void MemorySink::Append(const nlohmann::json& record, bool /*durable*/) {
  records.push_back(record);
}

std::string RecordLine(const nlohmann::json& record) {
  return record.dump(-1, ' ', false, json::error_handler_t::replace) + "\n";
}

LogFile::LogFile(int fd, std::string path, LogContents contents, std::size_t size_bytes)
    : fd_(fd), path_(std::move(path)), contents_(std::move(contents)), size_bytes_(size_bytes) {}

LogFile::~LogFile() {
  if (fd_ >= 0) close(fd_);
}

std::unique_ptr<LogFile> LogFile::Open(const std::string& path) {
  // a link, FIFO, device or read-only file is refused before anything is opened
  io::CheckOutputPath(path, "study log");
  // O_APPEND: every write lands at the end even if something else extended the file;
  // O_NOFOLLOW: a link put there since the check is refused, not written through
  const int flags = O_RDWR | O_APPEND | O_CLOEXEC | O_NOFOLLOW;
  bool created = true;
  int fd = open(path.c_str(), flags | O_CREAT | O_EXCL, 0644);
  if (fd < 0 && errno == EEXIST) {
    created = false;
    fd = open(path.c_str(), flags);
  }
  if (fd < 0) throw Error(SystemError(path, "cannot open or create the log"));
  try {
    struct stat st {};
    if (fstat(fd, &st) != 0) throw Error(SystemError(path, "cannot stat the log"));
    if (!S_ISREG(st.st_mode)) throw Error(path + ": not a regular file");
    if (flock(fd, LOCK_EX | LOCK_NB) != 0) {
      if (errno == EWOULDBLOCK) {
        throw Error(path + ": the log is in use by another running session");
      }
      throw Error(SystemError(path, "cannot lock the log"));
    }
    const std::string bytes = ReadAll(fd, path);
    LogContents contents = ParseLog(bytes, path);
    auto log = std::unique_ptr<LogFile>(new LogFile(fd, path, std::move(contents), bytes.size()));
    log->created_ = created;
    return log;
  } catch (...) {
    close(fd);
    if (created) unlink(path.c_str());
    throw;
  }
}

void LogFile::DropTornTail() {
  if (contents_.torn_tail_bytes == 0) return;
  if (ftruncate(fd_, static_cast<off_t>(contents_.valid_bytes)) != 0) {
    throw io::OutputError(SystemError(path_, "cannot truncate the torn last line"));
  }
  if (fsync(fd_) != 0) throw io::OutputError(SystemError(path_, "cannot sync the log"));
  size_bytes_ = contents_.valid_bytes;
  contents_.torn_tail_bytes = 0;
}

void LogFile::Append(const nlohmann::json& record, bool durable) {
  if (contents_.torn_tail_bytes != 0) DropTornTail();
  const std::string line = RecordLine(record);
  // normally one write(2); a short one is continued, and the error that cut it (EFBIG at the
  // file size limit, ENOSPC) is reported
  std::size_t done = 0;
  int error_number = 0;
  while (done < line.size()) {
    const ssize_t n = write(fd_, line.data() + done, line.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      error_number = n < 0 ? errno : EIO;
      break;
    }
    done += static_cast<std::size_t>(n);
  }
  if (done != line.size()) {
    const std::string reason = io::WriteFailureReason(error_number);
    if (created_ && size_bytes_ == 0) {
      // nothing of this session reached the log this run created: leave no empty log behind
      unlink(path_.c_str());
      throw io::OutputError(path_ + ": cannot write the first record (" + reason +
                            "); the log was not kept");
    }
    // a partial line would be a torn tail: take it back so the log stays whole lines
    if (ftruncate(fd_, static_cast<off_t>(size_bytes_)) != 0) {
      throw io::OutputError(path_ + ": cannot write a record (" + reason +
                            ") nor remove the partial line; resume will drop it");
    }
    throw io::OutputError(path_ + ": cannot write a record (" + reason +
                          "); the records before it are intact and the session can be resumed");
  }
  size_bytes_ += line.size();
  if (durable && fsync(fd_) != 0) {
    throw io::OutputError(path_ + ": cannot sync the log (" + io::WriteFailureReason(errno) + ")");
  }
}

}  // namespace rigidtouch::study
