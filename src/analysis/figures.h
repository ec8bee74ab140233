// Runs the project's matplotlib scripts (python/plot_*.py) in a Python interpreter. Offline only:
// spawns a process and waits for it, never from the haptic loop.
#pragma once

#include <string>
#include <vector>

namespace rigidtouch::analysis {

/// How a plot script ended.
enum class FigureStatus {
  kOk,                  // exit code 0
  kMissingMatplotlib,   // exit code 3: the script could not import matplotlib
  kInterpreterMissing,  // neither /usr/bin/python3 nor python3 on PATH could be started
  kFailed,              // any other exit code or a signal
};

/// Outcome of RunPlotScript.
struct FigureResult {
  FigureStatus status = FigureStatus::kFailed;
  int exit_code = -1;       // the script's exit code, -1 if it did not exit normally
  std::string interpreter;  // the interpreter that ran (or was last tried)
  std::string output;       // the script's combined stdout and stderr
  /// A one-line description for the user, e.g. "matplotlib is not installed: ...".
  std::string message;
};

/// Runs `interpreter script args...`, where the interpreter is /usr/bin/python3 if it is
/// executable, else python3 from PATH. The script's stdout and stderr are captured (so a CLI
/// printing JSON on stdout stays clean), never thrown: every failure is in the result.
FigureResult RunPlotScript(const std::string& script, const std::vector<std::string>& args);

}  // namespace rigidtouch::analysis
