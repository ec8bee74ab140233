#include "loop/rate_loop.h"

#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <limits>
#include <string>

#include "rigidtouch/types.h"

namespace rigidtouch::loop {
namespace {

constexpr std::int64_t kNsPerS = 1'000'000'000;
// period-error histogram: 1 us bins up to 10 ms, plus an overflow bin
constexpr std::int64_t kHistogramBinNs = 1'000;
constexpr std::size_t kHistogramBins = 10'000;
// stack prefaulted when memory is locked, so the first deep call does not page-fault
constexpr std::size_t kPrefaultStackBytes = std::size_t{256} * 1024;
// BusyBudget's window: the CPU-time share is judged over the last 100-200 ms
constexpr std::int64_t kBusyWindowNs = 100'000'000;

std::int64_t ClockNs(clockid_t clock) noexcept {
  timespec now{};
  clock_gettime(clock, &now);
  return static_cast<std::int64_t>(now.tv_sec) * kNsPerS + now.tv_nsec;
}

std::int64_t NowNs() noexcept {
  return ClockNs(CLOCK_MONOTONIC);
}

// the calling thread's CPU time, as the kernel charges it (what its real-time throttle counts)
std::int64_t ThreadCpuNs() noexcept {
  return ClockNs(CLOCK_THREAD_CPUTIME_ID);
}

timespec ToTimespec(std::int64_t time_ns) noexcept {
  timespec out{};
  out.tv_sec = static_cast<time_t>(time_ns / kNsPerS);
  out.tv_nsec = static_cast<long>(time_ns % kNsPerS);
  return out;
}

[[noreturn]] void ThrowField(const std::string& field, double value, const std::string& range) {
  throw Error("loop options: " + field + " = " + std::to_string(value) + " is outside " + range);
}

__attribute__((noinline)) void PrefaultStack() {
  volatile unsigned char stack[kPrefaultStackBytes];
  for (std::size_t i = 0; i < kPrefaultStackBytes; i += 4096) stack[i] = 0;
  static_cast<void>(stack[0]);  // a volatile read: the writes above are kept
}

// sets SCHED_FIFO and locks memory for the duration of a run; restores both on exit
class RealtimeScope {
 public:
  RealtimeScope(const LoopOptions& options, LoopStats* stats) {
    if (options.realtime_priority) {
      if (pthread_getschedparam(pthread_self(), &old_policy_, &old_param_) == 0) {
        sched_param param{};
        param.sched_priority = options.fifo_priority;
        const int error = pthread_setschedparam(pthread_self(), SCHED_FIFO, &param);
        if (error == 0) {
          policy_changed_ = true;
          stats->realtime_priority_active = true;
        } else {
          stats->warnings.push_back(
              "could not set SCHED_FIFO priority " + std::to_string(options.fifo_priority) + ": " +
              std::strerror(error) +
              " (needs CAP_SYS_NICE or an rtprio limit); running at normal priority");
        }
      }
    }
    if (options.cpu >= 0) {
      cpu_set_t one;
      CPU_ZERO(&one);
      CPU_SET(options.cpu, &one);
      const int got = pthread_getaffinity_np(pthread_self(), sizeof(old_cpus_), &old_cpus_);
      const int error = got != 0 ? got : pthread_setaffinity_np(pthread_self(), sizeof(one), &one);
      if (error == 0) {
        pinned_ = true;
        stats->pinned_cpu = options.cpu;
      } else {
        stats->warnings.push_back("could not pin the loop to CPU " + std::to_string(options.cpu) +
                                  ": " + std::strerror(error) + "; running unpinned");
      }
    }
    if (options.lock_memory) {
      if (mlockall(MCL_CURRENT | MCL_FUTURE) == 0) {
        locked_ = true;
        stats->memory_locked = true;
        PrefaultStack();
      } else {
        stats->warnings.push_back(std::string("could not lock memory (mlockall): ") +
                                  std::strerror(errno) +
                                  " (needs CAP_IPC_LOCK or a larger RLIMIT_MEMLOCK); page faults "
                                  "may delay ticks");
      }
    }
  }
  ~RealtimeScope() {
    if (pinned_) pthread_setaffinity_np(pthread_self(), sizeof(old_cpus_), &old_cpus_);
    if (policy_changed_) pthread_setschedparam(pthread_self(), old_policy_, &old_param_);
    if (locked_) munlockall();
  }
  RealtimeScope(const RealtimeScope&) = delete;
  RealtimeScope& operator=(const RealtimeScope&) = delete;

