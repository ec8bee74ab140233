#include "loop/stop_signal.h"

#include <cerrno>
#include <csignal>
#include <cstring>
#include <string>

#include "rigidtouch/types.h"

namespace rigidtouch::loop {
namespace {

// a namespace-scope atomic: signal handlers may only touch lock-free atomics
std::atomic<bool> stop_flag{false};
std::atomic<int> stop_signal{0};
static_assert(std::atomic<bool>::is_always_lock_free);
static_assert(std::atomic<int>::is_always_lock_free);

void OnStopSignal(int signal_number) {
  stop_signal.store(signal_number, std::memory_order_relaxed);
  stop_flag.store(true, std::memory_order_release);
}

}  // namespace

const std::atomic<bool>& InstallStopSignalHandlers() {
  struct sigaction action {};
  action.sa_handler = OnStopSignal;
  sigemptyset(&action.sa_mask);
  // no SA_RESTART: clock_nanosleep returns EINTR and the loop checks the flag at once
  action.sa_flags = 0;
  for (const int signal_number : {SIGINT, SIGTERM}) {
    if (sigaction(signal_number, &action, nullptr) != 0) {
      throw Error("cannot install a handler for signal " + std::to_string(signal_number) + ": " +
                  std::strerror(errno));
    }
  }
  return stop_flag;
}

const std::atomic<int>& StopSignalNumber() {
  return stop_signal;
}

void ResetStopSignalFlag() noexcept {
  stop_signal.store(0, std::memory_order_relaxed);
  stop_flag.store(false, std::memory_order_release);
}

}  // namespace rigidtouch::loop
