// A second thread for the tick (Model::threads 2): started when the Data is made (the Workspace
// owns it), it waits for a job, runs it, and says it is done. The stages that share work with it
// (collision, classification, contact forces, the group solves) take it as an argument. It lives
// in geometry/, the folder every other stage may include. Posting and finishing never allocate,
// lock or throw: the hand-off is three counters (a spin, then a futex sleep of bounded length:
// WakeCounter), so the haptic thread stays lock-free, and a job the worker has not taken when the
// tick's thread is ready for it is run on the tick's thread, so a worker that the system has not
// scheduled never holds the tick up (docs/decisions.md, "A second thread in the tick").
#pragma once

#include <atomic>
#include <cstdint>
#include <thread>

namespace rigidtouch::parallel {

/// Indices [begin, end) shared by two threads, one taking from the front and one from the back,
/// so that each takes what the other has not reached: the split follows the speed the threads
/// actually have. Taking is lock-free (one compare-exchange).
class TwoEndedRange {
 public:
  /// Sets the range; call before the other thread may take from it.
  void Reset(int begin, int end) { ends_.store(Pack(begin, end), std::memory_order_relaxed); }
  /// The lowest index left, taken; -1 when none is left.
  int TakeFront() { return Take(true); }
  /// The highest index left, taken; -1 when none is left.
  int TakeBack() { return Take(false); }

 private:
  static std::uint64_t Pack(int front, int back) {
    return static_cast<std::uint64_t>(static_cast<std::uint32_t>(front)) |
           static_cast<std::uint64_t>(static_cast<std::uint32_t>(back)) << 32;
  }
  int Take(bool front) {
    std::uint64_t now = ends_.load(std::memory_order_relaxed);
    for (;;) {
      const auto f = static_cast<int>(static_cast<std::uint32_t>(now));
      const auto b = static_cast<int>(static_cast<std::uint32_t>(now >> 32));
      if (f >= b) return -1;
      const std::uint64_t next = front ? Pack(f + 1, b) : Pack(f, b - 1);
      if (ends_.compare_exchange_weak(now, next, std::memory_order_relaxed)) {
        return front ? f : b - 1;
      }
    }
  }
  std::atomic<std::uint64_t> ends_{0};  // the front (low half) and the back (high half)
};

/// Work a stage's caller gives the tick's thread to do while the worker starts on the stage's
/// shared range (ShareRange's `before`): a function and its argument, so that it passes a stage's
/// interface without allocating. An empty task does nothing.
struct Task {
  void (*run)(void* context) = nullptr;
  void* context = nullptr;
  void operator()() const {
    if (run != nullptr) run(context);
  }
};

/// Work a stage runs for each item of its shared range once the stage's own work on it is done
/// (ShareRangeSides' side: 0 the tick's thread's end of the range, 1 the worker's), so that the
/// next stage's work on that item follows while its data is in the cache. An empty task does
/// nothing.
struct ItemTask {
  void (*run)(void* context, int item, int side) = nullptr;
  void* context = nullptr;
  void operator()(int item, int side) const {
    if (run != nullptr) run(context, item, side);
  }
};

/// A counter that one thread raises and another waits on until it changes: the waiter spins
/// for a number of polls, then sleeps on a futex, and never for longer than a bound, so that a
/// wake-up that is lost costs at most that bound instead of leaving the waiter asleep for good
/// (one was seen with C++20 atomic wait/notify: docs/decisions.md, "The real-time loop's worker
/// and the kernel's real-time throttle"). The
/// raising side wakes only when a waiter has said it sleeps (a seq_cst flag and a seq_cst store
/// on both sides, so that one of them always sees the other). Linux futexes; nothing allocates.
class WakeCounter {
 public:
  /// The value.
  std::uint32_t Load(std::memory_order order = std::memory_order_acquire) const {
    return value_.load(order);
  }
  /// Sets the value and wakes a thread sleeping on it. Every write before it is visible to the
  /// thread that sees the value.
  void Publish(std::uint32_t value);
  /// Adds one and wakes a thread sleeping on it; returns the new value.
  std::uint32_t Increment();
  /// Sets the value without waking anyone: what a lost wake-up looks like (for tests).
  void StoreWithoutWaking(std::uint32_t value) { value_.store(value); }
  /// Returns the value once it differs from `old`: `spins` polls, then sleeps of at most
  /// `sleep_limit_ns` each until it does.
  std::uint32_t AwaitChange(std::uint32_t old, int spins, long sleep_limit_ns) const;

 private:
  void WakeSleeper();
  std::atomic<std::uint32_t> value_{0};
  mutable std::atomic<std::uint32_t> sleepers_{0};  // threads that may be asleep on value_
};

class Worker {
 public:
  using Job = void (*)(void* context);

