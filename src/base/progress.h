// Progress of long work (a study simulation, a prediction, a comparison of renderers, a
// benchmark), reported for the person waiting: on stderr, never on stdout, where --json output
// goes. A terminal gets one bar redrawn in place; a file or pipe gets a line at most every two
// seconds. Nothing is printed during the first two seconds, so short runs stay silent.
//
// The same object carries the request to stop (SIGINT or SIGTERM, set by the CLI): long work
// checks StopRequested between units and ends cleanly, keeping what it finished, and the CLI then
// exits 128 + the signal's number (130 for Ctrl-C).
#pragma once

#include <atomic>
#include <iosfwd>
#include <stdexcept>
#include <string>
#include <string_view>

namespace rigidtouch {

/// Thrown by long work that stopped at a stop request (Progress::StopRequested); what it finished
/// is kept. The CLI prints the message with the prefix "rigidtouch: interrupted:" and exits
/// 128 + signal.
class Interrupted : public std::runtime_error {
 public:
  Interrupted(int signal, const std::string& what) : std::runtime_error(what), signal_(signal) {}
  /// The signal that asked to stop (2 for SIGINT).
  int signal() const { return signal_; }

 private:
  int signal_;
};

/// "0.4 s", "12 s", "3 min 05 s", "2 h 07 min": a duration for people.
std::string FormatDuration(double seconds);

/// Reports how far one task is. Not thread-safe: one thread reports.
class Progress {
 public:
  struct Options {
    bool enabled = true;         ///< false: print nothing (--quiet); stop requests still work
    bool terminal = false;       ///< redraw one bar in place (the stream is a terminal)
    double first_after_s = 2.0;  ///< print nothing before this much time has passed
    double every_s = 2.0;        ///< lines: at most one per this; a bar is redrawn at most 10/s
  };
  /// Seconds on a steady clock (tests pass their own).
  using Clock = double (*)();

  /// Reports `task` (e.g. "study simulate") on `out`. `stop` (may be null) is the flag a signal
  /// handler sets, `signal` where it records which signal it was (may be null).
  Progress(std::ostream& out, std::string task, Options options,
           const std::atomic<bool>* stop = nullptr, const std::atomic<int>* signal = nullptr,
           Clock clock = nullptr);
  ~Progress();
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

  /// Whether a report would print now (cheap: one clock read). Callers that must build the
  /// `where` text check this first.
  bool Due() const;
  /// Reports that `fraction` (0 to 1) of the task is done, `where` saying what it is at (e.g.
  /// "participant 3 of 10"). Prints if due; the remaining time is estimated from the rate since
  /// the first report (work done before, e.g. a resumed log, does not count as fast).
  void Report(double fraction, std::string_view where);
  /// Starts the next phase of the task under the name `task`: the remaining time is estimated
  /// from the new phase's reports only; the elapsed time counts from the construction.
  void Restart(std::string task);
  /// Ends the bar's line (a terminal) after something was printed. Called by the destructor too.
  void Finish();

  /// Whether a stop was requested (SIGINT or SIGTERM).
  bool StopRequested() const;
  /// Throws Interrupted("<task> stopped at <where>; <kept>") if a stop was requested.
  void ThrowIfStopped(std::string_view where, std::string_view kept) const;
  /// The signal that asked to stop; 2 (SIGINT) if none was recorded.
  int StopSignal() const;

  /// The text of a report at `now` seconds (no prefix, no newline): for tests.
  std::string Text(double fraction, std::string_view where, double now) const;
  /// Reports printed so far.
  int printed() const { return printed_; }

 private:
  double Now() const;

  std::ostream& out_;
  std::string task_;
  Options options_;
  const std::atomic<bool>* stop_;
  const std::atomic<int>* signal_;
  Clock clock_;
  double start_s_ = 0.0;
  double first_report_s_ = -1.0;  // time and fraction of the first report: the rate's origin
  double first_fraction_ = 0.0;
  double last_print_s_ = -1.0;
  int printed_ = 0;
  bool bar_open_ = false;
};

}  // namespace rigidtouch
