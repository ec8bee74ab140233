// The real-time haptic loop: at each deadline Read the device, Tick, Write the command, end the
// device's period, and hand a trace sample to the writer thread (read, compute, write, count the
// rate). Every device, real or simulated, runs this same path.
#pragma once

#include <atomic>
#include <cstdint>

#include "loop/rate_loop.h"
#include "loop/trace_queue.h"
#include "rigidtouch/device.h"
#include "rigidtouch/rigidtouch.h"

namespace rigidtouch::loop {

/// Counts of one run besides the timing statistics.
struct HapticLoopResult {
  LoopStats timing;
  std::int64_t invalid_device_ticks = 0;  // ticks whose device state was invalid (zero force)
  std::int64_t safe_fallback_ticks = 0;   // ticks that output the safe zero force
  std::int64_t impulses = 0;              // impulses applied to the tool's group
  std::int64_t clipped_ticks = 0;         // ticks the device force limit clipped
  double max_force_N = 0.0;               // largest force commanded
  bool finite = true;                     // every command was finite
};

/// Runs `model` against `device` at options.rate_hz (the model's time step should be its period).
/// Each tick: Read, Tick, Write, AnnotateTrace (when tracing), EndPeriod(1 / rate_hz); a device
/// that lives in loop time (the simulated one) advances in EndPeriod. `traces`, when given,
/// receives one sample per tick (never blocks). Stops at the duration or on `*stop`; never
/// throws inside the loop.
HapticLoopResult RunHapticLoop(const Model& model, Data& data, device::Device& device,
                               const LoopOptions& options, const std::atomic<bool>* stop,
                               TraceQueue* traces = nullptr);

}  // namespace rigidtouch::loop
