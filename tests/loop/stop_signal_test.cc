#include "loop/stop_signal.h"

#include <gtest/gtest.h>
#include <pthread.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <thread>

#include "loop/rate_loop.h"

namespace rigidtouch::loop {
namespace {

TEST(StopSignal, SigintAndSigtermSetTheFlag) {
  const std::atomic<bool>& stop = InstallStopSignalHandlers();
  EXPECT_EQ(&stop, &InstallStopSignalHandlers()) << "idempotent: one process-wide flag";
  ResetStopSignalFlag();
  EXPECT_FALSE(stop.load());
  std::raise(SIGINT);
  EXPECT_TRUE(stop.load());
  ResetStopSignalFlag();
  std::raise(SIGTERM);
  EXPECT_TRUE(stop.load());
  ResetStopSignalFlag();
}

TEST(StopSignal, InterruptsASleepingLoop) {
  const std::atomic<bool>& stop = InstallStopSignalHandlers();
  ResetStopSignalFlag();
  LoopOptions options;
  options.rate_hz = 1.0;  // a one-second sleep after the first tick
  RateLoop loop(options);
  std::atomic<bool> first_tick_done{false};
  const pthread_t loop_thread = pthread_self();
  std::thread signaller([&] {
    while (!first_tick_done.load()) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    pthread_kill(loop_thread, SIGINT);
  });
  const LoopStats stats = loop.Run(
      [&](std::int64_t, double) {
        first_tick_done.store(true);
        return true;
      },
      &stop);
  signaller.join();
  EXPECT_TRUE(stats.stop_requested);
  EXPECT_EQ(stats.ticks, 1) << "the stop arrived during the sleep before tick 1";
  // generous bound: without EINTR handling the loop would sleep the whole 1 s period
  EXPECT_LT(stats.elapsed_s, 0.9);
  ResetStopSignalFlag();
}

}  // namespace
}  // namespace rigidtouch::loop
