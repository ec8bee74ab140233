#include "loop/rate_loop.h"

#include <gtest/gtest.h>
#include <pthread.h>
#include <sched.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "limit_malloc.h"
#include "loop/trace_queue.h"
#include "rigidtouch/types.h"
#include "test_util.h"

namespace rigidtouch::loop {
namespace {

std::string MessageOf(const LoopOptions& options) {
  try {
    ValidateLoopOptions(options);
  } catch (const Error& error) {
    return error.what();
  }
  return "";
}

TEST(RateLoop, ValidationNamesTheField) {
  for (const double rate : {0.0, 0.5, 20000.5, -1.0, std::nan("")}) {
    LoopOptions options;
    options.rate_hz = rate;
    const std::string message = MessageOf(options);
    EXPECT_NE(message.find("rate_hz"), std::string::npos) << rate;
    EXPECT_NE(message.find("[1, 20000] Hz"), std::string::npos) << message;
  }
  LoopOptions options;
  options.rate_hz = 1000.0;
  options.spin_us = 1000.0;  // a whole period
  EXPECT_NE(MessageOf(options).find("spin_us"), std::string::npos);
  options.spin_us = -1.0;
  EXPECT_NE(MessageOf(options).find("spin_us"), std::string::npos);
  options.spin_us = 0.0;
  options.duration_s = -1.0;
  EXPECT_NE(MessageOf(options).find("duration_s"), std::string::npos);
  options.duration_s = 1e-5;  // less than one tick
  EXPECT_NE(MessageOf(options).find("duration_s"), std::string::npos);
  options.duration_s = 0.0;
  options.fifo_priority = 0;
  EXPECT_NE(MessageOf(options).find("fifo_priority"), std::string::npos);
  options.fifo_priority = 80;
  EXPECT_EQ(MessageOf(options), "");
  options.rate_hz = 1.0;
  EXPECT_EQ(MessageOf(options), "");
  options.rate_hz = 20000.0;
  EXPECT_EQ(MessageOf(options), "");
  options.rate_hz = 0.0;
  EXPECT_THROW(RateLoop{options}, Error);
}

TEST(RateLoop, RunsTheScheduledTicksAndReportsConsistentStats) {
  LoopOptions options;
  options.rate_hz = 2000.0;
  options.duration_s = 0.1;  // 200 deadlines
  RateLoop loop(options);
  std::vector<std::int64_t> ticks;
  std::vector<double> times_s;
  ticks.reserve(200);
  times_s.reserve(200);
  const LoopStats stats = loop.Run([&](std::int64_t tick, double t_s) {
    ticks.push_back(tick);
    times_s.push_back(t_s);
    return true;
  });
  // every deadline either ran a tick or was skipped after an overrun (a loaded machine)
  EXPECT_EQ(stats.ticks + stats.skipped_periods, 200);
  ASSERT_EQ(static_cast<std::int64_t>(ticks.size()), stats.ticks);
  for (std::size_t i = 0; i < ticks.size(); ++i) {
    EXPECT_EQ(ticks[i], static_cast<std::int64_t>(i));
    // t_s is the tick's deadline: slot / rate, slot >= tick; deadlines are rounded to 1 ns
    EXPECT_GE(times_s[i], static_cast<double>(i) / options.rate_hz - 1e-9);
    if (i > 0) {
      EXPECT_GT(times_s[i], times_s[i - 1]);
    }
  }
  EXPECT_EQ(times_s[0], 0.0);
  EXPECT_EQ(stats.rate_hz, 2000.0);
  EXPECT_EQ(stats.period_error_samples, static_cast<std::uint64_t>(stats.ticks - 1));
  EXPECT_LE(stats.period_error_p50_s, stats.period_error_p99_s);
  EXPECT_LE(stats.period_error_p99_s, stats.period_error_p999_s);
  EXPECT_LE(stats.period_error_p999_s, stats.period_error_max_s);
  EXPECT_GE(stats.period_error_mean_s, 0.0);
  // absolute deadlines: tick k starts no earlier than k periods after the first deadline, so
  // the achieved rate can never exceed the requested one (up to the 1 ns deadline rounding)
  EXPECT_GT(stats.achieved_rate_hz, 0.0);
  EXPECT_LE(stats.achieved_rate_hz, options.rate_hz * (1.0 + 1e-6));
  EXPECT_GE(stats.elapsed_s, static_cast<double>(stats.ticks - 1) / options.rate_hz - 1e-9);
  EXPECT_FALSE(stats.stop_requested);
  // a loaded machine may overrun: then, and only then, a warning says so
  EXPECT_EQ(stats.warnings.size(), stats.overruns > 0 ? 1u : 0u);
}

TEST(RateLoop, StepReturningFalseStops) {
  LoopOptions options;
  options.rate_hz = 5000.0;
  RateLoop loop(options);  // no duration: only the step can end it
  const LoopStats stats = loop.Run([](std::int64_t tick, double) { return tick < 9; });
  EXPECT_EQ(stats.ticks, 10);
  EXPECT_FALSE(stats.stop_requested);
}

TEST(RateLoop, StopFlagsEndTheRun) {
  LoopOptions options;
  options.rate_hz = 5000.0;
  RateLoop loop(options);
  std::atomic<bool> stop{false};
  LoopStats stats = loop.Run(
      [&](std::int64_t tick, double) {
        if (tick == 5) stop.store(true);
        return true;
      },
      &stop);
  EXPECT_EQ(stats.ticks, 6);
  EXPECT_TRUE(stats.stop_requested);

  stats = loop.Run([&](std::int64_t tick, double) {
    if (tick == 3) loop.RequestStop();
    return true;
  });
  EXPECT_EQ(stats.ticks, 4);
  EXPECT_TRUE(stats.stop_requested);
  // sticky until cleared
  stats = loop.Run([](std::int64_t, double) { return true; });
  EXPECT_EQ(stats.ticks, 0);
  loop.ClearStop();
  stats = loop.Run([](std::int64_t tick, double) { return tick < 2; });
  EXPECT_EQ(stats.ticks, 3);
}

TEST(RateLoop, StopFromAnotherThread) {
  LoopOptions options;
  options.rate_hz = 1000.0;
  RateLoop loop(options);
  std::atomic<std::int64_t> ticks_seen{0};
  std::thread stopper([&] {
    while (ticks_seen.load() < 10) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    loop.RequestStop();
  });
  const LoopStats stats = loop.Run([&](std::int64_t tick, double) {
    ticks_seen.store(tick + 1);
    return true;
  });
  stopper.join();
  EXPECT_TRUE(stats.stop_requested);
  EXPECT_GE(stats.ticks, 10);
}

TEST(RateLoop, OverrunsAreCountedAndWholeMissedPeriodsSkipped) {
  LoopOptions options;
  options.rate_hz = 1000.0;
  options.duration_s = 0.02;  // 20 deadlines
  RateLoop loop(options);
  const LoopStats stats = loop.Run([](std::int64_t tick, double) {
    // tick 2 takes >= 3 ms: the next deadline is >= 2 ms behind, so >= 2 periods are dropped
    if (tick == 2) std::this_thread::sleep_for(std::chrono::milliseconds(3));
    return true;
  });
  EXPECT_GE(stats.overruns, 1);
  EXPECT_GE(stats.skipped_periods, 2);
  EXPECT_EQ(stats.ticks + stats.skipped_periods, 20);
  // the interval around the slow tick is >= 3 ms against a 1 ms period
  EXPECT_GE(stats.period_error_max_s, 2e-3 - 1e-9);
  // and the run says so in a warning with the counts
  ASSERT_EQ(stats.warnings.size(), 1u);
  EXPECT_NE(stats.warnings[0].find(std::to_string(stats.overruns) + " of " +
                                   std::to_string(stats.ticks) + " ticks"),
            std::string::npos)
      << stats.warnings[0];
  EXPECT_NE(stats.warnings[0].find(std::to_string(stats.skipped_periods) + " whole periods"),
            std::string::npos)
      << stats.warnings[0];
}

TEST(RateLoop, SpinKeepsTheSchedule) {
  LoopOptions options;
  options.rate_hz = 4000.0;
  options.duration_s = 0.01;
  options.spin_us = 50.0;
  RateLoop loop(options);
  std::vector<double> times_s;
  times_s.reserve(40);
  const LoopStats stats = loop.Run([&](std::int64_t, double t_s) {
    times_s.push_back(t_s);
    return true;
  });
  EXPECT_EQ(stats.ticks + stats.skipped_periods, 40);
  EXPECT_GE(stats.wakeup_latency_max_s, 0.0);
}

TEST(RateLoop, RealtimeRequestsEitherTakeEffectOrWarn) {
  LoopOptions options;
  options.rate_hz = 1000.0;
  options.duration_s = 0.01;
  options.realtime_priority = true;
  options.lock_memory = true;
  RateLoop loop(options);
  int policy_inside = -1;
  const LoopStats stats = loop.Run([&](std::int64_t, double) {
    sched_param param{};
    pthread_getschedparam(pthread_self(), &policy_inside, &param);
    return true;
  });
  bool fifo_warning = false;
  bool memory_warning = false;
  for (const std::string& warning : stats.warnings) {
    fifo_warning |= warning.find("SCHED_FIFO") != std::string::npos;
    memory_warning |= warning.find("mlockall") != std::string::npos;
  }
  EXPECT_NE(stats.realtime_priority_active, fifo_warning);
  EXPECT_NE(stats.memory_locked, memory_warning);
  EXPECT_EQ(policy_inside == SCHED_FIFO, stats.realtime_priority_active);
  // the policy is restored after the run
  int policy_after = -1;
  sched_param param{};
  pthread_getschedparam(pthread_self(), &policy_after, &param);
  EXPECT_NE(policy_after, SCHED_FIFO);
}

TEST(RateLoop, PinningKeepsTheLoopOnItsCpuAndRestoresTheAffinity) {
  LoopOptions options;
  options.cpu = CPU_SETSIZE;
  EXPECT_NE(MessageOf(options).find("cpu"), std::string::npos);
  options.cpu = -2;
  EXPECT_NE(MessageOf(options).find("cpu"), std::string::npos);

  cpu_set_t before;
  ASSERT_EQ(pthread_getaffinity_np(pthread_self(), sizeof(before), &before), 0);
  int target = -1;  // the last CPU this process may use
  for (int c = 0; c < CPU_SETSIZE; ++c) {
    if (CPU_ISSET(c, &before)) target = c;
  }
  ASSERT_GE(target, 0);
  options.rate_hz = 1000.0;
  options.duration_s = 0.02;
  options.cpu = target;
  RateLoop loop(options);
  bool elsewhere = false;
  const LoopStats stats = loop.Run([&](std::int64_t, double) {
    elsewhere |= sched_getcpu() != target;
    return true;
  });
  if (stats.pinned_cpu == target) {
    EXPECT_FALSE(elsewhere);
  } else {  // refused: said so
    ASSERT_EQ(stats.warnings.size(), 1u);
    EXPECT_NE(stats.warnings[0].find("could not pin"), std::string::npos);
  }
  cpu_set_t after;
  ASSERT_EQ(pthread_getaffinity_np(pthread_self(), sizeof(after), &after), 0);
  EXPECT_TRUE(CPU_EQUAL(&before, &after));
}

// a thread that waits until told to end: a stand-in for the tick's worker
class IdleHelper {
 public:
  IdleHelper() : thread_([this] { ended_.wait(false); }) {}
  ~IdleHelper() {
    ended_.store(true);
    ended_.notify_one();
    thread_.join();
  }
  std::thread::native_handle_type handle() { return thread_.native_handle(); }