  /// Polls a waiting thread spends spinning before it sleeps on a counter (with PAUSE: some tens
  /// of microseconds): a job posted within that comes without a wake-up.
  static constexpr int kDefaultSpins = 2000;
  /// The longest a waiting thread sleeps before it looks again: the tick's thread waiting for a
  /// job the worker runs (a lost wake-up delays the tick by at most this), and the worker waiting
  /// for the next job (the tick's thread takes back what the worker has not started, so a late
  /// worker only misses work; a job that must run on the worker, Wait, waits at most this).
  static constexpr long kTickSleepLimitNs = 200'000;
  static constexpr long kWorkerSleepLimitNs = 5'000'000;

  /// Starts the thread. Throws Error if the system cannot start one. `spins`: the polls both
  /// threads spend before sleeping (0: sleep at once, as tests do to exercise the wake-ups);
  /// the sleep limits as above (tests lengthen them, so that a missing wake-up shows).
  explicit Worker(int spins = kDefaultSpins, long tick_sleep_limit_ns = kTickSleepLimitNs,
                  long worker_sleep_limit_ns = kWorkerSleepLimitNs);
  /// Stops the thread (after the job it may be running) and joins it.
  ~Worker();
  Worker(const Worker&) = delete;
  Worker& operator=(const Worker&) = delete;

  /// Offers job(context) to the worker thread. Every write before Post is visible to the job. At
  /// most one job at a time: call Finish before the next Post.
  void Post(Job job, void* context);
  /// Returns when the posted job has run, on the worker or, if the worker has not taken it yet,
  /// here on the calling thread; its writes are then visible to the caller.
  void Finish();
  /// Returns when the worker thread has run the posted job (never runs it here): for a job that
  /// must run on the worker, such as one that sets up the worker's own thread-local state.
  void Wait();
  /// Jobs that Finish ran on the calling thread, since the start.
  long jobs_taken_back() const { return taken_back_; }
  /// Jobs posted since the start (for the posting thread).
  long jobs_posted() const { return posted_.Load(std::memory_order_relaxed); }
  /// A range for the posting thread and the job to share (ShareRange).
  TwoEndedRange& range() { return range_; }
  /// The worker thread's handle, for a real-time loop that keeps it off its CPU
  /// (loop::LoopOptions::helper_threads).
  std::thread::native_handle_type native_handle() { return thread_.native_handle(); }

 private:
  void Loop();

  WakeCounter posted_;                   // jobs posted
  std::atomic<std::uint32_t> taken_{0};  // jobs taken, by the worker or back by Finish
  WakeCounter finished_;                 // the last job the worker ran to the end
  std::atomic<bool> quit_{false};
  const int spins_;
  const long tick_sleep_limit_ns_;
  const long worker_sleep_limit_ns_;
  Job job_ = nullptr;  // written before posted_ is raised, read by whoever takes the job
  void* context_ = nullptr;
  long taken_back_ = 0;  // the calling thread's own count
  TwoEndedRange range_;
  std::thread thread_;
};

/// Runs body(k) for every k in [0, n), once each: with a worker, shared through the worker's
/// range (this thread from the front, the worker from the back, until they meet); without one, in
/// order here. body must be safe to run for different k on the two threads at once. before(),
/// if given, runs first on this thread while the worker starts on the range: for work of the
/// tick's thread that the range's work neither reads nor writes. Never allocates.
///
/// ShareRangeSides calls body(k, side) instead: side 0 for the items this thread takes from the
/// front, 1 for those taken from the back (by the worker, or by this thread when Finish takes the
/// worker's job back, after its own), so that each side can have scratch of its own.
template <class Body, class Before>
void ShareRangeSides(Worker* worker, int n, const Body& body, const Before& before) {
  if (worker == nullptr) {
    before();
    for (int k = 0; k < n; ++k) body(k, 0);
    return;
  }
  struct Context {
    const Body* body;
    TwoEndedRange* range;
  } context{&body, &worker->range()};
  worker->range().Reset(0, n);
  worker->Post(
      [](void* c) {
        const auto* x = static_cast<const Context*>(c);
        for (int k = x->range->TakeBack(); k >= 0; k = x->range->TakeBack()) (*x->body)(k, 1);
      },
      &context);
  before();
  for (int k = worker->range().TakeFront(); k >= 0; k = worker->range().TakeFront()) body(k, 0);
  worker->Finish();
}

template <class Body, class Before>
void ShareRange(Worker* worker, int n, const Body& body, const Before& before) {
  ShareRangeSides(
      worker, n, [&body](int k, int) { body(k); }, before);
}

template <class Body>
void ShareRange(Worker* worker, int n, const Body& body) {
  ShareRange(worker, n, body, [] {});
}

}  // namespace rigidtouch::parallel
