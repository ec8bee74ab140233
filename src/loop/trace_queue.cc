#include "loop/trace_queue.h"

#include <pthread.h>
#include <sched.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>
#include <utility>

#include "rigidtouch/types.h"

namespace rigidtouch::loop {
namespace {

// the writer hands the sink at most this many samples at once
constexpr std::size_t kMaxBatch = 4096;

std::size_t CheckedCapacity(std::size_t capacity) {
  if (capacity < 1) throw Error("trace queue: capacity = 0 is outside [1, inf) samples");
  return capacity;
}

std::chrono::nanoseconds CheckedIdlePeriod(double idle_period_s) {
  if (!(std::isfinite(idle_period_s) && idle_period_s > 0.0 && idle_period_s <= 1.0)) {
    throw Error("trace queue: idle_period_s = " + std::to_string(idle_period_s) +
                " is outside (0, 1] s");
  }
  return std::chrono::nanoseconds(std::llround(idle_period_s * 1e9));
}

}  // namespace

template <typename Sample>
SampleQueue<Sample>::SampleQueue(std::size_t capacity, Sink sink, double idle_period_s)
    : sink_(std::move(sink)),
      capacity_(CheckedCapacity(capacity)),
      idle_period_(CheckedIdlePeriod(idle_period_s)),
      queue_(capacity_),
      batch_(std::min(capacity, kMaxBatch)) {
  if (!sink_) throw Error("trace queue: the sink is empty");
  writer_ = std::thread([this] { WriterMain(); });
}

template <typename Sample>
bool SampleQueue<Sample>::AvoidCpu(int cpu) {
  if (cpu < 0 || cpu >= CPU_SETSIZE || !writer_.joinable()) return false;
  cpu_set_t cpus;
  if (sched_getaffinity(0, sizeof(cpus), &cpus) != 0) return false;
  CPU_CLR(cpu, &cpus);
  if (CPU_COUNT(&cpus) == 0) return false;
  return pthread_setaffinity_np(writer_.native_handle(), sizeof(cpus), &cpus) == 0;
}

template <typename Sample>
SampleQueue<Sample>::~SampleQueue() {
  try {
    Close();
  } catch (...) {
    // the destructor cannot report a sink failure; Close() exists for that
  }
}

template <typename Sample>
bool SampleQueue<Sample>::Push(const Sample& sample) noexcept {
  pushed_.fetch_add(1, std::memory_order_relaxed);
  if (closing_.load(std::memory_order_relaxed) || !queue_.push(sample)) {
    dropped_.fetch_add(1, std::memory_order_relaxed);
    return false;
  }
  return true;
}

template <typename Sample>
void SampleQueue<Sample>::Close() {
  if (closed_) return;
  closed_ = true;
  // release: every push before this store is visible to the writer's final drain
  closing_.store(true, std::memory_order_release);
  if (writer_.joinable()) writer_.join();
  if (sink_error_) std::rethrow_exception(std::exchange(sink_error_, nullptr));
}

template <typename Sample>
TraceQueueStats SampleQueue<Sample>::stats() const {
  TraceQueueStats out;
  out.pushed = pushed_.load(std::memory_order_relaxed);
  out.dropped = dropped_.load(std::memory_order_relaxed);
  out.written = written_.load(std::memory_order_relaxed);
  out.sink_failed = sink_failed_.load(std::memory_order_relaxed);
  out.capacity = capacity_;
  return out;
}

template <typename Sample>
void SampleQueue<Sample>::WriterMain() {
  for (;;) {
    // read the flag before draining, so a close is only acted on after a drain that follows it
    const bool closing = closing_.load(std::memory_order_acquire);
    std::size_t count = 0;
    while ((count = queue_.pop(batch_.data(), batch_.size())) > 0) {
      if (sink_error_) {
        sink_failed_.fetch_add(count, std::memory_order_relaxed);
        continue;
      }
      try {
        sink_(std::span<const Sample>(batch_.data(), count));
        written_.fetch_add(count, std::memory_order_relaxed);
      } catch (...) {
        sink_error_ = std::current_exception();
        sink_failed_.fetch_add(count, std::memory_order_relaxed);
      }
    }
    if (closing) return;
    std::this_thread::sleep_for(idle_period_);
  }
}

template class SampleQueue<TraceSample>;
template class SampleQueue<io::RecordSample>;

TraceQueue::Sink VectorSink(std::vector<TraceSample>* samples) {
  return [samples](std::span<const TraceSample> batch) {
    samples->insert(samples->end(), batch.begin(), batch.end());
  };
}

}  // namespace rigidtouch::loop
