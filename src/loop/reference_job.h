// A fixed job of known length, timed beside the steps of `rigidtouch bench --reference`: what a
// job whose work never varies takes on this machine shows how much of a step's tail the machine
// itself adds (preemption, another tenant on the core, interrupts, clock changes), so that the
// tail the steps have beyond it is the engine's (docs/performance.md, "The machine's own tail").
#pragma once

#include <array>
#include <cstdint>
#include <functional>

namespace rigidtouch::loop {

/// A compute-bound job over a buffer that stays in the first-level cache, so that running it
/// between two steps does not evict the scene's data from the larger caches. Its work is the same
/// for the same number of units; one unit is some tens of nanoseconds on a current CPU, fine
/// enough to match a step of a fraction of a microsecond.
class ReferenceJob {
 public:
  /// Values per unit, each one multiply-add in one dependent chain, taken in turn from a buffer
  /// of kBufferValues (16 KB).
  static constexpr int kUnitValues = 16;
  static constexpr int kBufferValues = 2048;

  /// Runs `units` units (none for units <= 0); returns the chain's value, which depends on every
  /// unit run since construction (so that the work cannot be left out).
  double Run(long units);
  /// Run(units), timed: how long it took [ns], by the steady clock.
  std::int64_t TimedRunNs(long units);
  /// The median of `runs` (at least one) TimedRunNs(units).
  double MedianNs(long units, int runs);
  /// The chain's value after every unit run since construction.
  double chain() const { return chain_; }

 private:
  static std::array<double, kBufferValues> MakeValues();
  std::array<double, kBufferValues> values_ = MakeValues();
  int next_ = 0;  // the first value of the next unit
  double chain_ = 0.0;
};

/// Units of the job at which its median length is `target_ns`: from a first guess of
/// `first_units`, two rounds of scaling the units by target over the median that `median_ns_of`
/// reports for that many units (the caller times the job). At least 1, at most `max_units`; the
/// first guess if a median is not positive.
long CalibrateUnits(double target_ns, long first_units, long max_units,
                    const std::function<double(long units)>& median_ns_of);

}  // namespace rigidtouch::loop
