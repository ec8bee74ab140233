#include "geometry/worker.h"

#include <string>
#include <system_error>

#include "rigidtouch/types.h"

namespace rigidtouch::geometry {
namespace {

// loads spent spinning before sleeping on the counter: a job of the tick comes back within
// microseconds, sooner than a sleep and wake-up take; a worker idle between ticks sleeps
constexpr int kSpins = 4000;

// returns the counter's value once it differs from `old`
std::uint32_t AwaitChange(const std::atomic<std::uint32_t>& counter, std::uint32_t old) {
  for (int i = 0; i < kSpins; ++i) {
    const std::uint32_t now = counter.load(std::memory_order_acquire);
    if (now != old) return now;
  }
  for (;;) {
    counter.wait(old, std::memory_order_acquire);
    const std::uint32_t now = counter.load(std::memory_order_acquire);
    if (now != old) return now;
  }
}

}  // namespace

Worker::Worker() {
  try {
    thread_ = std::thread([this] { Loop(); });
  } catch (const std::system_error& e) {
    throw Error(std::string("could not start the worker thread (threads 2): ") + e.what());
  }
}

Worker::~Worker() {
  quit_.store(true, std::memory_order_relaxed);
  posted_.fetch_add(1, std::memory_order_release);
  posted_.notify_one();
  thread_.join();
}

void Worker::Post(Job job, void* context) {
  job_ = job;
  context_ = context;
  posted_.fetch_add(1, std::memory_order_release);
  posted_.notify_one();
}

void Worker::Wait() {
  const std::uint32_t target = posted_.load(std::memory_order_relaxed);
  std::uint32_t now = finished_.load(std::memory_order_acquire);
  while (now != target) now = AwaitChange(finished_, now);
}

void Worker::Loop() {
  std::uint32_t seen = 0;
  for (;;) {
    seen = AwaitChange(posted_, seen);
    if (quit_.load(std::memory_order_relaxed)) return;
    job_(context_);
    finished_.store(seen, std::memory_order_release);
    finished_.notify_one();
  }
}

}  // namespace rigidtouch::geometry
