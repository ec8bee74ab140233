#include "study/random.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <set>
#include <vector>

namespace rigidtouch::study {
namespace {

TEST(RandomTest, SameSeedSameSequence) {
  Rng a(42);
  Rng b(42);
  for (int i = 0; i < 100; ++i) EXPECT_EQ(a.NextU64(), b.NextU64());
}

TEST(RandomTest, DerivedSeedsDependOnEveryPartAndItsOrder) {
  std::set<std::uint64_t> seeds;
  for (std::uint64_t i = 0; i < 50; ++i) {
    for (std::uint64_t j = 0; j < 50; ++j) seeds.insert(DeriveSeed(7, {i, j}));
  }
  EXPECT_EQ(seeds.size(), 2500u);
  EXPECT_NE(DeriveSeed(7, {1, 2}), DeriveSeed(7, {2, 1}));
  EXPECT_NE(DeriveSeed(7, {1}), DeriveSeed(8, {1}));
  EXPECT_NE(DeriveSeed(7, {}), DeriveSeed(7, {0}));
}

// the stream of Normal is part of every seeded result: 1 - Uniform() then Uniform(), Box-Muller
TEST(RandomTest, NormalIsBoxMullerOfOneMinusUniformThenUniform) {
  Rng normal(123);
  Rng uniform(123);
  for (int i = 0; i < 100; ++i) {
    const double u1 = 1.0 - uniform.Uniform();
    const double u2 = uniform.Uniform();
    ASSERT_EQ(normal.Normal(),
              std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2));
  }
}

TEST(RandomTest, UniformAndNormalMoments) {
  // n = 200000: standard errors 0.00065 (uniform mean), 0.0022 (normal mean), 0.0032 (normal
  // variance); tolerances are 5 standard errors
  constexpr int n = 200000;
  Rng rng(1);
  double su = 0.0;
  double sn = 0.0;
  double sn2 = 0.0;
  for (int i = 0; i < n; ++i) {
    const double u = rng.Uniform();
    ASSERT_GE(u, 0.0);
    ASSERT_LT(u, 1.0);
    su += u;
    const double z = rng.Normal();
    sn += z;
    sn2 += z * z;
  }
  EXPECT_NEAR(su / n, 0.5, 5 * 0.00065);
  EXPECT_NEAR(sn / n, 0.0, 5 * 0.0022);
  EXPECT_NEAR(sn2 / n, 1.0, 5 * 0.0032);
}

TEST(RandomTest, BelowIsUniform) {
  // 7 bins, 70000 draws: each count ~ 10000 with SD sqrt(10000 * 6/7) = 92.6; tolerance 5 SD
  Rng rng(3);
  std::vector<int> counts(7, 0);
  for (int i = 0; i < 70000; ++i) ++counts[rng.Below(7)];
  for (int c : counts) EXPECT_NEAR(c, 10000, 5 * 92.6);
}

TEST(RandomTest, BernoulliEdges) {
  Rng rng(5);
  for (int i = 0; i < 1000; ++i) {
    EXPECT_FALSE(rng.Bernoulli(0.0));
    EXPECT_TRUE(rng.Bernoulli(1.0));
  }
}

}  // namespace
}  // namespace rigidtouch::study
