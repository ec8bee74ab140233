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

struct KickResult {
  int failed = 0;   // impulses the solvers gave up on
  int large = 0;    // impulses of groups of 200 rows or more
  int largest = 0;  // rows of the largest group
};

// settles the pile for `settle` steps, kicks every body and runs `steps` more, checking that no
// impulse adds energy
KickResult KickThePile(int settle, int steps) {
  const Model model = LoadModel(std::string(RIGIDTOUCH_SCENES) + "/pile.xml", LoadOptions{});
  Data data = MakeData(model);
  TickInput in;
  for (int k = 0; k < settle; ++k) Tick(model, data, in);
  std::mt19937_64 rng(3);
  // per component: 0.3 m/s and 10 rad/s in norm on average
  std::normal_distribution<double> v(0.0, 0.3 / std::sqrt(3.0)), w(0.0, 10.0 / std::sqrt(3.0));
  for (BodyState& body : data.bodies) {
    body.v_W += test::Draw3(v, rng);
    body.w_W += test::Draw3(w, rng);
  }
  const int failed_before = data.warnings[static_cast<int>(Warning::kSolverFailed)].count;
  KickResult r;
  for (int k = 0; k < steps; ++k) {
    Tick(model, data, in);
    for (int i = 0; i < data.nimpulse; ++i) {
      const ImpulseEvent& ev = data.impulses[i];
      if (ev.contacts >= 200) ++r.large;
      r.largest = std::max(r.largest, ev.contacts);
      // an impulse never adds energy; tolerance: rounding, 1e-12 of the energy before
      EXPECT_LE(ev.kinetic_energy_after_J, ev.kinetic_energy_before_J * (1.0 + 1e-12) + 1e-15)
          << "step " << ev.step << ", " << ev.contacts << " rows";
    }
  }
  r.failed = data.warnings[static_cast<int>(Warning::kSolverFailed)].count - failed_before;
  return r;
}

// the whole landing (1.5 s after the kick): a release-build test (label slow-engine)
TEST(KickedPileTest, SlowEveryImpulseOfALargeDegenerateGroupIsSolved) {
  const KickResult r = KickThePile(500, 1500);
  EXPECT_EQ(r.failed, 0);
  // the kick did make the groups this test is about
  EXPECT_GT(r.large, 20);
  EXPECT_GE(r.largest, 300);
}

// its fast counterpart, run under the sanitizers too: the first 0.2 s after the kick, where the
// largest groups form (measured: 156 impulses of 200 rows or more, the largest of 462)
TEST(KickedPileTest, EveryImpulseOfTheFirstLargeDegenerateGroupsIsSolved) {
  const KickResult r = KickThePile(300, 200);
  EXPECT_EQ(r.failed, 0);
  EXPECT_GT(r.large, 50);
  EXPECT_GE(r.largest, 300);
}

}  // namespace
}  // namespace rigidtouch
