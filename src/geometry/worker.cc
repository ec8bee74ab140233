#include "geometry/worker.h"

#include <string>
#include <system_error>

#include "rigidtouch/types.h"

namespace rigidtouch::geometry {
namespace {

// polls spent spinning before sleeping on a counter (with PAUSE, some tens of microseconds): a
// job posted within that comes without a wake-up; longer spins slowed the tick's own thread on
// the 2-core machine (docs/performance.md), and a worker that wakes late still takes its share,
// since the tick's thread does not wait for it to start (Finish, TwoEndedRange)
constexpr int kSpins = 2000;

// tells the core that this is a spin (x86's PAUSE): a core shared with the tick's thread (two
// hardware threads of one core) then gives it more of its issue slots
inline void Relax() {
#if defined(__x86_64__) || defined(__i386__)
  __builtin_ia32_pause();
#endif
}

// returns the counter's value once it differs from `old`
std::uint32_t AwaitChange(const std::atomic<std::uint32_t>& counter, std::uint32_t old) {
  for (int i = 0; i < kSpins; ++i) {
    const std::uint32_t now = counter.load(std::memory_order_acquire);
    if (now != old) return now;
    Relax();
  }
  for (;;) {
    counter.wait(old, std::memory_order_acquire);
    const std::uint32_t now = counter.load(std::memory_order_acquire);
    if (now != old) return now;
  }
}

// takes job n (moves `taken` from n - 1 to n); false if the other thread took it first
bool Take(std::atomic<std::uint32_t>& taken, std::uint32_t n) {
  std::uint32_t expected = n - 1;
  return taken.compare_exchange_strong(expected, n, std::memory_order_acq_rel);
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

void Worker::Finish() {
  const std::uint32_t n = posted_.load(std::memory_order_relaxed);
  if (Take(taken_, n)) {
    ++taken_back_;
    job_(context_);
    return;
  }
  Wait();
}

void Worker::Wait() {
  const std::uint32_t n = posted_.load(std::memory_order_relaxed);
  std::uint32_t now = finished_.load(std::memory_order_acquire);
  while (now != n) now = AwaitChange(finished_, now);
}

void Worker::Loop() {
  std::uint32_t seen = 0;
  for (;;) {
    seen = AwaitChange(posted_, seen);
    if (quit_.load(std::memory_order_relaxed)) return;
    // a job taken back by Finish is not run here; the next one is posted only after that
    if (!Take(taken_, seen)) continue;
    job_(context_);
    finished_.store(seen, std::memory_order_release);
    finished_.notify_one();
  }
}

}  // namespace rigidtouch::geometry
