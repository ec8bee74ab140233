#include "loop/timing_histogram.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "rigidtouch/types.h"

namespace rigidtouch::loop {

TimingHistogram::TimingHistogram(std::int64_t bin_width_ns, std::size_t bin_count)
    : bin_width_ns_(bin_width_ns) {
  if (bin_width_ns < 1 || bin_count < 1) {
    throw Error("timing histogram: bin width " + std::to_string(bin_width_ns) + " ns and " +
                std::to_string(bin_count) + " bins: both must be at least 1");
  }
  bins_.assign(bin_count, 0);
}

void TimingHistogram::Add(std::int64_t value_ns) noexcept {
  value_ns = std::max<std::int64_t>(value_ns, 0);
  const auto bin = static_cast<std::uint64_t>(value_ns / bin_width_ns_);
  if (bin < bins_.size()) {
    ++bins_[bin];
  } else {
    ++overflow_;
  }
  ++count_;
  max_ns_ = std::max(max_ns_, value_ns);
  sum_ns_ += static_cast<long double>(value_ns);
}

void TimingHistogram::Clear() noexcept {
  std::fill(bins_.begin(), bins_.end(), 0);
  overflow_ = 0;
  count_ = 0;
  max_ns_ = 0;
  sum_ns_ = 0.0;
}

double TimingHistogram::mean_s() const {
  if (count_ == 0) return 0.0;
  return static_cast<double>(sum_ns_ / static_cast<long double>(count_)) * 1e-9;
}

double TimingHistogram::Percentile(double fraction) const noexcept {
  if (count_ == 0) return 0.0;
  fraction = std::clamp(fraction, 0.0, 1.0);
  // nearest rank: the smallest value with at least ceil(fraction * n) values at or below it
  const auto rank = std::max<std::uint64_t>(
      1, static_cast<std::uint64_t>(std::ceil(fraction * static_cast<double>(count_))));
  std::uint64_t cumulative = 0;
  for (std::size_t bin = 0; bin < bins_.size(); ++bin) {
    cumulative += bins_[bin];
    if (cumulative >= rank) {
      const auto upper_edge_ns = static_cast<std::int64_t>(bin + 1) * bin_width_ns_;
      return static_cast<double>(std::min(upper_edge_ns, max_ns_)) * 1e-9;
    }
  }
  // the rank falls in the overflow bin: the maximum is the only bound we have
  return max_s();
}

}  // namespace rigidtouch::loop
