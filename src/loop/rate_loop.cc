#include "loop/rate_loop.h"

#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>

#include <cerrno>
#include <cmath>
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

std::int64_t NowNs() noexcept {
  timespec now{};
  clock_gettime(CLOCK_MONOTONIC, &now);
  return static_cast<std::int64_t>(now.tv_sec) * kNsPerS + now.tv_nsec;
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

}  // namespace

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
    if (late_ns > 0) {
      ++stats.overruns;
      // late by whole periods: drop those deadlines, keep at most one late tick
      // (never past the end of the run, so ticks + skipped_periods = the scheduled count)
      const std::int64_t whole_periods = std::min(late_ns / period_whole_ns, max_slots - slot);
      slot += whole_periods;
      stats.skipped_periods += whole_periods;
    }
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
  if (stats.overruns > 0) {
    // after the run, never inside it: the loop only counts
    stats.warnings.push_back(std::to_string(stats.overruns) + " of " + std::to_string(stats.ticks) +
                             " ticks ended after the next deadline and " +
                             std::to_string(stats.skipped_periods) +
                             " whole periods were skipped: the loop did not keep " +
                             std::to_string(static_cast<long long>(std::lround(options_.rate_hz))) +
                             " Hz here (a lower --rate, --realtime or a less loaded machine)");
  }
  return stats;
}

}  // namespace rigidtouch::loop
