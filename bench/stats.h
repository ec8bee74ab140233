// Order statistics of per-step times.
#pragma once

#include <cstdint>
#include <vector>

namespace rigidtouch::bench {

/// Summary of a set of per-step durations, in nanoseconds.
struct TimeSummary {
  long count = 0;
  double median_ns = 0.0;
  double p99_ns = 0.0;
  double p999_ns = 0.0;  ///< 99.9th percentile
  double max_ns = 0.0;
  double mean_ns = 0.0;
};

/// Returns the nearest-rank percentile `fraction` in (0, 1] of an ascending sorted sample: the
/// smallest value with at least `fraction * n` values at or below it. Returns 0 for an empty
/// sample.
double NearestRankPercentile(const std::vector<std::int64_t>& sorted_ns, double fraction);

/// Summarises durations in nanoseconds; sorts `durations_ns` in place.
TimeSummary Summarize(std::vector<std::int64_t>& durations_ns);

}  // namespace rigidtouch::bench
