// Numbers for people (text::Fixed, Significant, Percent) and the typo finder of the CLI's errors.
#include "base/text.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace rigidtouch::text {
namespace {

TEST(TextTest, FixedNeverPrintsNegativeZero) {
  EXPECT_EQ(Fixed(-1.11491e-20, 6), "0.000000");
  EXPECT_EQ(Fixed(-0.0, 1), "0.0");
  EXPECT_EQ(Fixed(-0.00004, 4), "0.0000");
  EXPECT_EQ(Fixed(-0.00006, 4), "-0.0001");
  EXPECT_EQ(Fixed(2.5, 2), "2.50");
  EXPECT_EQ(Fixed(std::numeric_limits<double>::quiet_NaN(), 2), "nan");
  EXPECT_EQ(Fixed(-std::numeric_limits<double>::infinity(), 2), "-inf");
}

TEST(TextTest, SignificantKeepsTheDigitsAMeasurementMeans) {
  EXPECT_EQ(Significant(16570.4), "16570");
  EXPECT_EQ(Significant(118.59), "118.6");
  EXPECT_EQ(Significant(955.6701270105289), "955.7");
  EXPECT_EQ(Significant(0.000796, 3), "0.000796");
  EXPECT_EQ(Significant(231.44), "231.4");
  // the digits after rounding: 99.996 is 100.0, not 100.00
  EXPECT_EQ(Significant(99.996), "100.0");
  EXPECT_EQ(Significant(1.0 / (10 * 0.001)), "100.0");
  EXPECT_EQ(Significant(1.234e-7), "1.234e-07");
  EXPECT_EQ(Significant(2.5e9, 3), "2.50e+09");
  EXPECT_EQ(Significant(0.0), "0");
  EXPECT_EQ(Significant(-3.14159, 3), "-3.14");
}

TEST(TextTest, PercentIsToATenth) {
  EXPECT_EQ(Percent(0.943794), "94.4%");
  EXPECT_EQ(Percent(1.0), "100.0%");
}

}  // namespace
}  // namespace rigidtouch::text
