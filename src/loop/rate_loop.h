// Fixed-rate loop with absolute deadlines (clock_nanosleep, TIMER_ABSTIME, on CLOCK_MONOTONIC),
// optional SCHED_FIFO priority, locked memory and an end-of-period spin, and timing statistics
// collected without allocation (OpenSurgSim BasicThread: sleep until start + k * period, no
// drift).
#pragma once

#include <atomic>
#include <cstdint>
#include <string>
#include <thread>
#include <type_traits>
#include <utility>
#include <vector>

#include "loop/timing_histogram.h"

namespace rigidtouch::loop {

/// Configuration of a RateLoop (immutable once the loop is built).
struct LoopOptions {
  double rate_hz = 1000.0;  // tick rate, in [1, 20000] Hz
  // run time: round(duration_s * rate_hz) deadlines (ticks + skipped periods); 0 runs until
  // the step returns false or a stop is requested
  double duration_s = 0.0;
  bool realtime_priority = false;  // try SCHED_FIFO for the calling thread during Run
  bool lock_memory = false;        // try mlockall(MCL_CURRENT | MCL_FUTURE) during Run
  double spin_us = 0.0;            // busy-wait this long before each deadline, in [0, period)
  int fifo_priority = 80;          // SCHED_FIFO priority when realtime_priority, in [1, 99]
  // pin the calling thread to this CPU during Run (-1: not pinned), in [-1, CPU_SETSIZE); a CPU
  // the process may not use is a warning, not an error (the loop then runs unpinned)
  int cpu = -1;
  // threads the step waits for (the tick's worker, Model::threads 2): when `cpu` is set they are
  // kept off it during Run, so that they never take the loop's CPU; restored after the run
  std::vector<std::thread::native_handle_type> helper_threads;
};

/// Throws Error naming the field, its value and the valid range when an option is invalid.
void ValidateLoopOptions(const LoopOptions& options);

/// The share of recent time a loop's thread has run, against a budget: Linux stops SCHED_FIFO
/// threads that use more than sched_rt_runtime_us of each sched_rt_period_us (95% of every
/// second by default) until the period ends, a stall of about 50 ms. A real-time loop whose steps
/// take (nearly) the whole period meets that limit; RateLoop samples its thread's CPU time (what
/// the kernel charges, sleeps and wake-ups included: at 10 kHz on a virtual machine those took a
/// quarter of each period) and, when the budget is spent, sleeps until the next deadline but one,
/// so the device misses one period instead of fifty. CPU time is counted over the current window
/// and the one before it; no verdict until a whole window has passed. Plain arithmetic, no
/// allocation.
class BusyBudget {
 public:
  /// `max_share` in (0, 1]; `window_ns` > 0.
  BusyBudget(double max_share, std::int64_t window_ns);
  /// At now_ns (monotonic, non-decreasing) the thread's CPU-time clock reads cpu_ns.
  void Sample(std::int64_t now_ns, std::int64_t cpu_ns);
  /// Whether the CPU time over the counted windows, up to now_ns, exceeds the share.
  bool Spent(std::int64_t now_ns) const;

