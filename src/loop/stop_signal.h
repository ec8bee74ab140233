// SIGINT / SIGTERM -> a stop flag for RateLoop::Run, so Ctrl-C ends a run cleanly (statistics
// printed, traces flushed) instead of killing the process.
#pragma once

#include <atomic>

namespace rigidtouch::loop {

/// Installs SIGINT and SIGTERM handlers that set the returned process-wide flag (one lock-free
/// atomic store, async-signal-safe). Idempotent. Pass the flag to RateLoop::Run. Throws Error
/// when sigaction fails.
const std::atomic<bool>& InstallStopSignalHandlers();

/// The number of the last stop signal received (SIGINT 2, SIGTERM 15); 0 before any. Set by the
/// handlers InstallStopSignalHandlers installs, before the flag.
const std::atomic<int>& StopSignalNumber();

/// Clears the process-wide stop flag (e.g. between two runs).
void ResetStopSignalFlag() noexcept;

}  // namespace rigidtouch::loop
