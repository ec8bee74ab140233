#include "bench/stats.h"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace rigidtouch::bench {

double NearestRankPercentile(const std::vector<std::int64_t>& sorted_ns, double fraction) {
  if (sorted_ns.empty()) return 0.0;
  const auto n = static_cast<double>(sorted_ns.size());
  // rank in 1..n; the small epsilon keeps 0.99 * 1000 from rounding up to 991
  auto rank = static_cast<long>(std::ceil(fraction * n - 1e-9));
  rank = std::clamp(rank, 1L, static_cast<long>(sorted_ns.size()));
  return static_cast<double>(sorted_ns[static_cast<std::size_t>(rank - 1)]);
}

TimeSummary Summarize(std::vector<std::int64_t>& durations_ns) {
  TimeSummary summary;
  if (durations_ns.empty()) return summary;
  std::sort(durations_ns.begin(), durations_ns.end());
  summary.count = static_cast<long>(durations_ns.size());
  summary.median_ns = NearestRankPercentile(durations_ns, 0.5);
  summary.p99_ns = NearestRankPercentile(durations_ns, 0.99);
  summary.p999_ns = NearestRankPercentile(durations_ns, 0.999);
  summary.max_ns = static_cast<double>(durations_ns.back());
  const double total_ns =
      std::accumulate(durations_ns.begin(), durations_ns.end(), 0.0,
                      [](double sum, std::int64_t d) { return sum + static_cast<double>(d); });
  summary.mean_ns = total_ns / static_cast<double>(durations_ns.size());
  return summary;
}

}  // namespace rigidtouch::bench