 private:
  void Roll(std::int64_t now_ns);
  double max_share_;
  std::int64_t window_ns_;
  std::int64_t start_ns_ = -1;  // the current window's start; -1 before the first sample
  std::int64_t last_cpu_ns_ = 0;
  std::int64_t busy_ns_ = 0;  // CPU time in the current window
  std::int64_t previous_busy_ns_ = 0;
  std::int64_t previous_length_ns_ = 0;  // 0 until a window has ended
};

/// The share of each second a SCHED_FIFO loop may run before Linux throttles it, less a margin
/// of 5 points: from /proc/sys/kernel/sched_rt_runtime_us and sched_rt_period_us (0.9 with the
/// default 950000 / 1000000); 0 when the kernel does not throttle (runtime -1), and the default's
/// 0.9 when the files cannot be read.
double RealtimeBusyShare();

/// Timing statistics of one Run (plain data; loop_json.h turns it into JSON).
struct LoopStats {
  double rate_hz = 0.0;           // requested rate
  double achieved_rate_hz = 0.0;  // (ticks - 1) / (last tick's wake-up - first deadline); 0 if < 2
  double elapsed_s = 0.0;         // first deadline to the end of the last step
  std::int64_t ticks = 0;         // steps called
  std::int64_t overruns = 0;      // steps that ended after the next deadline
  std::int64_t skipped_periods = 0;  // deadlines dropped after an overrun longer than a period
  // of those, dropped so that a SCHED_FIFO loop stays within the kernel's real-time budget
  // (BusyBudget): the loop slept through one deadline instead of being stopped for ~50 ms
  std::int64_t yielded_periods = 0;
  // |wake-up interval - period| between consecutive ticks (ticks - 1 samples), 1 us bins
  double period_error_p50_s = 0.0;
  double period_error_p99_s = 0.0;
  double period_error_p999_s = 0.0;
  double period_error_max_s = 0.0;
  double period_error_mean_s = 0.0;
  std::uint64_t period_error_samples = 0;
  std::uint64_t period_error_overflow = 0;  // samples beyond the histogram's range (10 ms)
  double wakeup_latency_max_s = 0.0;        // largest delay from a deadline to its wake-up
  bool realtime_priority_active = false;    // SCHED_FIFO was set for this run
  bool memory_locked = false;               // mlockall succeeded for this run
  int pinned_cpu = -1;                      // the CPU the loop thread was pinned to, or -1
  int helper_threads = 0;                   // LoopOptions::helper_threads given
  int helpers_off_loop_cpu = 0;             // of them, kept off the loop's pinned CPU
  bool stop_requested = false;              // the run ended on a stop request
  std::vector<std::string> warnings;        // e.g. "could not set SCHED_FIFO: ..."
};

/// Runs a step function at a fixed rate on the calling thread. Tick k is due at
/// start + k * period; a step that overruns is followed at once by the next one (no sleep), and
/// an overrun longer than a whole period drops the missed deadlines (counted in skipped_periods)
/// instead of running a burst of catch-up steps. Between steps the loop neither allocates, locks,
/// does I/O nor throws.
class RateLoop {
 public:
  /// Validates the options (Error otherwise) and allocates the statistics buffers.
  explicit RateLoop(const LoopOptions& options);

  /// Calls `step(std::int64_t tick, double t_s) -> bool` at each deadline until the duration is
  /// reached, `step` returns false, RequestStop() is called, or `*stop` becomes true. `t_s` is the
  /// tick's deadline relative to the first one. Exceptions thrown by `step` propagate (after the
  /// scheduling policy and memory locking are restored). Not reentrant.
  template <typename Step>
  LoopStats Run(Step&& step, const std::atomic<bool>* stop = nullptr) {
    static_assert(std::is_invocable_r_v<bool, Step&, std::int64_t, double>,
                  "step must be callable as bool(std::int64_t tick, double t_s)");
    using StepType = std::remove_reference_t<Step>;
    const StepFunction call = [](void* context, std::int64_t tick, double t_s) -> bool {
      return (*static_cast<StepType*>(context))(tick, t_s);
    };
    return RunImpl(call, const_cast<void*>(static_cast<const void*>(&step)), stop);
  }

  /// Asks a running (or the next) Run to return before its next step. Thread-safe and
  /// async-signal-safe (one lock-free atomic store). Sticky until ClearStop().
  void RequestStop() noexcept { stop_requested_.store(true, std::memory_order_release); }
  /// Forgets an earlier RequestStop().
  void ClearStop() noexcept { stop_requested_.store(false, std::memory_order_release); }

  /// The validated options.
  const LoopOptions& options() const { return options_; }

 private:
  using StepFunction = bool (*)(void* context, std::int64_t tick, double t_s);
  LoopStats RunImpl(StepFunction step, void* context, const std::atomic<bool>* stop);
  bool StopRequested(const std::atomic<bool>* stop) const noexcept;

  LoopOptions options_;
  TimingHistogram period_error_;
  std::atomic<bool> stop_requested_{false};
  static_assert(std::atomic<bool>::is_always_lock_free);
};

}  // namespace rigidtouch::loop
