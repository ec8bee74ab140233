#include "bench_test_config.h"

#ifdef RIGIDTOUCH_BENCH_ENABLED

#include <algorithm>
#include <numeric>
#include <random>

#include "bench/stats.h"

namespace rigidtouch::bench {
namespace {

// every expected value below is an element of the sample, so comparisons are exact

TEST(Stats, NearestRankPercentilesOfOneToThousand) {
  std::vector<std::int64_t> durations_ns(1000);
  std::iota(durations_ns.begin(), durations_ns.end(), 1);
  std::shuffle(durations_ns.begin(), durations_ns.end(), std::mt19937(7));
  const TimeSummary summary = Summarize(durations_ns);
  EXPECT_EQ(summary.count, 1000);
  EXPECT_EQ(summary.median_ns, 500.0);  // rank ceil(0.5 * 1000) = 500
  EXPECT_EQ(summary.p99_ns, 990.0);     // rank 990
  EXPECT_EQ(summary.p999_ns, 999.0);    // rank 999
  EXPECT_EQ(summary.max_ns, 1000.0);
  EXPECT_DOUBLE_EQ(summary.mean_ns, 500.5);
  EXPECT_TRUE(std::is_sorted(durations_ns.begin(), durations_ns.end()));
}

TEST(Stats, SmallSamplesUseTheNearestRank) {
  const std::vector<std::int64_t> sorted_ns = {10, 20, 30};
  EXPECT_EQ(NearestRankPercentile(sorted_ns, 0.5), 20.0);   // rank ceil(1.5) = 2
  EXPECT_EQ(NearestRankPercentile(sorted_ns, 0.99), 30.0);  // rank ceil(2.97) = 3
  EXPECT_EQ(NearestRankPercentile(sorted_ns, 0.01), 10.0);  // rank ceil(0.03) = 1
  std::vector<std::int64_t> one_ns = {42};
  const TimeSummary summary = Summarize(one_ns);
  EXPECT_EQ(summary.median_ns, 42.0);
  EXPECT_EQ(summary.p999_ns, 42.0);
  EXPECT_EQ(summary.max_ns, 42.0);
}

TEST(Stats, EmptySampleGivesZeros) {
  std::vector<std::int64_t> empty_ns;
  const TimeSummary summary = Summarize(empty_ns);
  EXPECT_EQ(summary.count, 0);
  EXPECT_EQ(summary.median_ns, 0.0);
  EXPECT_EQ(NearestRankPercentile(empty_ns, 0.5), 0.0);
}

}  // namespace
}  // namespace rigidtouch::bench

#else
RIGIDTOUCH_BENCH_SKIPPED_TEST(Stats)
#endif
