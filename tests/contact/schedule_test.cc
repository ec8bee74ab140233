#include "contact/schedule.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace rigidtouch::contact {
namespace {

RenderParams Train(double t_c, double f) {
  RenderParams r;
  r.renderer = RendererKind::kTrain;
  r.t_collision_s = t_c;
  r.frequency_hz = f;
  return r;
}

std::vector<std::int64_t> DueSteps(const Schedule& s, std::int64_t onset, std::int64_t until) {
  std::vector<std::int64_t> steps;
  WindowState w;
  w.onset_step = onset;
  for (std::int64_t k = 0; k < until; ++k) {
    int index = 0, remaining = 0;
    if (ImpulseDue(s, w, k, &index, &remaining)) {
      EXPECT_EQ(index, static_cast<int>(steps.size()) + 1);
      EXPECT_EQ(remaining, s.impulses - index + 1);  // Eq. 8 divisor N - i + 1
      steps.push_back(k);
    }
  }
  return steps;
}

// Eq. 6-7 with h = 1 ms, t_c = 0.1 s: f = 250 Hz gives 25 impulses 4 steps apart
TEST(ScheduleTest, Train250HzGives25Impulses4StepsApart) {
  const Schedule s = MakeSchedule(0.001, Train(0.1, 250.0));
  EXPECT_EQ(s.window_steps, 100);
  EXPECT_EQ(s.interval_steps, 4);
  EXPECT_EQ(s.impulses, 25);
  const auto steps = DueSteps(s, 10, 400);
  ASSERT_EQ(steps.size(), 25u);
  for (std::size_t i = 0; i < steps.size(); ++i) EXPECT_EQ(steps[i], 10 + 4 * (std::int64_t)i);
}

// f = 50 Hz gives 5 impulses 20 steps apart
TEST(ScheduleTest, Train50HzGives5Impulses20StepsApart) {
  const Schedule s = MakeSchedule(0.001, Train(0.1, 50.0));
  EXPECT_EQ(s.interval_steps, 20);
  EXPECT_EQ(s.impulses, 5);
  const auto steps = DueSteps(s, 0, 400);
  ASSERT_EQ(steps.size(), 5u);
  EXPECT_EQ(steps.back(), 80);
}

// the bounds: f = 1/t_c gives one impulse, f = 1/h one per step
TEST(ScheduleTest, FrequencyBoundsAreInclusive) {
  EXPECT_EQ(MakeSchedule(0.001, Train(0.1, 10.0)).impulses, 1);
  const Schedule every = MakeSchedule(0.001, Train(0.1, 1000.0));
  EXPECT_EQ(every.interval_steps, 1);
  EXPECT_EQ(every.impulses, 100);
}

TEST(ScheduleTest, FrequencyOutsideBoundsExplainsEq6And7) {
  try {
    MakeSchedule(0.001, Train(0.1, 2000.0));
    FAIL() << "f > 1/h accepted";
  } catch (const Error& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("frequency_hz"), std::string::npos) << m;
    EXPECT_NE(m.find("[10, 1000]"), std::string::npos) << m;
    EXPECT_NE(m.find("Eq. 7"), std::string::npos) << m;
  }
  EXPECT_THROW(MakeSchedule(0.001, Train(0.1, 5.0)), Error);
  EXPECT_THROW(MakeSchedule(0.001, Train(0.0005, 1000.0)), Error);  // window under one step
}

TEST(ScheduleTest, SingleImpulseAndPenaltyAreSpecialCases) {
  RenderParams r;
  r.renderer = RendererKind::kImpulse;
  const Schedule s = MakeSchedule(0.001, r);
  EXPECT_EQ(s.impulses, 1);
  EXPECT_EQ(DueSteps(s, 3, 50), (std::vector<std::int64_t>{3}));
  WindowState never;
  int i = 0, rem = 0;
  EXPECT_FALSE(ImpulseDue(s, never, 0, &i, &rem));
}

// Eq. 8's equal shares without a material; with one, at a constant approach velocity the
// impulses follow the envelope: p_j / p_0 = r^j, r = e^(-B n_i h), and the last share is 1
TEST(ScheduleTest, MaterialTrainSharesFollowTheEnvelope) {
  RenderParams r;
  r.renderer = RendererKind::kTrain;
  r.frequency_hz = 100.0;
  r.t_collision_s = 0.05;
  const double h = 1e-3;
  const Schedule s = MakeSchedule(h, r);
  ASSERT_EQ(s.impulses, 5);
  for (int remaining = 1; remaining <= 5; ++remaining) {
    EXPECT_DOUBLE_EQ(TrainShare(s, r, h, remaining), 1.0 / remaining);
  }
  r.material = {"wood", 15.0, 60.0, 100.0};
  const double ratio = std::exp(-60.0 * 10 * h);
  double left = 1.0, first = 0.0;
  for (int j = 0; j < s.impulses; ++j) {
    const double share = TrainShare(s, r, h, s.impulses - j);
    ASSERT_GT(share, 0.0);
    ASSERT_LE(share, 1.0);
    const double p = share * left;
    if (j == 0) first = p;
    EXPECT_NEAR(p / first, std::pow(ratio, j), 1e-12) << "impulse " << j;
    left -= p;
  }
  EXPECT_NEAR(left, 0.0, 1e-15);  // the last one stops the approach
  EXPECT_EQ(TrainShare(s, r, h, 1), 1.0);
}

}  // namespace
}  // namespace rigidtouch::contact
