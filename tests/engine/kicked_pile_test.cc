// The 100-box pile of scenes/pile.xml kicked: every body given a random velocity (seeded). The
// boxes then collide in contact groups of 300 to 600 rows on about 100 bodies, whose Delassus
// matrices are nearly singular (rank about 160 of 220 rows, condition 1e9 to 1e11 on their
// range), where MPRGP's conjugate gradients crawl: with MPRGP alone, impulses failed (3 in this
// test's 1.5 s, each after some 9000 iterations) and were answered with none, and the test took
// 12 s instead of 1.
// The body-space interior-point method (impulse_interior.cc) takes such groups over; every
// impulse is then solved, and each dissipates energy (plastic, Eq. 8).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>

#include "draw.h"
#include "rigidtouch/rigidtouch.h"

namespace rigidtouch {
namespace {

TEST(KickedPileTest, EveryImpulseOfALargeDegenerateGroupIsSolved) {
  const Model model = LoadModel(std::string(RIGIDTOUCH_SCENES) + "/pile.xml", LoadOptions{});
  Data data = MakeData(model);
  TickInput in;
  for (int k = 0; k < 500; ++k) Tick(model, data, in);  // settle
  std::mt19937_64 rng(3);
  // per component: 0.3 m/s and 10 rad/s in norm on average
  std::normal_distribution<double> v(0.0, 0.3 / std::sqrt(3.0)), w(0.0, 10.0 / std::sqrt(3.0));
  for (BodyState& body : data.bodies) {
    body.v_W += test::Draw3(v, rng);
    body.w_W += test::Draw3(w, rng);
  }
  const int failed_before = data.warnings[static_cast<int>(Warning::kSolverFailed)].count;
  int large = 0;
  int largest = 0;
  for (int k = 0; k < 1500; ++k) {
    Tick(model, data, in);
    for (int i = 0; i < data.nimpulse; ++i) {
      const ImpulseEvent& ev = data.impulses[i];
      if (ev.contacts >= 200) ++large;
      largest = std::max(largest, ev.contacts);
      // an impulse never adds energy; tolerance: rounding, 1e-12 of the energy before
      ASSERT_LE(ev.kinetic_energy_after_J, ev.kinetic_energy_before_J * (1.0 + 1e-12) + 1e-15)
          << "step " << ev.step << ", " << ev.contacts << " rows";
    }
  }
  EXPECT_EQ(data.warnings[static_cast<int>(Warning::kSolverFailed)].count, failed_before);
  // the kick did make the groups this test is about
  EXPECT_GT(large, 20);
  EXPECT_GE(largest, 300);
}

}  // namespace
}  // namespace rigidtouch
