// A second thread for the tick (Model::threads = 2): started when the Data is made, it waits for
// a job, runs it, and says it is done. Posting and waiting never allocate, lock or throw: the
// hand-off is two counters (C++20 atomic wait / notify, after a short spin), so the haptic thread
// stays lock-free (docs/decisions.md, "A second thread for the narrow phase").
#pragma once

#include <atomic>
#include <cstdint>
#include <thread>

namespace rigidtouch::geometry {

class Worker {
 public:
  using Job = void (*)(void* context);

  /// Starts the thread. Throws Error if the system cannot start one.
  Worker();
  /// Stops the thread (after the job it may be running) and joins it.
  ~Worker();
  Worker(const Worker&) = delete;
  Worker& operator=(const Worker&) = delete;

  /// Runs job(context) on the worker thread. Every write before Post is visible to the job. At
  /// most one job at a time: call Wait before the next Post.
  void Post(Job job, void* context);
  /// Returns when the posted job has finished; its writes are then visible to the caller.
  void Wait();

 private:
  void Loop();

  std::atomic<std::uint32_t> posted_{0};    // jobs posted (the worker runs each new one)
  std::atomic<std::uint32_t> finished_{0};  // jobs finished
  std::atomic<bool> quit_{false};
  Job job_ = nullptr;  // written before posted_ is raised, read after it is seen
  void* context_ = nullptr;
  std::thread thread_;
};

}  // namespace rigidtouch::geometry
