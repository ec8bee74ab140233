// The real-time haptic loop: at each deadline Read the device, Tick, Write the command, end the
// device's period, and hand a trace sample to the writer thread (read, compute, write, count the
// rate). Every device, real or simulated, runs this same path, and every command passes the
// loop's last guards before Write.
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
  std::int64_t stale_device_ticks = 0;    // valid ticks whose state repeated the last sequence
  std::int64_t held_force_ticks = 0;      // stale ticks whose force was held to the last fresh one
  std::int64_t safe_fallback_ticks = 0;   // ticks that output the safe zero force
  std::int64_t non_finite_commands = 0;   // commands the loop's guard replaced by zero
  std::int64_t impulses = 0;              // impulses applied to the tool's group
  std::int64_t clipped_ticks = 0;         // ticks a force limit clipped (the model's or device's)
  std::int64_t guard_clipped_ticks = 0;   // ... of which the loop's guard clipped, after Tick
  double max_force_N = 0.0;               // largest force commanded
  double force_limit_N = 0.0;             // the last limit the guard applied (0: none known)
  bool finite = true;                     // every command was finite
};

/// Sees every tick on the haptic thread, after Write (a live viewer's feed). OnTick must not
/// allocate, lock, block or throw: it runs inside the loop's period.
class TickObserver {
 public:
  virtual ~TickObserver() = default;
  /// `sample` is the tick's trace sample with the device's annotations; `data` the state after
  /// the tick.
  virtual void OnTick(const Model& model, const Data& data, const TraceSample& sample) noexcept = 0;
};

/// Runs `model` against `device` at options.rate_hz (the model's time step should be its period).
/// Each tick: Read, Tick, guard, Write, AnnotateTrace (when tracing), EndPeriod(1 / rate_hz); a
/// device that lives in loop time (the simulated one) advances in EndPeriod. `traces`, when
/// given, receives one sample per tick (never blocks). Stops at the duration, on `*stop` or after
/// the period in which the device reports Ended(); never throws inside the loop.
///
/// A valid state whose sequence equals the previous tick's is stale: the loop passes
/// DeviceState::fresh = false to Tick (no window starts, no impulse) and holds the force's
/// magnitude at most at the last fresh tick's. Before every Write the guard makes a non-finite
/// command the safe zero wrench and clips the force to the stricter of DeviceParams::max_force_N
/// and device.limits().max_force_N (read every tick: a bridge may announce its limits late),
/// setting DeviceCommand::clipped and Warning::kForceClipped.
///
/// When it stops (the duration, `*stop`, the device's end), the loop writes one more command
/// after the last EndPeriod: the zero wrench, flagged safe-fallback, with the last state's
/// sequence, so that the device does not go on displaying the last tick's force. Over the UDP
/// bridge that is one datagram; the bridge's watchdog zeroes the force if it is lost.
///
/// `records`, when given, receives every tick's device state (as read, `fresh` as decided) and
/// command (as written), with the device's annotations, for `--record` (never blocks).
HapticLoopResult RunHapticLoop(const Model& model, Data& data, device::Device& device,
                               const LoopOptions& options, const std::atomic<bool>* stop,
                               TraceQueue* traces = nullptr, RecordQueue* records = nullptr,
                               TickObserver* observer = nullptr);

/// Runs `ticks` periods of the same step as RunHapticLoop back to back, without waiting for
/// deadlines (as fast as they compute; a replayed device, offline), or fewer if the device ends
/// or `*stop` is set. The device still ends each
/// period with EndPeriod(1 / rate_hz), and gets the zero wrench last, as from RunHapticLoop.
/// Timing statistics hold only ticks, elapsed_s and the achieved rate.
HapticLoopResult RunHapticTicks(const Model& model, Data& data, device::Device& device,
                                double rate_hz, std::int64_t ticks, const std::atomic<bool>* stop,
                                TraceQueue* traces = nullptr, RecordQueue* records = nullptr,
                                TickObserver* observer = nullptr);

/// Polls `device` about every millisecond until it reports a valid state, writing a zero wrench
/// flagged safe-fallback after each read (so a bridge learns where to stream), for at most
/// `timeout_s`. Returns whether a valid state came; false also when `*stop` is set. For devices
/// that may not be there (the UDP bridge); not real-time.
bool AwaitFirstState(device::Device& device, double timeout_s, const std::atomic<bool>* stop);

}  // namespace rigidtouch::loop
