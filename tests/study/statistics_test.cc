#include "study/statistics.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace rigidtouch::study {
namespace {

// reference values below were computed independently with exact rational arithmetic (binomial)
// and Python's statistics.NormalDist (normal quantiles)

TEST(NormalTest, CdfMatchesKnownValues) {
  EXPECT_DOUBLE_EQ(NormalCdf(0.0), 0.5);
  EXPECT_NEAR(NormalCdf(1.96), 0.9750021048517796, 1e-12);  // erfc is accurate to ~1 ulp
  EXPECT_NEAR(NormalCdf(-1.96), 1.0 - 0.9750021048517796, 1e-12);
}

TEST(NormalTest, QuantileInvertsCdf) {
  EXPECT_NEAR(NormalQuantile(0.975), 1.9599639845400536, 1e-12);
  // round trip (tolerance: bisection resolution 1e-14 plus erfc error); above x = 4 the round trip
  // is limited by the spacing of doubles near 1, not by the quantile, so the range stops there
  for (double x = -8.0; x <= 4.0; x += 0.25) {
    EXPECT_NEAR(NormalQuantile(NormalCdf(x)), x, 1e-9) << x;
  }
  EXPECT_TRUE(std::isinf(NormalQuantile(0.0)) && NormalQuantile(0.0) < 0.0);
  EXPECT_TRUE(std::isinf(NormalQuantile(1.0)) && NormalQuantile(1.0) > 0.0);
}

TEST(BinomialTest, SymmetricCaseMatchesExactFractions) {
  // 15 of 20 at p0 = 0.5: P(X >= 15) = 5425 / 262144, two-sided = 5425 / 131072
  const BinomialTest t = ExactBinomialTest(15, 20, 0.5);
  EXPECT_NEAR(t.p_greater, 5425.0 / 262144.0, 1e-12);
  EXPECT_NEAR(t.p_less, 260595.0 / 262144.0, 1e-12);
  EXPECT_NEAR(t.p_two_sided, 5425.0 / 131072.0, 1e-12);
}

TEST(BinomialTest, BelowChanceIsSeenByTheLowerTail) {
  // 12 of 40 correct: the one-sided test toward "below chance" is significant
  const BinomialTest t = ExactBinomialTest(12, 40, 0.5);
  EXPECT_NEAR(t.p_less, 0.008294501687487355, 1e-12);
  EXPECT_NEAR(t.p_greater, 0.9967867119521543, 1e-12);
  EXPECT_NEAR(t.p_two_sided, 0.01658900337497471, 1e-12);
}

TEST(BinomialTest, AsymmetricNullUsesMinLikelihoodTwoSidedP) {
  // 3 of 10 at p0 = 0.1: outcomes no more likely than 3 are 3..10, so two-sided = P(X >= 3)
  const BinomialTest t = ExactBinomialTest(3, 10, 0.1);
  EXPECT_NEAR(t.p_greater, 0.0701908264, 1e-10);
  EXPECT_NEAR(t.p_two_sided, 0.0701908264, 1e-10);
  EXPECT_NEAR(t.p_less, 0.9872048016, 1e-10);
}

TEST(BinomialTest, NoTrialsGivesOne) {
  const BinomialTest t = ExactBinomialTest(0, 0, 0.5);
  EXPECT_EQ(t.p_two_sided, 1.0);
  EXPECT_EQ(t.p_greater, 1.0);
  EXPECT_EQ(t.p_less, 1.0);
}

TEST(BinomialTest, PmfSumsToOneAndQuantilesBracketTheMean) {
  double sum = 0.0;
  for (int k = 0; k <= 50; ++k) sum += BinomialPmf(k, 50, 0.3);
  EXPECT_NEAR(sum, 1.0, 1e-12);
  // 95% central interval of Binomial(4000, 0.5), computed exactly: [1938, 2062]
  EXPECT_EQ(BinomialQuantile(4000, 0.5, 0.025), 1938);
  EXPECT_EQ(BinomialQuantile(4000, 0.5, 0.975), 2062);
}

TEST(DPrimeTest, LogLinearCorrectionKeepsPerfectScoresFinite) {
  // 10/10 hits, 0/10 false alarms: H = 10.5/11, F = 0.5/11
  const DPrime d = LogLinearDPrime(10, 10, 0, 10);
  EXPECT_NEAR(d.hit_rate, 10.5 / 11.0, 1e-15);
  EXPECT_NEAR(d.false_alarm_rate, 0.5 / 11.0, 1e-15);
  EXPECT_NEAR(d.d_prime, 3.3812432591697963, 1e-9);
  EXPECT_NEAR(d.criterion, 0.0, 1e-9);
}

TEST(DPrimeTest, MatchesHandComputation) {
  // 7/10 hits, 2/10 false alarms
  const DPrime d = LogLinearDPrime(7, 10, 2, 10);
  EXPECT_NEAR(d.d_prime, 1.2206477157555693, 1e-9);
  EXPECT_NEAR(d.criterion, 0.13753473688551743, 1e-9);
}

TEST(DPrimeTest, SwappedLabelsGiveNegativeDPrime) {
  EXPECT_LT(LogLinearDPrime(1, 10, 9, 10).d_prime, -2.0);
}

TEST(MeanSdTest, SampleStandardDeviation) {
  const std::vector<double> v = {1.0, 2.0, 3.0, 4.0};
  const MeanSd m = ComputeMeanSd(v);
  EXPECT_DOUBLE_EQ(m.mean, 2.5);
  EXPECT_NEAR(m.sd, std::sqrt(5.0 / 3.0), 1e-15);
  EXPECT_EQ(m.n, 4);
  const std::vector<double> one = {7.0};
  EXPECT_TRUE(std::isnan(ComputeMeanSd(one).sd));
}

}  // namespace
}  // namespace rigidtouch::study
