// Runs the rigidtouch binary from a test and captures its exit code and output.
#pragma once

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <system_error>
#include <vector>

namespace rigidtouch::test {

struct CliResult {
  int exit_code = -1;
  std::string out;
  std::string err;
};

/// A fresh folder for one test's files, removed when the test process ends.
inline std::filesystem::path TempDir(const std::string& name) {
  struct Made {
    std::vector<std::filesystem::path> dirs;
    ~Made() {
      std::error_code ignored;
      for (const auto& dir : dirs) std::filesystem::remove_all(dir, ignored);
    }
  };
  static Made made;
  const auto dir = std::filesystem::temp_directory_path() /
                   ("rigidtouch_cli_" + name + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  made.dirs.push_back(dir);
  return dir;
}

inline std::string ReadAll(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

/// Runs `rigidtouch ARGS` through the shell with `env` prepended (e.g. "PYTHONPATH=x").
inline CliResult RunCli(const std::string& args, const std::string& env = "") {
  const auto dir = TempDir("run");
  const auto out = dir / "stdout", err = dir / "stderr";
  const std::string cmd = env + (env.empty() ? "" : " ") + RIGIDTOUCH_CLI + std::string(" ") +
                          args + " >" + out.string() + " 2>" + err.string();
  const int status = std::system(cmd.c_str());
  CliResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = ReadAll(out);
  r.err = ReadAll(err);
  std::filesystem::remove_all(dir);
  return r;
}

/// A UDP port that was free a moment ago on 127.0.0.1.
inline int FreePort() {
  const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  a.sin_port = 0;
  ::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a);
  socklen_t n = sizeof a;
  ::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &n);
  ::close(fd);
  return ntohs(a.sin_port);
}

/// Starts the shell command `command` in the background with stdout to `out`; returns its pid.
inline pid_t SpawnCommand(const std::string& command, const std::string& out) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    const std::string cmd = "exec " + command + " >" + out;
    ::execl("/bin/sh", "sh", "-c", cmd.c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  return pid;
}

/// Starts `rigidtouch ARGS` in the background with stdout to `out`; returns its pid.
inline pid_t Spawn(const std::string& args, const std::string& out) {
  return SpawnCommand(std::string(RIGIDTOUCH_CLI) + " " + args, out);
}

/// Waits for `pid`; its exit status, or -1 if it did not exit normally.
inline int Wait(pid_t pid) {
  int status = 0;
  ::waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

}  // namespace rigidtouch::test
