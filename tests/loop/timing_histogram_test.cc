#include "loop/timing_histogram.h"

#include <gtest/gtest.h>

#include "rigidtouch/types.h"

namespace rigidtouch::loop {
namespace {

// values (k + 0.5) us for k = 0..99, in 1 us bins: sorted, the r-th value (1-based) sits in bin
// r - 1, so the nearest-rank percentile p is the upper edge ceil(100 p) us, clamped to the max
// 99.5 us; exact up to double rounding of ns -> s (tolerance 1e-12 s)
TEST(TimingHistogram, NearestRankPercentilesOfAUniformSample) {
  TimingHistogram histogram(1000, 1000);
  for (int k = 99; k >= 0; --k) histogram.Add(k * 1000 + 500);  // order does not matter
  EXPECT_EQ(histogram.count(), 100u);
  EXPECT_NEAR(histogram.Percentile(0.5), 50e-6, 1e-12);
  EXPECT_NEAR(histogram.Percentile(0.99), 99e-6, 1e-12);
  EXPECT_NEAR(histogram.Percentile(0.999), 99.5e-6, 1e-12);  // bin edge 100 us, clamped to max
  EXPECT_NEAR(histogram.Percentile(0.0), 1e-6, 1e-12);       // rank 1: the first bin
  EXPECT_NEAR(histogram.max_s(), 99.5e-6, 1e-12);
  EXPECT_NEAR(histogram.mean_s(), 50e-6, 1e-12);  // mean of k + 0.5 over k = 0..99
  EXPECT_EQ(histogram.overflow(), 0u);
}

TEST(TimingHistogram, PercentileIsAnUpperBoundWithinOneBin) {
  TimingHistogram histogram(1000, 100);
  for (int i = 0; i < 1000; ++i) histogram.Add(12'345);      // all in bin 12
  EXPECT_NEAR(histogram.Percentile(0.5), 12.345e-6, 1e-12);  // bin edge 13 us, clamped to max
  histogram.Add(12'999);
  EXPECT_NEAR(histogram.Percentile(0.5), 12.999e-6, 1e-12);
}

TEST(TimingHistogram, OverflowBinReportsTheMaximum) {
  TimingHistogram histogram(1000, 10);  // range [0, 10) us
  histogram.Add(2'000);
  histogram.Add(50'000);
  histogram.Add(70'000);
  EXPECT_EQ(histogram.overflow(), 2u);
  EXPECT_NEAR(histogram.Percentile(0.2), 3e-6, 1e-12);
  EXPECT_NEAR(histogram.Percentile(0.9), 70e-6, 1e-12);
  EXPECT_NEAR(histogram.max_s(), 70e-6, 1e-12);
}

TEST(TimingHistogram, NegativeValuesCountAsZeroAndClearEmpties) {
  TimingHistogram histogram(1000, 10);
  histogram.Add(-5'000);
  EXPECT_EQ(histogram.count(), 1u);
  EXPECT_EQ(histogram.max_s(), 0.0);
  EXPECT_EQ(histogram.Percentile(0.5), 0.0);
  histogram.Add(4'000);
  histogram.Clear();
  EXPECT_EQ(histogram.count(), 0u);
  EXPECT_EQ(histogram.Percentile(0.99), 0.0);
  EXPECT_EQ(histogram.max_s(), 0.0);
  EXPECT_EQ(histogram.mean_s(), 0.0);
}

TEST(TimingHistogram, RejectsEmptyShapes) {
  EXPECT_THROW(TimingHistogram(0, 10), Error);
  EXPECT_THROW(TimingHistogram(1000, 0), Error);
}

}  // namespace
}  // namespace rigidtouch::loop
