// Hands trace samples (and device records) from the real-time loop to a writer thread through a
// fixed-capacity lock-free single-producer/single-consumer queue (boost::lockfree::spsc_queue). The
// loop side never blocks: when the queue is full the sample is dropped and counted.
#pragma once

#include <atomic>
#include <boost/lockfree/spsc_queue.hpp>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <exception>
#include <functional>
#include <span>
#include <thread>
#include <vector>

#include "io/device_record.h"
#include "rigidtouch/trace.h"

namespace rigidtouch::loop {

/// Counts of a TraceQueue (consistent once Close() has returned: pushed = written + dropped +
/// sink_failed).
struct TraceQueueStats {
  std::uint64_t pushed = 0;       // Push calls
  std::uint64_t dropped = 0;      // Push calls that found the queue full
  std::uint64_t written = 0;      // samples the sink accepted
  std::uint64_t sink_failed = 0;  // samples discarded because the sink had thrown
  std::size_t capacity = 0;
};

/// A single-producer queue of samples (TraceSample, io::RecordSample) drained by its own writer
/// thread into a sink. Instantiated for those two types (trace_queue.cc).
template <typename Sample>
class SampleQueue {
 public:
  /// Receives batches of samples, in push order, on the writer thread. May throw: the writer
  /// then stops calling it, discards later samples and Close() rethrows the exception.
  using Sink = std::function<void(std::span<const Sample> batch)>;

  /// Allocates room for `capacity` samples and starts the writer thread, which polls every
  /// `idle_period_s` when the queue is empty. Throws Error when capacity < 1, idle_period_s is
  /// outside (0, 1] s or the sink is empty.
  SampleQueue(std::size_t capacity, Sink sink, double idle_period_s = 1e-3);
  /// Calls Close(), swallowing a sink exception (call Close() yourself to see it).
  ~SampleQueue();
  SampleQueue(const SampleQueue&) = delete;
  SampleQueue& operator=(const SampleQueue&) = delete;

  /// Producer side (one thread only): enqueues a copy of `sample`. Wait-free, allocation-free;
  /// returns false and counts a drop when the queue is full or closed.
  bool Push(const Sample& sample) noexcept;

  /// Waits until every sample pushed before the call reached the sink, then stops the writer
  /// thread. Idempotent. Call it from the producer thread or after the producer has stopped.
  /// Rethrows the sink's exception, once, if it threw.
  void Close();

  /// Keeps the writer thread off `cpu` (the haptic loop's, when it is pinned there): the writer
  /// may then run on every other CPU the process may use. False (nothing changed) if the system
  /// refuses or no other CPU is left.
  bool AvoidCpu(int cpu);

  /// Current counts (approximate while the queue is running).
  TraceQueueStats stats() const;

 private:
  void WriterMain();

  Sink sink_;
  std::size_t capacity_;
  std::chrono::nanoseconds idle_period_;
  boost::lockfree::spsc_queue<Sample> queue_;
  std::vector<Sample> batch_;  // writer-thread scratch, sized once
  std::atomic<bool> closing_{false};
  std::atomic<std::uint64_t> pushed_{0};
  std::atomic<std::uint64_t> dropped_{0};
  std::atomic<std::uint64_t> written_{0};
  std::atomic<std::uint64_t> sink_failed_{0};
  std::exception_ptr sink_error_;  // set by the writer, read after join
  bool closed_ = false;
  std::thread writer_;  // last: starts after every other member is ready
};

/// The loop's trace samples.
using TraceQueue = SampleQueue<TraceSample>;
/// Every tick's device state and command, for --record (io/device_record.h).
using RecordQueue = SampleQueue<io::RecordSample>;

extern template class SampleQueue<TraceSample>;
extern template class SampleQueue<io::RecordSample>;

/// A sink that appends every sample to `*samples` (reserve it first to avoid reallocation on the
/// writer thread). `samples` must outlive the queue.
TraceQueue::Sink VectorSink(std::vector<TraceSample>* samples);

}  // namespace rigidtouch::loop
