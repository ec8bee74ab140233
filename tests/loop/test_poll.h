// Polling helper (shared by the loop and UDP device tests) for tests that wait on sockets or
// threads: no timing assertion, only a generous upper bound so a broken implementation fails
// instead of hanging.
#pragma once

#include <chrono>
#include <thread>

namespace rigidtouch::testing {

/// Calls `done()` every `interval` until it returns true or `timeout` passes; returns its last
/// answer.
template <typename Predicate>
bool PollUntil(Predicate&& done, std::chrono::milliseconds timeout = std::chrono::seconds(5),
               std::chrono::microseconds interval = std::chrono::microseconds(200)) {
  const auto give_up = std::chrono::steady_clock::now() + timeout;
  while (!done()) {
    if (std::chrono::steady_clock::now() > give_up) return done();
    std::this_thread::sleep_for(interval);
  }
  return true;
}

}  // namespace rigidtouch::testing
