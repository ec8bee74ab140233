// The fixed job of `rigidtouch bench --reference`: the same work for the same units, and its
// sizing against a clock the test controls (no real timing here: machines are noisy).
#include "loop/reference_job.h"

#include <gtest/gtest.h>

#include <vector>

namespace rigidtouch::loop {
namespace {

TEST(ReferenceJobTest, TheSameUnitsDoTheSameWorkAndEveryUnitCounts) {
  ReferenceJob a, b;
  EXPECT_EQ(a.Run(3), b.Run(3));
  EXPECT_EQ(a.Run(0), b.Run(0)) << "no units: the chain as it was";
  EXPECT_EQ(a.Run(2), b.Run(2));
  ReferenceJob c, d;
  const double one = c.Run(1), two = d.Run(2);
  EXPECT_NE(one, two) << "a second unit changes the chain";
  EXPECT_EQ(c.Run(1), two) << "two units in two runs are two units in one";
  // timed, the same work: the chain as after Run (no time is asserted)
  ReferenceJob e, f;
  e.TimedRunNs(3);
  f.MedianNs(1, 3);
  EXPECT_EQ(e.chain(), ReferenceJob().Run(3));
  EXPECT_EQ(f.chain(), ReferenceJob().Run(3)) << "three timed runs of one unit";
}

// a job of known cost per unit, as a clock would report it
TEST(ReferenceJobTest, CalibrationFindsTheUnitsOfTheTargetLength) {
  std::vector<long> asked;
  const auto linear = [&asked](long units) {
    asked.push_back(units);
    return 4800.0 * static_cast<double>(units) + 3000.0;  // 4.8 us per unit, 3 us to start
  };
  // 650 us: (650000 - 3000) / 4800 = 134.8 units; two rounds of scaling land within one unit
  const long units = CalibrateUnits(650'000.0, 16, 10'000'000, linear);
  EXPECT_NEAR(static_cast<double>(units), 134.8, 1.0);
  ASSERT_EQ(asked.size(), 2u) << "two rounds, each timing the job once at its current size";
  EXPECT_EQ(asked[0], 16);
  // a job shorter than one unit is one unit; the cap bounds a job that a bad clock makes huge
  EXPECT_EQ(CalibrateUnits(100.0, 16, 10'000'000, linear), 1);
  EXPECT_EQ(CalibrateUnits(1e15, 16, 1000, linear), 1000);
}

TEST(ReferenceJobTest, AClockThatReportsNothingLeavesTheFirstGuess) {
  const auto zero = [](long) { return 0.0; };
  EXPECT_EQ(CalibrateUnits(650'000.0, 16, 10'000'000, zero), 16);
  const auto linear = [](long units) { return 1000.0 * static_cast<double>(units); };
  EXPECT_EQ(CalibrateUnits(0.0, 16, 10'000'000, linear), 16) << "no target: nothing to scale to";
  EXPECT_EQ(CalibrateUnits(5000.0, 0, 10'000'000, linear), 5) << "a first guess below one is one";
}

}  // namespace
}  // namespace rigidtouch::loop