 private:
  std::atomic<bool> ended_{false};
  std::thread thread_;
};

TEST(RateLoop, HelperThreadsKeepOffThePinnedLoopsCpuAndKeepTheirPolicy) {
  const int target = test::LastCpuOfSeveral();
  if (target < 0) GTEST_SKIP() << "needs two CPUs";
  IdleHelper helper;
  int policy_before = -1;
  sched_param param_before{};
  ASSERT_EQ(pthread_getschedparam(helper.handle(), &policy_before, &param_before), 0);
  cpu_set_t cpus_before;
  ASSERT_EQ(pthread_getaffinity_np(helper.handle(), sizeof(cpus_before), &cpus_before), 0);

  LoopOptions options;
  options.rate_hz = 1000.0;
  options.duration_s = 0.01;
  options.realtime_priority = true;
  options.cpu = target;
  options.helper_threads.push_back(helper.handle());
  RateLoop loop(options);
  int policy_inside = -1;
  bool on_loop_cpu = true;
  const LoopStats stats = loop.Run([&](std::int64_t, double) {
    sched_param param{};
    pthread_getschedparam(helper.handle(), &policy_inside, &param);
    cpu_set_t cpus;
    pthread_getaffinity_np(helper.handle(), sizeof(cpus), &cpus);
    on_loop_cpu = CPU_ISSET(target, &cpus);
    return true;
  });
  EXPECT_EQ(stats.helper_threads, 1);
  // the loop's real-time policy is its own, not its helpers'
  EXPECT_EQ(policy_inside, policy_before);
  if (stats.pinned_cpu == target) {
    EXPECT_EQ(stats.helpers_off_loop_cpu, 1);
    EXPECT_FALSE(on_loop_cpu);
  }
  // restored after the run
  cpu_set_t cpus_after;
  ASSERT_EQ(pthread_getaffinity_np(helper.handle(), sizeof(cpus_after), &cpus_after), 0);
  EXPECT_TRUE(CPU_EQUAL(&cpus_before, &cpus_after));
}

constexpr std::int64_t kMs = 1'000'000;

TEST(BusyBudget, GivesNoVerdictBeforeAWholeWindow) {
  BusyBudget budget(0.9, 100 * kMs);
  budget.Sample(0, 0);
  budget.Sample(99 * kMs, 99 * kMs);  // busy all the time, but for less than a window
  EXPECT_FALSE(budget.Spent(99 * kMs));
  budget.Sample(101 * kMs, 101 * kMs);
  EXPECT_TRUE(budget.Spent(101 * kMs));
}

TEST(BusyBudget, ComparesTheCpuShareWithTheBudget) {
  // a thread charged 0.95 ms of every 1 ms: 95% > 90%
  BusyBudget busy(0.9, 100 * kMs);
  bool spent = false;
  for (std::int64_t k = 0; k < 300; ++k) {
    busy.Sample(k * kMs, k * 950'000);
    spent = busy.Spent(k * kMs);
  }
  EXPECT_TRUE(spent);
  // one charged 0.85 ms of every 1 ms: within 90%, never spent once a window has passed
  BusyBudget light(0.9, 100 * kMs);
  bool ever_spent = false;
  for (std::int64_t k = 0; k < 300; ++k) {
    light.Sample(k * kMs, k * 850'000);
    if (k >= 100) ever_spent |= light.Spent(k * kMs);
  }
  EXPECT_FALSE(ever_spent);
}

TEST(BusyBudget, ForgetsWhatLiesTwoWindowsBack) {
  BusyBudget budget(0.9, 100 * kMs);
  budget.Sample(0, 0);
  budget.Sample(150 * kMs, 150 * kMs);  // busy through the first window and half the second
  EXPECT_TRUE(budget.Spent(150 * kMs));
  // then idle for more than two windows: the old CPU time no longer counts
  budget.Sample(400 * kMs, 150 * kMs);
  budget.Sample(401 * kMs, 151 * kMs);
  EXPECT_FALSE(budget.Spent(401 * kMs));
}

TEST(BusyBudget, CountsTheCpuTimeOfTheWindowBefore) {
  BusyBudget budget(0.5, 100 * kMs);
  budget.Sample(0, 0);
  budget.Sample(90 * kMs, 80 * kMs);   // 80 ms of the first window's 90
  budget.Sample(110 * kMs, 80 * kMs);  // a new window, idle so far
  // 80 ms of 110: more than half
  EXPECT_TRUE(budget.Spent(110 * kMs));
  // 80 ms of 170: less than half
  EXPECT_FALSE(budget.Spent(170 * kMs));
}

// a 2.5 s SCHED_FIFO run whose steps busy-wait `step_us`: the stats, or nothing when this
// machine does not throttle or does not allow SCHED_FIFO (the caller skips)
std::optional<LoopStats> RunBusyRealtimeLoop(double rate_hz, double step_us) {
  if (RealtimeBusyShare() <= 0.0) return std::nullopt;
  LoopOptions options;
  options.rate_hz = rate_hz;
  options.duration_s = 2.5;  // the kernel's budget is per second: two periods of it and more
  options.realtime_priority = true;
  RateLoop loop(options);
  const auto step = std::chrono::nanoseconds(std::llround(step_us * 1e3));
  const LoopStats stats = loop.Run([step](std::int64_t, double) {
    const auto until = std::chrono::steady_clock::now() + step;
    while (std::chrono::steady_clock::now() < until) {
    }
    return true;
  });
  if (!stats.realtime_priority_active) return std::nullopt;
  return stats;
}

// every step busy for 1.2 periods: without yielding, the loop never sleeps, and at SCHED_FIFO the
// kernel stops it for ~50 ms once it has run for 95% of a second
TEST(RateLoop, ARealtimeLoopThatRunsLateSleepsBeforeTheKernelStopsIt) {
  const std::optional<LoopStats> stats = RunBusyRealtimeLoop(1000.0, 1200.0);
  if (!stats) GTEST_SKIP() << "no SCHED_FIFO, or no real-time throttle, here";
  EXPECT_GT(stats->yielded_periods, 0);
  EXPECT_LE(stats->yielded_periods, stats->skipped_periods);
  EXPECT_EQ(stats->ticks + stats->skipped_periods, 2500);
  // a step of 1.2 ms and a yielded period give gaps of at most ~3 ms; a throttled loop's is
  // ~50 ms. 20 ms leaves room for this shared machine's interruptions of a few ms
  EXPECT_LT(stats->period_error_max_s, 0.02);
  bool said = false;
  for (const std::string& warning : stats->warnings) {
    said |= warning.find(std::to_string(stats->yielded_periods) + " periods were slept through") !=
            std::string::npos;
  }
  EXPECT_TRUE(said);
}

// steps of 70% of a 100 us period: the loop sleeps between them, but on a virtual machine each
// sleep and wake-up is charged to the thread too (measured: 96% of its time), and the kernel
// stopped such a loop for ~50 ms when the budget counted only the steps. It counts the thread's
// CPU time, so the loop stays within the budget wherever it runs
TEST(RateLoop, ARealtimeLoopAtTenKilohertzIsNotStoppedByTheKernel) {
  const std::optional<LoopStats> stats = RunBusyRealtimeLoop(10000.0, 70.0);
  if (!stats) GTEST_SKIP() << "no SCHED_FIFO, or no real-time throttle, here";
  EXPECT_EQ(stats->ticks + stats->skipped_periods, 25000);
  EXPECT_LT(stats->period_error_max_s, 0.02);
}

TEST(RateLoop, AllocationCounterSeesAllocations) {
  if (!test::kMallocCounting) GTEST_SKIP() << "malloc is owned by the sanitizer";
  // the check below is only meaningful if the counter works
  test::LimitMalloc guard;
  auto value = std::make_unique<volatile int>(5);
  EXPECT_EQ(*value, 5);
  EXPECT_GT(guard.allocations(), 0);
}

TEST(RateLoop, NothingAllocatesBetweenTicks) {
  if (!test::kMallocCounting) GTEST_SKIP() << "malloc is owned by the sanitizer";
  LoopOptions options;
  options.rate_hz = 5000.0;
  options.duration_s = 0.0;  // a count of ticks, not of slots: a loaded machine skips slots
  RateLoop loop(options);
  TraceQueue traces(1024, [](std::span<const TraceSample>) {});
  long at_first_tick = 0;
  long at_last_tick = 0;
  test::LimitMalloc guard;  // the loop runs its ticks on this thread
  const LoopStats stats = loop.Run([&](std::int64_t tick, double t_s) {
    TraceSample sample;
    sample.step = tick;
    sample.time_s = t_s;
    traces.Push(sample);
    if (tick == 0) at_first_tick = guard.allocations();
    at_last_tick = guard.allocations();
    return tick + 1 < 100;
  });
  ASSERT_EQ(stats.ticks, 100);
  // the loop machinery (sleep, statistics) and Push between the first and last tick
  EXPECT_EQ(at_last_tick - at_first_tick, 0);
}

}  // namespace
}  // namespace rigidtouch::loop
