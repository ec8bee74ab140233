#include "parallel/worker.h"

#include <linux/futex.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <ctime>
#include <string>
#include <system_error>

#include "rigidtouch/types.h"

namespace rigidtouch::parallel {
namespace {

// tells the core that this is a spin (x86's PAUSE): a core shared with the tick's thread (two
// hardware threads of one core) then gives it more of its issue slots
inline void Relax() {
#if defined(__x86_64__) || defined(__i386__)
  __builtin_ia32_pause();
#endif
}

// sleeps while *word == old, for at most limit_ns (or until woken, or a signal)
void FutexSleep(const std::atomic<std::uint32_t>& word, std::uint32_t old, long limit_ns) {
  static_assert(sizeof(std::atomic<std::uint32_t>) == sizeof(std::uint32_t) &&
                std::atomic<std::uint32_t>::is_always_lock_free);
  timespec limit{};
  limit.tv_sec = limit_ns / 1'000'000'000;
  limit.tv_nsec = limit_ns % 1'000'000'000;
  syscall(SYS_futex, reinterpret_cast<const std::uint32_t*>(&word), FUTEX_WAIT_PRIVATE, old, &limit,
          nullptr, 0);
}

// takes job n (moves `taken` from n - 1 to n); false if the other thread took it first
bool Take(std::atomic<std::uint32_t>& taken, std::uint32_t n) {
  std::uint32_t expected = n - 1;
  return taken.compare_exchange_strong(expected, n, std::memory_order_acq_rel);
}

}  // namespace

void WakeCounter::WakeSleeper() {
  // seq_cst: the store above and this load, against the sleeper's flag and its load of the value
  if (sleepers_.load(std::memory_order_seq_cst) != 0) {
    syscall(SYS_futex, reinterpret_cast<std::uint32_t*>(&value_), FUTEX_WAKE_PRIVATE, 1, nullptr,
            nullptr, 0);
  }
}

void WakeCounter::Publish(std::uint32_t value) {
  value_.store(value, std::memory_order_seq_cst);
  WakeSleeper();
}

std::uint32_t WakeCounter::Increment() {
  const std::uint32_t now = value_.fetch_add(1, std::memory_order_seq_cst) + 1;
  WakeSleeper();
  return now;
}

std::uint32_t WakeCounter::AwaitChange(std::uint32_t old, int spins, long sleep_limit_ns) const {
  for (int i = 0; i < spins; ++i) {
    const std::uint32_t now = value_.load(std::memory_order_acquire);
    if (now != old) return now;
    Relax();
  }
  for (;;) {
    sleepers_.fetch_add(1, std::memory_order_seq_cst);
    if (value_.load(std::memory_order_seq_cst) == old) FutexSleep(value_, old, sleep_limit_ns);
    sleepers_.fetch_sub(1, std::memory_order_relaxed);
    const std::uint32_t now = value_.load(std::memory_order_acquire);
    if (now != old) return now;
  }
}

Worker::Worker(int spins, long tick_sleep_limit_ns, long worker_sleep_limit_ns)
    : spins_(spins),
      tick_sleep_limit_ns_(tick_sleep_limit_ns),
      worker_sleep_limit_ns_(worker_sleep_limit_ns) {
  try {
    thread_ = std::thread([this] { Loop(); });
  } catch (const std::system_error& e) {
    throw Error(std::string("could not start the worker thread (threads 2): ") + e.what());
  }
}

Worker::~Worker() {
  quit_.store(true, std::memory_order_relaxed);
  posted_.Increment();
  thread_.join();
}

void Worker::Post(Job job, void* context) {
  job_ = job;
  context_ = context;
  posted_.Increment();
}

void Worker::Finish() {
  const std::uint32_t n = posted_.Load(std::memory_order_relaxed);
  if (Take(taken_, n)) {
    ++taken_back_;
    job_(context_);
    return;
  }
  Wait();
}

void Worker::Wait() {
  const std::uint32_t n = posted_.Load(std::memory_order_relaxed);
  std::uint32_t now = finished_.Load();
  while (now != n) now = finished_.AwaitChange(now, spins_, tick_sleep_limit_ns_);
}

void Worker::Loop() {
  std::uint32_t seen = 0;
  for (;;) {
    seen = posted_.AwaitChange(seen, spins_, worker_sleep_limit_ns_);
    if (quit_.load(std::memory_order_relaxed)) return;
    // a job taken back by Finish is not run here; the next one is posted only after that
    if (!Take(taken_, seen)) continue;
    job_(context_);
    finished_.Publish(seen);
  }
}

}  // namespace rigidtouch::parallel