 private:
  int old_policy_ = SCHED_OTHER;
  sched_param old_param_{};
  bool policy_changed_ = false;
  bool locked_ = false;
  cpu_set_t old_cpus_{};
  bool pinned_ = false;
};

// keeps the helper threads (the tick's worker) off the loop's pinned CPU for the duration of a
// run; restores their CPUs on exit. Allocates once, before the first tick. Their scheduling
// policy stays theirs (docs/decisions.md, "The real-time loop's worker and the kernel's
// real-time throttle": a SCHED_FIFO worker was tried and not kept)
class HelperScope {
 public:
  HelperScope(const LoopOptions& options, LoopStats* stats) {
    stats->helper_threads = static_cast<int>(options.helper_threads.size());
    if (options.cpu < 0) return;  // the loop is not pinned: nothing to keep off
    saved_.reserve(options.helper_threads.size());
    for (const std::thread::native_handle_type thread : options.helper_threads) {
      Saved h{thread, {}};
      // the CPUs the helper may use now, less the loop's
      int error = pthread_getaffinity_np(thread, sizeof(h.cpus), &h.cpus);
      cpu_set_t others = h.cpus;
      CPU_CLR(options.cpu, &others);
      if (error == 0) {
        error = CPU_COUNT(&others) == 0 ? EINVAL
                                        : pthread_setaffinity_np(thread, sizeof(others), &others);
      }
      if (error == 0) {
        saved_.push_back(h);
        ++stats->helpers_off_loop_cpu;
      } else {
        stats->warnings.push_back("could not keep the tick's worker thread off CPU " +
                                  std::to_string(options.cpu) + ": " + std::strerror(error));
      }
    }
  }
  ~HelperScope() {
    for (const Saved& h : saved_) pthread_setaffinity_np(h.thread, sizeof(h.cpus), &h.cpus);
  }
  HelperScope(const HelperScope&) = delete;
  HelperScope& operator=(const HelperScope&) = delete;

