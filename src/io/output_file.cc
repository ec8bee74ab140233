#include "io/output_file.h"

#include <fcntl.h>
#include <signal.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <filesystem>
#include <system_error>

namespace rigidtouch::io {

namespace {

namespace fs = std::filesystem;

std::string ErrnoReason(int error_number) {
  return std::generic_category().message(error_number);
}

std::string Prefix(std::string_view what, const std::string& path) {
  return "cannot write " + std::string(what) + " '" + path + "': ";
}

// the folder a file at `path` goes into ("." for a bare name)
std::string FolderOf(const std::string& path) {
  const fs::path parent = fs::path(path).parent_path();
  return parent.empty() ? std::string(".") : parent.string();
}

// "" if `dir` is a writable folder, else why not
std::string FolderProblem(const std::string& dir) {
  struct stat st {};
  if (::stat(dir.c_str(), &st) != 0) {
    const int e = errno;
    if (e == ENOENT) return "folder '" + dir + "' does not exist (" + ErrnoReason(e) + ")";
    return "folder '" + dir + "': " + ErrnoReason(e);
  }
  if (!S_ISDIR(st.st_mode)) return "'" + dir + "' is not a folder";
  if (::access(dir.c_str(), W_OK | X_OK) != 0) {
    return "folder '" + dir + "' is not writable (" + ErrnoReason(errno) + ")";
  }
  // access() passes for root, and on file systems that take no new files (/proc, /sys): a file
  // created and removed at once is the only sure test, made before the run rather than after it
  std::string probe = (fs::path(dir) / ".rigidtouch-probe.XXXXXX").string();
  const int fd = ::mkstemp(probe.data());
  if (fd < 0) return "folder '" + dir + "' takes no new file (" + ErrnoReason(errno) + ")";
  ::close(fd);
  ::unlink(probe.c_str());
  return "";
}

const char* KindOf(mode_t mode) {
  if (S_ISLNK(mode)) return "a symbolic link";
  if (S_ISDIR(mode)) return "a folder";
  if (S_ISFIFO(mode)) return "a FIFO";
  if (S_ISCHR(mode) || S_ISBLK(mode)) return "a device";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a regular file";
}

bool WriteAll(int fd, std::string_view data) {
  const char* p = data.data();
  std::size_t left = data.size();
  while (left > 0) {
    const ssize_t n = ::write(fd, p, left);
    if (n < 0) {
      if (errno == EINTR) continue;
      return false;
    }
    p += n;
    left -= static_cast<std::size_t>(n);
  }
  return true;
}

}  // namespace

std::string WriteFailureReason(int error_number) {
  std::string reason = ErrnoReason(error_number);
  if (error_number == EFBIG) reason += "; the file size limit (ulimit -f) was reached";
  if (error_number == ENOSPC) reason += "; the disk is full";
  if (error_number == EDQUOT) reason += "; the disk quota is used up";
  return reason;
}

void CheckOutputPath(const std::string& path, std::string_view what) {
  if (path.empty()) throw Error("cannot write " + std::string(what) + ": the path is empty");
  if (path.back() == '/') throw Error(Prefix(what, path) + "it names a folder, not a file");
  const std::string problem = FolderProblem(FolderOf(path));
  if (!problem.empty()) throw Error(Prefix(what, path) + problem);
  struct stat st {};
  // lstat: a link is judged itself, never by what it points to
  if (::lstat(path.c_str(), &st) != 0) {
    if (errno == ENOENT) return;
    throw Error(Prefix(what, path) + ErrnoReason(errno));
  }
  if (!S_ISREG(st.st_mode)) {
    throw Error(Prefix(what, path) + "it is " + KindOf(st.st_mode) +
                "; only a regular file is replaced (give another name)");
  }
  // access() passes every check for root; the mode bits still say the user protected it
  if ((st.st_mode & 0222) == 0 || ::access(path.c_str(), W_OK) != 0) {
    throw Error(Prefix(what, path) + "it is read-only; it is not replaced (give another name)");
  }
}

void CheckOutputDir(const std::string& dir, std::string_view what) {
  if (dir.empty()) throw Error("cannot write " + std::string(what) + ": the folder name is empty");
  // the nearest part of the path that exists must be a writable folder
  fs::path existing = fs::path(dir);
  std::error_code ec;
  while (!existing.empty() && !fs::exists(fs::symlink_status(existing, ec))) {
    existing = existing.parent_path();
  }
  const std::string folder = existing.empty() ? std::string(".") : existing.string();
  const std::string problem = FolderProblem(folder);
  if (!problem.empty()) {
    throw Error("cannot write " + std::string(what) + " '" + dir + "': " + problem);
  }
}

void WriteFileAtomically(const std::string& path, std::string_view bytes, std::string_view what) {
  CheckOutputPath(path, what);
  // the temporary file sits in the target's folder so rename is atomic (same file system)
  std::string temp_path = path + ".tmp.XXXXXX";
  const int fd = ::mkstemp(temp_path.data());
  if (fd < 0) throw OutputError(Prefix(what, path) + WriteFailureReason(errno));
  const auto fail = [&](int error_number, bool open) {
    if (open) ::close(fd);
    ::unlink(temp_path.c_str());
    throw OutputError(Prefix(what, path) + WriteFailureReason(error_number));
  };
  // mkstemp creates 0600; give the file the usual permissions (subject to umask)
  const mode_t mask = ::umask(0);
  ::umask(mask);
  if (::fchmod(fd, 0666 & ~mask) != 0) fail(errno, true);
  if (!WriteAll(fd, bytes)) fail(errno, true);
  if (::fsync(fd) != 0) fail(errno, true);
  if (::close(fd) != 0) fail(errno, false);
  if (::rename(temp_path.c_str(), path.c_str()) != 0) fail(errno, false);
  // make the rename itself durable; a folder that cannot be synced loses nothing already written
  const int dir_fd = ::open(FolderOf(path).c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dir_fd >= 0) {
    ::fsync(dir_fd);
    ::close(dir_fd);
  }
}

void IgnoreFileSizeSignal() {
  ::signal(SIGXFSZ, SIG_IGN);
}

}  // namespace rigidtouch::io
