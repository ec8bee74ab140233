// Runs the rigidtouch binary from a test and captures its exit code and output.
#pragma once

#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace rigidtouch::test {

struct CliResult {
  int exit_code = -1;
  std::string out;
  std::string err;
};

/// A fresh folder for one test's files.
inline std::filesystem::path TempDir(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("rigidtouch_cli_" + name + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
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

}  // namespace rigidtouch::test