 private:
  struct Saved {
    std::thread::native_handle_type thread;
    cpu_set_t cpus;  // to restore
  };
  std::vector<Saved> saved_;  // the helpers kept off the loop's CPU
};

// after the run, never inside it: the loop only counts
void AddRunWarnings(double rate_hz, double busy_share, LoopStats* stats) {
  if (stats->overruns > 0) {
    stats->warnings.push_back(
        std::to_string(stats->overruns) + " of " + std::to_string(stats->ticks) +
        " ticks ended after the next deadline and " + std::to_string(stats->skipped_periods) +
        " whole periods were skipped: the loop did not keep " +
        std::to_string(static_cast<long long>(std::lround(rate_hz))) +
        " Hz here (a lower --rate, --realtime or a less loaded machine)");
  }
  if (stats->yielded_periods > 0) {
    stats->warnings.push_back(
        std::to_string(stats->yielded_periods) +
        " periods were slept through because the loop had run for more than " +
        std::to_string(static_cast<int>(std::lround(busy_share * 100.0))) +
        "% of its recent time: at SCHED_FIFO the kernel would otherwise have stopped it for the "
        "rest of its real-time period (sched_rt_runtime_us)");
  }
}

}  // namespace

BusyBudget::BusyBudget(double max_share, std::int64_t window_ns)
    : max_share_(max_share), window_ns_(window_ns) {}

void BusyBudget::Roll(std::int64_t now_ns) {
  const std::int64_t elapsed = now_ns - start_ns_;
  if (elapsed < window_ns_) return;
  // a window ended: it becomes the previous one, unless more than one has passed (then the
  // previous window was idle)
  previous_busy_ns_ = elapsed < 2 * window_ns_ ? std::min(busy_ns_, window_ns_) : 0;
  previous_length_ns_ = window_ns_;
  start_ns_ += (elapsed / window_ns_) * window_ns_;
  busy_ns_ = 0;
}

void BusyBudget::Sample(std::int64_t now_ns, std::int64_t cpu_ns) {
  if (start_ns_ < 0) {
    start_ns_ = now_ns;
    last_cpu_ns_ = cpu_ns;
    return;
  }
  Roll(now_ns);
  // the CPU time since the last sample, in the window it is seen in
  busy_ns_ += std::max<std::int64_t>(0, cpu_ns - last_cpu_ns_);
  last_cpu_ns_ = cpu_ns;
}

bool BusyBudget::Spent(std::int64_t now_ns) const {
  if (start_ns_ < 0) return false;
  const std::int64_t span = previous_length_ns_ + (now_ns - start_ns_);
  if (span < window_ns_) return false;
  return static_cast<double>(previous_busy_ns_ + busy_ns_) > max_share_ * static_cast<double>(span);
}

double RealtimeBusyShare() {
  constexpr double kDefault = 0.9;  // 950000 / 1000000, less the margin
  const auto read = [](const char* path, long long* value) {
    std::FILE* file = std::fopen(path, "r");
    if (file == nullptr) return false;
    const bool ok = std::fscanf(file, "%lld", value) == 1;
    std::fclose(file);
    return ok;
  };
  long long runtime_us = 0;
  long long period_us = 0;
  if (!read("/proc/sys/kernel/sched_rt_runtime_us", &runtime_us) ||
      !read("/proc/sys/kernel/sched_rt_period_us", &period_us) || period_us <= 0) {
    return kDefault;
  }
  if (runtime_us < 0) return 0.0;  // not throttled
  return std::clamp(static_cast<double>(runtime_us) / static_cast<double>(period_us) - 0.05, 0.05,
                    1.0);
}

void ValidateLoopOptions(const LoopOptions& options) {
  if (!(options.rate_hz >= 1.0 && options.rate_hz <= 20000.0)) {
    ThrowField("rate_hz", options.rate_hz, "[1, 20000] Hz");
  }
  if (!(std::isfinite(options.duration_s) && options.duration_s >= 0.0)) {
    ThrowField("duration_s", options.duration_s, "[0, inf) s (0 runs until stopped)");
  }
  if (options.duration_s > 0.0 && options.duration_s * options.rate_hz < 0.5) {
    ThrowField("duration_s", options.duration_s,
               "a range giving at least one tick at rate_hz = " + std::to_string(options.rate_hz));
  }
  const double period_us = 1e6 / options.rate_hz;
  if (!(options.spin_us >= 0.0 && options.spin_us < period_us)) {
    ThrowField("spin_us", options.spin_us, "[0, " + std::to_string(period_us) + ") us");
  }
  if (options.fifo_priority < 1 || options.fifo_priority > 99) {
    ThrowField("fifo_priority", options.fifo_priority, "[1, 99]");
  }
  if (options.cpu < -1 || options.cpu >= CPU_SETSIZE) {
    ThrowField("cpu", options.cpu, "[-1, " + std::to_string(CPU_SETSIZE) + ") (-1: not pinned)");
  }
}

RateLoop::RateLoop(const LoopOptions& options)
    : options_((ValidateLoopOptions(options), options)),
      period_error_(kHistogramBinNs, kHistogramBins) {}

bool RateLoop::StopRequested(const std::atomic<bool>* stop) const noexcept {
  return stop_requested_.load(std::memory_order_acquire) ||
         (stop != nullptr && stop->load(std::memory_order_acquire));
}

LoopStats RateLoop::RunImpl(StepFunction step, void* context, const std::atomic<bool>* stop) {
  LoopStats stats;
  stats.rate_hz = options_.rate_hz;
  stats.warnings.reserve(4);
  period_error_.Clear();
  const RealtimeScope realtime(options_, &stats);
  const HelperScope helpers(options_, &stats);

  // deadlines are computed from the slot index, so rounding never accumulates into drift
  const double period_ns = 1e9 / options_.rate_hz;
  const auto period_whole_ns = static_cast<std::int64_t>(std::llround(period_ns));
  const auto spin_ns = static_cast<std::int64_t>(std::llround(options_.spin_us * 1e3));
  // the duration is a number of schedule slots: skipped deadlines count against it
  const std::int64_t max_slots =
      options_.duration_s > 0.0
          ? std::max<std::int64_t>(1, std::llround(options_.duration_s * options_.rate_hz))
          : std::numeric_limits<std::int64_t>::max();
  const auto deadline_of = [&](std::int64_t slot) {
    return static_cast<std::int64_t>(std::llround(static_cast<double>(slot) * period_ns));
  };

  // the kernel's real-time throttle concerns SCHED_FIFO loops only (BusyBudget)
  const double busy_share = stats.realtime_priority_active ? RealtimeBusyShare() : 0.0;
  const bool guard_budget = busy_share > 0.0;
  BusyBudget budget(guard_budget ? busy_share : 1.0, kBusyWindowNs);
  const std::int64_t sample_every = std::max<std::int64_t>(1, std::llround(options_.rate_hz / 1e3));

  const std::int64_t start_ns = NowNs();
  std::int64_t slot = 0;
  std::int64_t previous_wake_ns = -1;
  std::int64_t last_wake_ns = start_ns;
  std::int64_t max_latency_ns = 0;
  std::int64_t end_ns = start_ns;
  while (slot < max_slots) {
    if (StopRequested(stop)) {
      stats.stop_requested = true;
      break;
    }
    const std::int64_t deadline_ns = start_ns + deadline_of(slot);
    const timespec sleep_until = ToTimespec(deadline_ns - spin_ns);
    // EINTR: a signal arrived; the stop check below returns promptly if it asked for a stop
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &sleep_until, nullptr) == EINTR &&
           !StopRequested(stop)) {
    }
    // a stop requested during the sleep wins over the step that was due
    if (StopRequested(stop)) {
      stats.stop_requested = true;
      break;
    }
    std::int64_t wake_ns = NowNs();
    while (wake_ns < deadline_ns) wake_ns = NowNs();  // the optional end-of-period spin

