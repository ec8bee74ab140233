#include "analysis/figures.h"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

extern char** environ;

namespace rigidtouch::analysis {

namespace {

// spawns `argv` with stdout and stderr on a pipe, collects the output and waits; returns the
// wait status, or -1 with errno_out set when the process could not be started
int SpawnAndWait(const std::vector<std::string>& argv, bool search_path, std::string& output,
                 int& errno_out) {
  int fds[2];
  if (::pipe2(fds, O_CLOEXEC) != 0) {
    errno_out = errno;
    return -1;
  }
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, fds[1], STDOUT_FILENO);
  posix_spawn_file_actions_adddup2(&actions, fds[1], STDERR_FILENO);

  std::vector<char*> c_argv;
  for (const std::string& a : argv) c_argv.push_back(const_cast<char*>(a.c_str()));
  c_argv.push_back(nullptr);

  pid_t pid = 0;
  const int spawn_error =
      search_path ? posix_spawnp(&pid, c_argv[0], &actions, nullptr, c_argv.data(), environ)
                  : posix_spawn(&pid, c_argv[0], &actions, nullptr, c_argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  ::close(fds[1]);
  if (spawn_error != 0) {
    ::close(fds[0]);
    errno_out = spawn_error;
    return -1;
  }
  char buffer[4096];
  while (true) {
    const ssize_t n = ::read(fds[0], buffer, sizeof(buffer));
    if (n > 0) {
      output.append(buffer, static_cast<std::size_t>(n));
    } else if (n < 0 && errno == EINTR) {
      continue;
    } else {
      break;
    }
  }
  ::close(fds[0]);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) {
      errno_out = errno;
      return -1;
    }
  }
  return status;
}

// last non-empty line of the script's output, for a one-line message
std::string LastLine(const std::string& text) {
  std::size_t end = text.find_last_not_of("\r\n ");
  if (end == std::string::npos) return "";
  const std::size_t begin = text.rfind('\n', end);
  return text.substr(begin == std::string::npos ? 0 : begin + 1,
                     end - (begin == std::string::npos ? 0 : begin + 1) + 1);
}

}  // namespace

FigureResult RunPlotScript(const std::string& script, const std::vector<std::string>& args) {
  FigureResult result;
  const bool usr_bin = ::access("/usr/bin/python3", X_OK) == 0;
  result.interpreter = usr_bin ? "/usr/bin/python3" : "python3";

  std::vector<std::string> argv = {result.interpreter, script};
  argv.insert(argv.end(), args.begin(), args.end());
  int spawn_errno = 0;
  const int status = SpawnAndWait(argv, !usr_bin, result.output, spawn_errno);
  if (status == -1) {
    result.status = FigureStatus::kInterpreterMissing;
    result.message =
        "cannot run Python (" + result.interpreter + "): " + std::strerror(spawn_errno);
    return result;
  }
  if (WIFEXITED(status)) {
    result.exit_code = WEXITSTATUS(status);
    if (result.exit_code == 0) {
      result.status = FigureStatus::kOk;
      result.message = "figure written";
    } else if (result.exit_code == 3) {
      result.status = FigureStatus::kMissingMatplotlib;
      result.message = "matplotlib is not installed, no figure drawn: " + LastLine(result.output);
    } else if (result.exit_code == 127) {
      // the shell convention for "command not found", in case the spawn reports it this way
      result.status = FigureStatus::kInterpreterMissing;
      result.message = "cannot run Python (" + result.interpreter + ")";
    } else {
      result.status = FigureStatus::kFailed;
      result.message = "plot script " + script + " failed with exit code " +
                       std::to_string(result.exit_code) + ": " + LastLine(result.output);
    }
  } else {
    result.status = FigureStatus::kFailed;
    result.message = "plot script " + script + " was killed by signal " +
                     std::to_string(WIFSIGNALED(status) ? WTERMSIG(status) : 0);
  }
  return result;
}

}  // namespace rigidtouch::analysis
