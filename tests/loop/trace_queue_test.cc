#include "loop/trace_queue.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <stdexcept>
#include <thread>
#include <vector>

#include "loop/test_poll.h"
#include "rigidtouch/types.h"

namespace rigidtouch::loop {
namespace {

TraceSample Sample(std::int64_t step) {
  TraceSample sample;
  sample.step = step;
  sample.time_s = 1e-3 * static_cast<double>(step);
  sample.device_force_N = Vec3(static_cast<double>(step), -1.0, 2.0);
  return sample;
}

TEST(TraceQueue, DeliversEverySampleInOrderWhenNotFull) {
  constexpr int kSamples = 10000;
  std::vector<TraceSample> written;
  written.reserve(kSamples);
  {
    TraceQueue queue(kSamples, VectorSink(&written));  // room for all: never full
    for (int i = 0; i < kSamples; ++i) ASSERT_TRUE(queue.Push(Sample(i)));
    queue.Close();
    const TraceQueueStats stats = queue.stats();
    EXPECT_EQ(stats.pushed, static_cast<std::uint64_t>(kSamples));
    EXPECT_EQ(stats.written, static_cast<std::uint64_t>(kSamples));
    EXPECT_EQ(stats.dropped, 0u);
    EXPECT_EQ(stats.capacity, static_cast<std::size_t>(kSamples));
  }
  ASSERT_EQ(written.size(), static_cast<std::size_t>(kSamples));
  for (int i = 0; i < kSamples; ++i) {
    EXPECT_EQ(written[i].step, i);
    EXPECT_EQ(written[i].device_force_N.x(), static_cast<double>(i));
  }
}

TEST(TraceQueue, CountsDropsWhenFullAndNeverBlocks) {
  std::atomic<bool> in_sink{false};
  std::atomic<bool> release{false};
  std::vector<std::int64_t> steps;
  TraceQueue queue(8, [&](std::span<const TraceSample> batch) {
    in_sink.store(true);
    while (!release.load()) std::this_thread::sleep_for(std::chrono::microseconds(100));
    for (const TraceSample& sample : batch) steps.push_back(sample.step);
  });
  // the writer takes sample 0 and blocks in the sink; the queue then holds 8 more
  ASSERT_TRUE(queue.Push(Sample(0)));
  ASSERT_TRUE(testing::PollUntil([&] { return in_sink.load(); }));
  int accepted = 0;
  for (int i = 1; i <= 20; ++i) accepted += queue.Push(Sample(i)) ? 1 : 0;
  EXPECT_EQ(accepted, 8);
  EXPECT_EQ(queue.stats().dropped, 12u);
  release.store(true);
  queue.Close();
  const TraceQueueStats stats = queue.stats();
  EXPECT_EQ(stats.pushed, 21u);
  EXPECT_EQ(stats.written, 9u);
  EXPECT_EQ(stats.pushed, stats.written + stats.dropped);
  EXPECT_EQ(steps, (std::vector<std::int64_t>{0, 1, 2, 3, 4, 5, 6, 7, 8}));
}

TEST(TraceQueue, ConcurrentProducerKeepsOrderAndAccountsForEverySample) {
  constexpr int kSamples = 200000;
  std::vector<std::int64_t> steps;
  steps.reserve(kSamples);
  TraceQueue queue(64, [&](std::span<const TraceSample> batch) {
    for (const TraceSample& sample : batch) steps.push_back(sample.step);
  });
  for (int i = 0; i < kSamples; ++i) queue.Push(Sample(i));
  queue.Close();
  const TraceQueueStats stats = queue.stats();
  EXPECT_EQ(stats.pushed, static_cast<std::uint64_t>(kSamples));
  EXPECT_EQ(stats.written + stats.dropped, stats.pushed);
  EXPECT_EQ(steps.size(), stats.written);
  // whatever was dropped, what arrives is in push order
  for (std::size_t i = 1; i < steps.size(); ++i) ASSERT_GT(steps[i], steps[i - 1]) << i;
}

TEST(TraceQueue, SinkExceptionIsRethrownByCloseAndLaterSamplesAreCounted) {
  TraceQueue queue(16, [](std::span<const TraceSample>) { throw std::runtime_error("disk full"); });
  for (int i = 0; i < 5; ++i) queue.Push(Sample(i));
  try {
    queue.Close();
    FAIL() << "expected the sink's exception";
  } catch (const std::runtime_error& error) {
    EXPECT_STREQ(error.what(), "disk full");
  }
  const TraceQueueStats stats = queue.stats();
  EXPECT_EQ(stats.written, 0u);
  EXPECT_EQ(stats.sink_failed + stats.dropped, 5u);
  EXPECT_NO_THROW(queue.Close());  // once only
}

TEST(TraceQueue, PushAfterCloseIsADrop) {
  std::vector<TraceSample> written;
  TraceQueue queue(4, VectorSink(&written));
  queue.Close();
  EXPECT_FALSE(queue.Push(Sample(1)));
  EXPECT_EQ(queue.stats().dropped, 1u);
  EXPECT_TRUE(written.empty());
}

TEST(TraceQueue, RejectsBadConfiguration) {
  EXPECT_THROW(TraceQueue(0, [](std::span<const TraceSample>) {}), Error);
  EXPECT_THROW(TraceQueue(4, TraceQueue::Sink{}), Error);
  EXPECT_THROW(TraceQueue(
                   4, [](std::span<const TraceSample>) {}, 0.0),
               Error);
  EXPECT_THROW(TraceQueue(
                   4, [](std::span<const TraceSample>) {}, 2.0),
               Error);
}

}  // namespace
}  // namespace rigidtouch::loop
