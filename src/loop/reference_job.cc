#include "loop/reference_job.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <vector>

namespace rigidtouch::loop {

std::array<double, ReferenceJob::kBufferValues> ReferenceJob::MakeValues() {
  std::array<double, kBufferValues> v{};
  for (int i = 0; i < kBufferValues; ++i) v[i] = 1.0 + 1e-3 * static_cast<double>(i % 97);
  return v;
}

double ReferenceJob::Run(long units) {
  static_assert(kBufferValues % kUnitValues == 0);
  double chain = chain_;
  int next = next_;
  for (long u = 0; u < units; ++u) {
    for (int i = next; i < next + kUnitValues; ++i) {
      // each value moves a little and feeds the chain: one dependent multiply-add per value
      double& x = values_[i];
      x = x * 0.9999999 + 1e-9;
      chain = chain * 0.999 + x;
    }
    next = (next + kUnitValues) % kBufferValues;
  }
  chain_ = chain;
  next_ = next;
  return chain;
}

std::int64_t ReferenceJob::TimedRunNs(long units) {
  const auto start = std::chrono::steady_clock::now();
  Run(units);
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now() -
                                                              start)
      .count();
}

double ReferenceJob::MedianNs(long units, int runs) {
  std::vector<std::int64_t> ns(static_cast<std::size_t>(std::max(runs, 1)));
  for (std::int64_t& t : ns) t = TimedRunNs(units);
  std::sort(ns.begin(), ns.end());
  return static_cast<double>(ns[ns.size() / 2]);
}

long CalibrateUnits(double target_ns, long first_units, long max_units,
                    const std::function<double(long units)>& median_ns_of) {
  const long cap = std::max(1L, max_units);
  long units = std::clamp(first_units, 1L, cap);
  for (int round = 0; round < 2; ++round) {
    const double ns = median_ns_of(units);
    if (!(ns > 0.0) || !(target_ns > 0.0)) return units;
    const double scaled = std::round(static_cast<double>(units) * target_ns / ns);
    units = static_cast<long>(std::clamp(scaled, 1.0, static_cast<double>(cap)));
  }
  return units;
}

}  // namespace rigidtouch::loop
