#include "study/log.h"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "rigidtouch/types.h"

namespace rigidtouch::study {

namespace {

using nlohmann::json;

std::string SystemError(const std::string& path, const std::string& what) {
  return path + ": " + what + " (" + std::strerror(errno) + ")";
}

void CheckFirstRecord(const json& record, std::string_view source) {
  const bool ok = record.value("type", "") == "session_start" &&
                  record.value("format", "") == kLogFormat && record.contains("format_version") &&
                  record["format_version"].is_number_integer();
  if (!ok) {
    throw Error(std::string(source) +
                ": line 1 is not the session_start record of a rigidtouch study log; the file "
                "was not modified");
  }
  if (record["format_version"].get<int>() != kLogFormatVersion) {
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

}  // namespace

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
    try {
      record = json::parse(line);
    } catch (const json::parse_error& e) {
      throw Error(std::string(source) + ": line " + std::to_string(line_number) +
                  " is not JSON (error at byte " + std::to_string(e.byte) +
                  " of the line); this is not a study log (JSON lines), so it was not modified");
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
  // O_APPEND: every write lands at the end even if something else extended the file
  const int fd = open(path.c_str(), O_RDWR | O_APPEND | O_CREAT | O_CLOEXEC, 0644);
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
    return std::unique_ptr<LogFile>(new LogFile(fd, path, std::move(contents), bytes.size()));
  } catch (...) {
    close(fd);
    throw;
  }
}

void LogFile::DropTornTail() {
  if (contents_.torn_tail_bytes == 0) return;
  if (ftruncate(fd_, static_cast<off_t>(contents_.valid_bytes)) != 0) {
    throw Error(SystemError(path_, "cannot truncate the torn last line"));
  }
  if (fsync(fd_) != 0) throw Error(SystemError(path_, "cannot sync the log"));
  size_bytes_ = contents_.valid_bytes;
  contents_.torn_tail_bytes = 0;
}

void LogFile::Append(const nlohmann::json& record, bool durable) {
  if (contents_.torn_tail_bytes != 0) DropTornTail();
  const std::string line = RecordLine(record);
  ssize_t written = -1;
  do {
    written = write(fd_, line.data(), line.size());
  } while (written < 0 && errno == EINTR);
  if (written != static_cast<ssize_t>(line.size())) {
    const std::string reason = written < 0 ? std::strerror(errno) : "short write";
    // a partial line would be a torn tail: take it back so the log stays whole lines
    if (written > 0 && ftruncate(fd_, static_cast<off_t>(size_bytes_)) != 0) {
      throw Error(path_ + ": cannot write a record (" + reason +
                  ") nor remove the partial line; resume will drop it");
    }
    throw Error(path_ + ": cannot write a record (" + reason + ")");
  }
  size_bytes_ += line.size();
  if (durable && fsync(fd_) != 0) throw Error(SystemError(path_, "cannot sync the log"));
}

}  // namespace rigidtouch::study