    max_latency_ns = std::max(max_latency_ns, wake_ns - deadline_ns);
    if (previous_wake_ns >= 0) {
      const std::int64_t interval_ns = wake_ns - previous_wake_ns;
      period_error_.Add(std::abs(interval_ns - period_whole_ns));
    }
    previous_wake_ns = wake_ns;
    last_wake_ns = wake_ns;

    const bool more =
        step(context, stats.ticks, static_cast<double>(deadline_ns - start_ns) * 1e-9);
    ++stats.ticks;
    end_ns = NowNs();
    if (!more) break;

    ++slot;
    const std::int64_t late_ns = end_ns - (start_ns + deadline_of(slot));
    // late by whole periods: drop those deadlines, keep at most one late tick
    std::int64_t drop = 0;
    if (late_ns > 0) {
      ++stats.overruns;
      drop = late_ns / period_whole_ns;
    }
    // never past the end of the run, so ticks + skipped_periods = the scheduled count
    const std::int64_t room = max_slots - slot;
    if (guard_budget) {
      // about once a millisecond: reading the thread's CPU time is a system call
      if (stats.ticks % sample_every == 0) budget.Sample(end_ns, ThreadCpuNs());
      // a SCHED_FIFO loop that has run for nearly all its recent time sleeps through the next
      // deadline, which the kernel's throttle would otherwise take ~50 ms later
      if (budget.Spent(end_ns) && drop < room) {
        ++drop;
        ++stats.yielded_periods;
      }
    }
    drop = std::min(drop, room);
    slot += drop;
    stats.skipped_periods += drop;
  }

  stats.elapsed_s = static_cast<double>(end_ns - start_ns) * 1e-9;
  if (stats.ticks >= 2 && last_wake_ns > start_ns) {
    stats.achieved_rate_hz = static_cast<double>(stats.ticks - 1) /
                             (static_cast<double>(last_wake_ns - start_ns) * 1e-9);
  }
  stats.period_error_samples = period_error_.count();
  stats.period_error_overflow = period_error_.overflow();
  stats.period_error_p50_s = period_error_.Percentile(0.5);
  stats.period_error_p99_s = period_error_.Percentile(0.99);
  stats.period_error_p999_s = period_error_.Percentile(0.999);
  stats.period_error_max_s = period_error_.max_s();
  stats.period_error_mean_s = period_error_.mean_s();
  stats.wakeup_latency_max_s = static_cast<double>(max_latency_ns) * 1e-9;
  AddRunWarnings(options_.rate_hz, busy_share, &stats);
  return stats;
}

}  // namespace rigidtouch::loop
