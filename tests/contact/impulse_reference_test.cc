#include "contact/impulse_reference.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <random>
#include <vector>

#include "contact/impulse_examples.h"
#include "contact/impulse_math.h"
#include "limit_malloc.h"

namespace rigidtouch::contact {
namespace {

// applies p to the example's bodies and returns Jc v afterwards
Eigen::VectorXd ApplyReferenceAndMeasure(ImpulseExample& example, const Eigen::VectorXd& p) {
  ApplyImpulses(example.bodies, example.rows, std::span<const double>(p.data(), p.size()));
  Eigen::VectorXd w(p.size());
  JcV(example.problem(), w);
  return w;
}

class ReferenceRestitution : public ::testing::TestWithParam<double> {};

TEST_P(ReferenceRestitution, SphereOnPlaneFollowsNewton) {
  const double e = GetParam();
  const double mass_kg = 2.0;
  const double v_n_mps = -1.5;
  ImpulseExample example = SpherePlane(mass_kg, 0.1, Vec3(0.2, 0.0, v_n_mps));
  const Eigen::VectorXd p = ReferenceImpulse(example.problem(), e, 1);
  ASSERT_EQ(p.size(), 1);
  // Eq. 5 for one row: p = -(1 + e) m v_n, then v = -e v_n (Eq. 4); tolerance 1e-12 relative
  EXPECT_NEAR(p[0], -(1.0 + e) * mass_kg * v_n_mps, 1e-12 * mass_kg);
  const Eigen::VectorXd w = ApplyReferenceAndMeasure(example, p);
  EXPECT_NEAR(w[0], -e * v_n_mps, 1e-12);
  EXPECT_DOUBLE_EQ(example.bodies[0].v_W.x(), 0.2);  // frictionless: tangential untouched
}

INSTANTIATE_TEST_SUITE_P(Restitution, ReferenceRestitution, ::testing::Values(0.0, 0.5, 1.0));

TEST(ReferenceImpulse, TrainRemovesEqualSharesOfTheApproach) {
  // Eq. 8 with no other forces: after impulse i of N the approach speed is v0 (N - i) / N
  constexpr int kImpulses = 5;
  const double v0_mps = -0.8;
  ImpulseExample example = SpherePlane(0.3, 0.01, Vec3(0, 0, v0_mps));
  for (int i = 1; i <= kImpulses; ++i) {
    const Eigen::VectorXd p = ReferenceImpulse(example.problem(), 0.0, kImpulses - i + 1);
    const Eigen::VectorXd w = ApplyReferenceAndMeasure(example, p);
    // tolerance: rounding, 1e-12 m/s
    EXPECT_NEAR(w[0], v0_mps * (kImpulses - i) / kImpulses, 1e-12) << "impulse " << i;
  }
}

TEST(ReferenceImpulse, BoxLandingFlatStopsEveryCorner) {
  // redundant rows (rank 3): the pseudo-inverse picks the minimum-norm impulse, which lies in
  // range(Jc) = span{1, r_x, r_y}: p_j = m |v_z| / 4 + c_x r_x,j + c_y r_y,j with
  // c_y = -I w_x / (4 h^2) and c_x = I w_y / (4 h^2) (torques about x and y cancel w)
  const double h = 0.05;
  const double mass_kg = 1.0;
  const Vec3 w0(2.0, -1.0, 0.0);
  ImpulseExample box = BoxOnPlane(h, mass_kg, Vec3(0, 0, -1.0), w0);
  const double inertia = mass_kg / 3.0 * 2.0 * h * h;
  const Eigen::VectorXd p = ReferenceImpulse(box.problem(), 0.0, 1);
  for (int j = 0; j < 4; ++j) {
    const Vec3& r = box.rows[j].r_a_W;
    const double expected = mass_kg / 4.0 + inertia * w0.y() / (4 * h * h) * r.x() -
                            inertia * w0.x() / (4 * h * h) * r.y();
    // tolerance: 1e-10 N s, a rank-revealing QR of a rank-3 matrix
    EXPECT_NEAR(p[j], expected, 1e-10) << "corner " << j;
  }
  const Eigen::VectorXd w = ApplyReferenceAndMeasure(box, p);
  EXPECT_LT(w.cwiseAbs().maxCoeff(), 1e-10);
  EXPECT_LT(box.bodies[0].w_W.norm(), 1e-9);
  EXPECT_LT(std::abs(box.bodies[0].v_W.z()), 1e-10);
}

TEST(ReferenceImpulse, HeadOnPlasticGivesCommonVelocity) {
  const double m_a = 2.0, v_a = -1.0, m_b = 0.5, v_b = 3.0;
  ImpulseExample example = HeadOn(m_a, v_a, m_b, v_b);
  const Eigen::VectorXd p = ReferenceImpulse(example.problem(), 0.0, 1);
  ApplyReferenceAndMeasure(example, p);
  const double common = (m_a * v_a + m_b * v_b) / (m_a + m_b);
  // tolerance: rounding, 1e-12 m/s
  EXPECT_NEAR(example.bodies[0].v_W.x(), common, 1e-12);
  EXPECT_NEAR(example.bodies[1].v_W.x(), common, 1e-12);
}

TEST(ReferenceImpulse, StruckStackStopsEverything) {
  // a tool hits a stack of three boxes on the floor, e = 0: the floor stops the whole stack
  ImpulseExample stack = StackWithTool(3, 0.05, 1.0, 0.5, -2.0);
  const Eigen::VectorXd p = ReferenceImpulse(stack.problem(), 0.0, 1);
  ApplyReferenceAndMeasure(stack, p);
  for (const SolverBody& body : stack.bodies) {
    // tolerance: 1e-10 m/s and rad/s against a 2 m/s strike
    EXPECT_LT(body.v_W.norm(), 1e-10);
    EXPECT_LT(body.w_W.norm(), 1e-9);
  }
  EXPECT_GT(p.minCoeff(), 0.0);  // every row pushes here
}

TEST(ReferenceImpulse, SeparatingRowGetsAnAdhesiveImpulse) {
  // a sphere (rows at its centre, no spin) against the floor (n1 = z, approaching at 1 m/s) and
  // a slope (n2 = (1,0,1)/sqrt2, separating at 1/sqrt2 m/s). Eq. 5 zeroes both relative
  // velocities: v+ = 0, so m (-2, 0, 1) = p1 n1 + p2 n2, p2 = -2 sqrt2 m < 0, p1 = 3 m.
  const double mass_kg = 0.5;
  ImpulseExample example = SpherePlane(mass_kg, 0.1, Vec3(2.0, 0.0, -1.0));
  example.rows[0].r_a_W = Vec3::Zero();
  SolverRow slope = example.rows[0];
  slope.n_W = Vec3(1, 0, 1).normalized();
  example.rows.push_back(slope);
  const Eigen::VectorXd p = ReferenceImpulse(example.problem(), 0.0, 1);
  // tolerance: rounding, 1e-12 N s
  EXPECT_NEAR(p[0], 3.0 * mass_kg, 1e-12);
  EXPECT_NEAR(p[1], -2.0 * std::sqrt(2.0) * mass_kg, 1e-12);
  EXPECT_LT(p[1], 0.0);
}

TEST(ReferenceImpulse, NeverAddsKineticEnergy) {
  // finding: the reference never increases kinetic energy, even when it pulls, because
  // w = A p + b = 0 on every row makes dKE = -(s - s^2/2) p^T A p <= 0 for s = 1 + e in [1, 2]
  std::mt19937_64 rng(17);
  int with_adhesion = 0;
  double worst = 0.0;
  for (int trial = 0; trial < 1000; ++trial) {
    const ImpulseExample example = RandomGroup(rng);
    for (const double e : {0.0, 1.0}) {
      ImpulseExample after = example;
      const Eigen::VectorXd p = ReferenceImpulse(example.problem(), e, 1);
      if (p.minCoeff() < 0.0) ++with_adhesion;
      const double ke0 = KineticEnergy(example.bodies);
      Eigen::VectorXd b(p.size());
      JcV(example.problem(), b);
      ApplyReferenceAndMeasure(after, p);
      const double ke1 = KineticEnergy(after.bodies);
      // tolerance: rounding of velocity changes of order impulse / mass,
      // 1e-12 (KE0 + v_ref sum |p|) (e = 1 conserves energy in exact arithmetic)
      const double energy_scale = ke0 + b.cwiseAbs().maxCoeff() * p.cwiseAbs().sum();
      worst = std::max(worst, (ke1 - ke0) / energy_scale);
      ASSERT_LE(ke1, ke0 + 1e-12 * energy_scale) << "trial " << trial << " e " << e;
    }
  }
  std::printf("adhesive answers: %d of 2000; worst relative energy gain %.3g\n", with_adhesion,
              worst);
  // the random groups do exercise adhesive answers
  EXPECT_GT(with_adhesion, 100);
}

TEST(ReferenceImpulse, RejectsBadParameters) {
  const ImpulseExample example = SpherePlane(1.0, 0.1, -Vec3::UnitZ());
  EXPECT_THROW(ReferenceImpulse(example.problem(), -0.1, 1), Error);
  EXPECT_THROW(ReferenceImpulse(example.problem(), 1.5, 1), Error);
  EXPECT_THROW(ReferenceImpulse(example.problem(), std::nan(""), 1), Error);
  EXPECT_THROW(ReferenceImpulse(example.problem(), 0.0, 0), Error);
  ImpulseExample bad = example;
  bad.rows[0].body_a = 3;
  try {
    ReferenceImpulse(bad.problem(), 0.0, 1);
    FAIL() << "expected rigidtouch::Error";
  } catch (const Error& error) {
    // the message names the row, the value and the valid range
    EXPECT_NE(std::string(error.what()).find("row 0"), std::string::npos);
    EXPECT_NE(std::string(error.what()).find("body_a = 3"), std::string::npos);
    EXPECT_NE(std::string(error.what()).find("[-1, 0]"), std::string::npos);
  }
  bad = example;
  bad.bodies[0].v_W.x() = std::nan("");
  EXPECT_THROW(ReferenceImpulse(bad.problem(), 0.0, 1), Error);
}

// --- ReferenceSolver: ReferenceImpulse on preallocated buffers ---

// agreement with ReferenceImpulse: 1e-10 of the impulse scale max |p| (both are exact up to the
// rounding of a rank-revealing factorisation of A)
constexpr double kAgreement = 1e-10;

// the largest difference between ReferenceSolver and ReferenceImpulse, relative to max |p|;
// -1 if the solver refused
double Disagreement(ReferenceSolver& solver, const ImpulseExample& example, double e,
                    int remaining) {
  const Eigen::VectorXd expected = ReferenceImpulse(example.problem(), e, remaining);
  std::vector<double> p(example.rows.size(), std::nan(""));
  if (!solver.Solve(example.problem(), e, remaining, p)) return -1.0;
  double diff = 0.0;
  for (std::size_t j = 0; j < p.size(); ++j) diff = std::max(diff, std::abs(p[j] - expected[j]));
  const double scale = expected.size() > 0 ? expected.cwiseAbs().maxCoeff() : 0.0;
  return scale > 0.0 ? diff / scale : diff;
}

TEST(ReferenceSolver, AgreesWithReferenceImpulseOnTheExamples) {
  ReferenceSolver solver(200, 40);
  std::vector<std::pair<const char*, ImpulseExample>> examples;
  examples.emplace_back("sphere", SpherePlane(2.0, 0.1, Vec3(0.2, 0.0, -1.5)));
  examples.emplace_back("box landing flat (redundant rows)",
                        BoxOnPlane(0.05, 1.0, Vec3(0, 0, -1.0), Vec3(2.0, -1.0, 0.0)));
  examples.emplace_back("head-on", HeadOn(2.0, -1.0, 0.5, 3.0));
  examples.emplace_back("struck stack", StackWithTool(3, 0.05, 1.0, 0.5, -2.0));
  examples.emplace_back("tall stack", StackWithTool(10, 0.05, 0.1, 0.5, -1.0));
  examples.emplace_back("grid pile", BoxGrid(3, 3, 3, 5));
  ImpulseExample separating = SpherePlane(0.5, 0.1, Vec3(2.0, 0.0, -1.0));
  separating.rows[0].r_a_W = Vec3::Zero();
  SolverRow slope = separating.rows[0];
  slope.n_W = Vec3(1, 0, 1).normalized();
  separating.rows.push_back(slope);
  examples.emplace_back("separating row (adhesive impulse)", separating);
  for (const auto& [name, example] : examples) {
    for (const double e : {0.0, 0.5, 1.0}) {
      EXPECT_LE(Disagreement(solver, example, e, 1), kAgreement) << name << ", e " << e;
      EXPECT_GE(Disagreement(solver, example, e, 1), 0.0) << name << ", e " << e;
    }
    // a train (Eq. 8, e = 0): impulse i of N
    for (int remaining = 1; remaining <= 5; ++remaining) {
      const double d = Disagreement(solver, example, 0.0, remaining);
      EXPECT_GE(d, 0.0) << name << ", remaining " << remaining;
      EXPECT_LE(d, kAgreement) << name << ", remaining " << remaining;
    }
  }
  // the adhesive impulse is reproduced, not clipped
  std::vector<double> p(2);
  ASSERT_TRUE(solver.Solve(separating.problem(), 0.0, 1, p));
  EXPECT_LT(p[1], 0.0);
}

TEST(ReferenceSolver, TrainRemovesEqualSharesOfTheApproach) {
  constexpr int kImpulses = 5;
  const double v0_mps = -0.8;
  ImpulseExample example = SpherePlane(0.3, 0.01, Vec3(0, 0, v0_mps));
  ReferenceSolver solver(1, 1);
  for (int i = 1; i <= kImpulses; ++i) {
    std::vector<double> p(1);
    ASSERT_TRUE(solver.Solve(example.problem(), 0.0, kImpulses - i + 1, p));
    ApplyImpulses(example.bodies, example.rows, p);
    // tolerance: rounding, 1e-12 m/s
    EXPECT_NEAR(NormalVelocity(example.problem(), 0), v0_mps * (kImpulses - i) / kImpulses, 1e-12);
  }
}

// the condition number of A on its range: largest over smallest eigenvalue above the
// pseudo-inverse's threshold
double RangeCondition(const ImpulseExample& example) {
  const auto c = static_cast<Eigen::Index>(example.rows.size());
  Eigen::MatrixXd A(c, c);
  DelassusDense(example.problem(), A);
  const Eigen::VectorXd eig = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(A).eigenvalues();
  const double largest = eig.maxCoeff();
  double smallest = largest;
  for (const double l : eig) {
    if (l > kReferencePinvThreshold * largest) smallest = std::min(smallest, l);
  }
  return largest / smallest;
}

TEST(ReferenceSolver, AgreesWithReferenceImpulseOnRandomGroups) {
  // tolerance: 1e-10 of max |p| or, for ill-conditioned groups, eps kappa with kappa the
  // condition number of A on its range. Both solutions carry errors of that order: against a
  // long-double complete orthogonal decomposition, either was off by up to 0.04 eps kappa
  // (2e-9 of max |p| at kappa = 3e8), while well-conditioned groups agree to about 1e-12
  ReferenceSolver solver(24, 6);
  std::mt19937_64 rng(17);
  double worst = 0.0;
  int ill_conditioned = 0;
  auto check = [&](const ImpulseExample& example, double e, int trial) {
    const double kappa = RangeCondition(example);
    const double tolerance = std::max(kAgreement, std::numeric_limits<double>::epsilon() * kappa);
    ill_conditioned += tolerance > kAgreement ? 1 : 0;
    const double d = Disagreement(solver, example, e, 1);
    worst = std::max(worst, d / tolerance);
    EXPECT_GE(d, 0.0) << "trial " << trial;
    EXPECT_LE(d, tolerance) << "trial " << trial << " e " << e << " kappa " << kappa;
  };
  for (int trial = 0; trial < 1000; ++trial) {
    const ImpulseExample example = RandomGroup(rng);
    for (const double e : {0.0, 1.0}) check(example, e, trial);
  }
  // many rows on few bodies: rank-deficient A throughout
  RandomGroupOptions crowded;
  crowded.max_bodies = 2;
  crowded.min_rows = 8;
  for (int trial = 0; trial < 300; ++trial) check(RandomGroup(rng, crowded), 0.0, trial);
  std::printf("worst disagreement: %.3g of the tolerance (%d checks ill-conditioned)\n", worst,
              ill_conditioned);
}

TEST(ReferenceSolver, RefusesBadInputWithoutThrowing) {
  const ImpulseExample example = SpherePlane(1.0, 0.1, -Vec3::UnitZ());
  ReferenceSolver solver(4, 2);
  std::vector<double> p(1, 7.0);
  auto refuses = [&](const ImpulseExample& ex, double e, int remaining) {
    bool ok = true;
    p.assign(ex.rows.size(), 7.0);
    EXPECT_NO_THROW(ok = solver.Solve(ex.problem(), e, remaining, p));
    for (const double value : p) EXPECT_EQ(value, 0.0);  // the safe impulse
    return !ok;
  };
  EXPECT_TRUE(refuses(example, -0.1, 1));
  EXPECT_TRUE(refuses(example, 1.5, 1));
  EXPECT_TRUE(refuses(example, std::nan(""), 1));
  EXPECT_TRUE(refuses(example, 0.0, 0));
  EXPECT_TRUE(refuses(example, 0.0, -3));
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  for (int field = 0; field < 6; ++field) {
    ImpulseExample bad = example;
    switch (field) {
      case 0:
        bad.bodies[0].v_W.x() = nan;
        break;
      case 1:
        bad.bodies[0].w_W.y() = inf;
        break;
      case 2:
        bad.bodies[0].inv_mass = nan;
        break;
      case 3:
        bad.bodies[0].inv_inertia_W(1, 2) = nan;
        break;
      case 4:
        bad.rows[0].n_W.z() = nan;
        break;
      default:
        bad.rows[0].r_a_W.x() = -inf;
        break;
    }
    EXPECT_TRUE(refuses(bad, 0.0, 1)) << "field " << field;
  }
  ImpulseExample bad = example;
  bad.bodies[0].inv_mass = -1.0;
  EXPECT_TRUE(refuses(bad, 0.0, 1));
  bad = example;
  bad.rows[0].body_a = 3;
  EXPECT_TRUE(refuses(bad, 0.0, 1));
  bad.rows[0].body_a = bad.rows[0].body_b = -1;
  EXPECT_TRUE(refuses(bad, 0.0, 1));
  // beyond the capacity: more rows, more bodies
  EXPECT_TRUE(refuses(BoxGrid(1, 1, 2, 1), 0.0, 1));
  EXPECT_TRUE(refuses(StackWithTool(2, 0.05, 1.0, 0.5, -1.0), 0.0, 1));
  // p of the wrong size
  std::vector<double> two(2, 7.0);
  EXPECT_FALSE(solver.Solve(example.problem(), 0.0, 1, two));
  // and after all that it still solves
  std::vector<double> one(1);
  EXPECT_TRUE(solver.Solve(example.problem(), 0.0, 1, one));
  EXPECT_NEAR(one[0], 1.0, 1e-12);  // m |v_n|
  // no rows: nothing to do
  ImpulseExample empty = example;
  empty.rows.clear();
  EXPECT_TRUE(solver.Solve(empty.problem(), 0.0, 1, {}));
}

// ReferenceSolver::Solve allocates nothing, solving or refusing (limit_malloc.h)
TEST(ReferenceSolver, SolveDoesNotAllocate) {
  if (!test::kMallocCounting) GTEST_SKIP() << "malloc is owned by the sanitizer";
  std::mt19937_64 rng(3);
  std::vector<ImpulseExample> examples = {BoxGrid(3, 3, 3, 2),
                                          BoxOnPlane(0.05, 1.0, -Vec3::UnitZ(), Vec3::UnitX()),
                                          StackWithTool(5, 0.05, 1.0, 0.5, -2.0)};
  for (int k = 0; k < 50; ++k) examples.push_back(RandomGroup(rng));
  ReferenceSolver solver(200, 40);
  std::vector<double> p(200);
  {
    // the probe works: an allocation is seen
    test::LimitMalloc probe_guard;
    test::ProbeAllocation();
    ASSERT_EQ(probe_guard.allocations(), 1);
  }
  ImpulseExample bad = examples[0];  // copied outside the count
  bad.bodies[0].v_W.x() = std::nan("");
  int solved = 0;
  bool refused = false;
  long allocations = -1;
  {
    test::LimitMalloc guard;
    for (const ImpulseExample& example : examples) {
      const std::span<double> p_rows(p.data(), example.rows.size());
      solved += solver.Solve(example.problem(), 0.5, 1, p_rows) ? 1 : 0;
      solved += solver.Solve(example.problem(), 0.0, 3, p_rows) ? 1 : 0;
    }
    refused = !solver.Solve(bad.problem(), 0.0, 1, std::span<double>(p.data(), bad.rows.size()));
    allocations = guard.allocations();
  }
  EXPECT_EQ(allocations, 0);
  EXPECT_EQ(solved, 2 * static_cast<int>(examples.size()));
  EXPECT_TRUE(refused);
}

}  // namespace
}  // namespace rigidtouch::contact
