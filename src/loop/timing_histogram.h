// Fixed-bin histogram of timing errors: allocated once, then filled from the real-time loop
// without allocation. Percentiles come from the bins (resolution = bin width).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace rigidtouch::loop {

/// Histogram of non-negative durations with `bin_count` bins of `bin_width_ns` plus an overflow
/// bin; the exact maximum is tracked separately.
class TimingHistogram {
 public:
  /// Allocates the bins. Throws Error when bin_width_ns < 1 or bin_count < 1.
  TimingHistogram(std::int64_t bin_width_ns, std::size_t bin_count);

  /// Adds one duration; negative values count as 0. Never allocates.
  void Add(std::int64_t value_ns) noexcept;
  /// Empties the histogram without releasing memory.
  void Clear() noexcept;

  /// Number of values added.
  std::uint64_t count() const { return count_; }
  /// Values at or beyond bin_width_ns * bin_count.
  std::uint64_t overflow() const { return overflow_; }
  /// Largest value added, in seconds (0 when empty).
  double max_s() const { return static_cast<double>(max_ns_) * 1e-9; }
  /// Mean of the values added, in seconds (0 when empty).
  double mean_s() const;

  /// Nearest-rank percentile, `fraction` in [0, 1], in seconds: the upper edge of the first bin
  /// whose cumulative count reaches ceil(fraction * count), never more than max_s(). An upper
  /// bound on the true percentile, within one bin width of it; 0 when empty.
  double Percentile(double fraction) const noexcept;

 private:
  std::int64_t bin_width_ns_;
  std::vector<std::uint64_t> bins_;
  std::uint64_t overflow_ = 0;
  std::uint64_t count_ = 0;
  std::int64_t max_ns_ = 0;
  long double sum_ns_ = 0.0;
};

}  // namespace rigidtouch::loop
