// A second thread for the tick (Model::threads 2): started when the Data is made (the Workspace
// owns it), it waits for a job, runs it, and says it is done. The stages that share work with it
// (collision, classification, contact forces, the group solves) take it as an argument. It lives
// in geometry/, the folder every other stage may include. Posting and finishing never allocate,
// lock or throw: the hand-off is three counters (C++20 atomic wait / notify after a spin), so the
// haptic thread stays lock-free, and a job the worker has not taken when the tick's thread is
// ready for it is run on the tick's thread, so a worker that the system has not scheduled never
// holds the tick up (docs/decisions.md, "A second thread in the tick").
#pragma once

#include <atomic>
#include <cstdint>
#include <thread>

namespace rigidtouch::geometry {

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

class Worker {
 public:
  using Job = void (*)(void* context);

  /// Starts the thread. Throws Error if the system cannot start one.
  Worker();
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
  long jobs_posted() const { return posted_.load(std::memory_order_relaxed); }
  /// A range for the posting thread and the job to share (ShareRange).
  TwoEndedRange& range() { return range_; }
  /// The worker thread's handle, for a real-time loop that gives it its own scheduling policy
  /// and keeps it off its CPU (loop::LoopOptions::helper_threads).
  std::thread::native_handle_type native_handle() { return thread_.native_handle(); }

 private:
  void Loop();

  std::atomic<std::uint32_t> posted_{0};    // jobs posted
  std::atomic<std::uint32_t> taken_{0};     // jobs taken, by the worker or back by Finish
  std::atomic<std::uint32_t> finished_{0};  // the last job the worker ran to the end
  std::atomic<bool> quit_{false};
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
template <class Body, class Before>
void ShareRange(Worker* worker, int n, const Body& body, const Before& before) {
  if (worker == nullptr) {
    before();
    for (int k = 0; k < n; ++k) body(k);
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
        for (int k = x->range->TakeBack(); k >= 0; k = x->range->TakeBack()) (*x->body)(k);
      },
      &context);
  before();
  for (int k = worker->range().TakeFront(); k >= 0; k = worker->range().TakeFront()) body(k);
  worker->Finish();
}

template <class Body>
void ShareRange(Worker* worker, int n, const Body& body) {
  ShareRange(worker, n, body, [] {});
}

}  // namespace rigidtouch::geometry
