#include "contact/impulse_solver.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/QR>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "contact/impulse_examples.h"
#include "contact/impulse_math.h"
#include "contact/impulse_reference.h"
#include "limit_malloc.h"

namespace rigidtouch::contact {
namespace {

// the dense path (active set and polish), or the matrix-free path alone (MPRGP and the
// conjugate-gradient polish, no dense buffers)
ImpulseSolverOptions PathOptions(bool matrix_free) {
  ImpulseSolverOptions options;
  options.dense_max_rows = matrix_free ? 0 : 1000;
  options.dense_polish_max_rows = matrix_free ? 0 : 1000;
  return options;
}

// solves with a fresh solver sized for the example; expects success
std::vector<double> SolveOk(const ImpulseExample& example, double scale, bool matrix_free,
                            ImpulseSolverStats* stats_out = nullptr) {
  ImpulseSolver solver(static_cast<int>(example.rows.size()),
                       static_cast<int>(example.bodies.size()), PathOptions(matrix_free));
  std::vector<double> p(example.rows.size(), -1.0);
  const ImpulseSolverStats stats = solver.Solve(example.problem(), scale, p);
  EXPECT_EQ(stats.error, ImpulseSolverError::kNone) << ToString(stats.error);
  EXPECT_EQ(stats.matrix_free, matrix_free);
  if (stats_out != nullptr) *stats_out = stats;
  return p;
}

// applies p and returns Jc v afterwards
Eigen::VectorXd ApplySolvedAndMeasure(ImpulseExample& example, const std::vector<double>& p) {
  ApplyImpulses(example.bodies, example.rows, p);
  Eigen::VectorXd w(static_cast<Eigen::Index>(p.size()));
  JcV(example.problem(), w);
  return w;
}

double MaxAbsVelocity(const ImpulseExample& example) {
  Eigen::VectorXd b(static_cast<Eigen::Index>(example.rows.size()));
  JcV(example.problem(), b);
  return b.cwiseAbs().maxCoeff();
}

// both paths of the production solver: dense active set (false) and MPRGP (true)
class SolverPath : public ::testing::TestWithParam<bool> {};

INSTANTIATE_TEST_SUITE_P(Paths, SolverPath, ::testing::Values(false, true),
                         [](const auto& info) { return info.param ? "MatrixFree" : "Dense"; });

TEST_P(SolverPath, SphereOnPlaneFollowsNewton) {
  for (const double e : {0.0, 0.5, 1.0}) {
    const double mass_kg = 2.0;
    const double v_n_mps = -1.5;
    ImpulseExample example = SpherePlane(mass_kg, 0.1, Vec3(0.2, 0.0, v_n_mps));
    const std::vector<double> p = SolveOk(example, 1.0 + e, GetParam());
    // Eq. 5: p = -(1 + e) m v_n, then v = -e v_n; tolerance 1e-12 relative
    EXPECT_NEAR(p[0], -(1.0 + e) * mass_kg * v_n_mps, 1e-12 * mass_kg) << "e " << e;
    const Eigen::VectorXd w = ApplySolvedAndMeasure(example, p);
    EXPECT_NEAR(w[0], -e * v_n_mps, 1e-12) << "e " << e;
  }
}

TEST_P(SolverPath, TrainRemovesEqualSharesOfTheApproach) {
  // Eq. 8, e = 0, scale 1 / (N - i + 1): after impulse i the approach speed is v0 (N - i) / N
  constexpr int kImpulses = 5;
  const double v0_mps = -0.8;
  ImpulseExample example = SpherePlane(0.3, 0.01, Vec3(0, 0, v0_mps));
  ImpulseSolver solver(1, 1, PathOptions(GetParam()));
  std::vector<double> p(1);
  for (int i = 1; i <= kImpulses; ++i) {
    const ImpulseSolverStats stats =
        solver.Solve(example.problem(), 1.0 / (kImpulses - i + 1), p, solver.plastic_impulse());
    ASSERT_EQ(stats.error, ImpulseSolverError::kNone);
    const Eigen::VectorXd w = ApplySolvedAndMeasure(example, p);
    // tolerance: rounding, 1e-12 m/s
    EXPECT_NEAR(w[0], v0_mps * (kImpulses - i) / kImpulses, 1e-12) << "impulse " << i;
  }
}

TEST_P(SolverPath, BoxLandingFlatStopsEveryCornerWithTheMinimumNormImpulse) {
  const double h = 0.05;
  const double mass_kg = 1.0;
  const Vec3 w0(2.0, -1.0, 0.0);
  ImpulseExample box = BoxOnPlane(h, mass_kg, Vec3(0, 0, -1.0), w0);
  const Eigen::VectorXd reference = ReferenceImpulse(box.problem(), 0.0, 1);
  ImpulseSolverStats stats;
  const std::vector<double> p = SolveOk(box, 1.0, GetParam(), &stats);
  EXPECT_TRUE(stats.min_norm);
  // closed form as in the reference test: p_j = m/4 + I w_y r_x / (4h^2) - I w_x r_y / (4h^2)
  const double inertia = mass_kg / 3.0 * 2.0 * h * h;
  for (int j = 0; j < 4; ++j) {
    const Vec3& r = box.rows[j].r_a_W;
    const double expected = mass_kg / 4.0 + inertia * w0.y() / (4 * h * h) * r.x() -
                            inertia * w0.x() / (4 * h * h) * r.y();
    // tolerance: 1e-10 N s on impulses of 0.25 N s
    EXPECT_NEAR(p[j], expected, 1e-10) << "corner " << j;
    EXPECT_NEAR(p[j], reference[j], 1e-10) << "corner " << j;
  }
  const Eigen::VectorXd w = ApplySolvedAndMeasure(box, p);
  EXPECT_LT(w.cwiseAbs().maxCoeff(), 1e-10);
  EXPECT_LT(box.bodies[0].w_W.norm(), 1e-9);
}

TEST_P(SolverPath, HeadOnPlasticGivesCommonVelocity) {
  const double m_a = 2.0, v_a = -1.0, m_b = 0.5, v_b = 3.0;
  ImpulseExample example = HeadOn(m_a, v_a, m_b, v_b);
  const std::vector<double> p = SolveOk(example, 1.0, GetParam());
  ApplySolvedAndMeasure(example, p);
  const double common = (m_a * v_a + m_b * v_b) / (m_a + m_b);
  // tolerance: rounding, 1e-12 m/s
  EXPECT_NEAR(example.bodies[0].v_W.x(), common, 1e-12);
  EXPECT_NEAR(example.bodies[1].v_W.x(), common, 1e-12);
}

TEST_P(SolverPath, StruckStackStopsEverything) {
  ImpulseExample stack = StackWithTool(3, 0.05, 1.0, 0.5, -2.0);
  const Eigen::VectorXd reference = ReferenceImpulse(stack.problem(), 0.0, 1);
  const std::vector<double> p = SolveOk(stack, 1.0, GetParam());
  for (std::size_t j = 0; j < p.size(); ++j) {
    // the reference is positive here, so the two agree; tolerance 1e-9 relative
    EXPECT_NEAR(p[j], reference[j], 1e-9 * reference.cwiseAbs().maxCoeff()) << "row " << j;
  }
  ApplySolvedAndMeasure(stack, p);
  for (const SolverBody& body : stack.bodies) {
    // tolerance: 1e-9 m/s and rad/s against a 2 m/s strike
    EXPECT_LT(body.v_W.norm(), 1e-9);
    EXPECT_LT(body.w_W.norm(), 1e-8);
  }
}

TEST_P(SolverPath, NeverPullsWhereTheReferenceDoes) {
  // the configuration of the reference test: Eq. 5 gives p = (3m, -2 sqrt2 m); the plastic LCP
  // answer is p = (m, 0): the floor stops the fall and the slope, which separates, is left alone
  const double mass_kg = 0.5;
  ImpulseExample example = SpherePlane(mass_kg, 0.1, Vec3(2.0, 0.0, -1.0));
  example.rows[0].r_a_W = Vec3::Zero();
  SolverRow slope = example.rows[0];
  slope.n_W = Vec3(1, 0, 1).normalized();
  example.rows.push_back(slope);
  const Eigen::VectorXd reference = ReferenceImpulse(example.problem(), 0.0, 1);
  ASSERT_LT(reference[1], 0.0);
  const std::vector<double> p = SolveOk(example, 1.0, GetParam());
  // tolerance: rounding, 1e-12 N s
  EXPECT_NEAR(p[0], mass_kg, 1e-12);
  EXPECT_EQ(p[1], 0.0);
  const Eigen::VectorXd w = ApplySolvedAndMeasure(example, p);
  EXPECT_NEAR(w[0], 0.0, 1e-12);
  EXPECT_NEAR(w[1], 2.0 / std::sqrt(2.0), 1e-12);  // v+ = (2, 0, 0) still separates the slope
}

TEST_P(SolverPath, NeverPullsInAChain) {
  // a chain: tool -> box 0 -> box 1 along -z with box 1 already moving away from box 0 fast;
  // the reference pulls box 1 back (negative row), the solver must not
  ImpulseExample stack = StackWithTool(2, 0.05, 1.0, 0.5, -1.0);
  stack.bodies[1].v_W = Vec3(0, 0, 3.0);  // the top box flies up off the lower box
  // drop the floor rows so box 0 is free: rows 0-3 are box 0 on the floor
  stack.rows.erase(stack.rows.begin(), stack.rows.begin() + 4);
  // rows now: box 1 on box 0 (4), tool on box 1 (1): tool moves down at 1, box 1 up at 3
  const Eigen::VectorXd reference = ReferenceImpulse(stack.problem(), 0.0, 1);
  ASSERT_LT(reference.minCoeff(), 0.0);
  ImpulseExample after = stack;
  const std::vector<double> p = SolveOk(after, 1.0, GetParam());
  const Eigen::VectorXd w = ApplySolvedAndMeasure(after, p);
  // closed form: only the tool row acts, tool (0.5 kg, -1) and box 1 (1 kg, +3) meet at
  // (0.5 * -1 + 3) / 1.5 = 5/3 m/s; box 1 still separates from box 0 at rest
  for (int j = 0; j < 4; ++j) EXPECT_EQ(p[j], 0.0);
  EXPECT_NEAR(after.bodies[1].v_W.z(), 5.0 / 3.0, 1e-12);
  EXPECT_NEAR(after.bodies[2].v_W.z(), 5.0 / 3.0, 1e-12);
  EXPECT_GE(w.minCoeff(), -1e-12);
}

TEST_P(SolverPath, EqualsReferenceWhenTheReferenceIsNonNegative) {
  std::mt19937_64 rng(23);
  RandomGroupOptions options;
  options.max_bodies = 4;
  options.max_rows = 12;
  int compared = 0;
  for (int trial = 0; trial < 4000 && compared < 300; ++trial) {
    const ImpulseExample example = RandomGroup(rng, options);
    const Eigen::VectorXd reference = ReferenceImpulse(example.problem(), 0.0, 1);
    // non-degenerate, non-negative reference answers only: every component clearly positive
    const double p_max = reference.cwiseAbs().maxCoeff();
    if (!(p_max > 0.0) || reference.minCoeff() < 1e-3 * p_max) continue;
    ++compared;
    const std::vector<double> p = SolveOk(example, 1.0, GetParam());
    for (Eigen::Index j = 0; j < reference.size(); ++j) {
      // tolerance: 1e-8 relative to the largest impulse
      ASSERT_NEAR(p[j], reference[j], 1e-8 * p_max) << "trial " << trial << " row " << j;
    }
  }
  EXPECT_GE(compared, 300);
}

// Non-negative least squares min |C mu - d| over mu >= 0 (Lawson-Hanson), for the independent
// minimum-norm check below; small dense problems only
Eigen::VectorXd Nnls(const Eigen::MatrixXd& C, const Eigen::VectorXd& d) {
  const Eigen::Index n = C.cols();
  Eigen::VectorXd mu = Eigen::VectorXd::Zero(n);
  std::vector<bool> passive(static_cast<std::size_t>(n), false);
  for (int outer = 0; outer < 10 * n + 10; ++outer) {
    const Eigen::VectorXd gradient = C.transpose() * (d - C * mu);
    Eigen::Index best = -1;
    for (Eigen::Index i = 0; i < n; ++i) {
      if (!passive[i] && gradient[i] > 1e-14 * (1.0 + d.norm()) &&
          (best < 0 || gradient[i] > gradient[best])) {
        best = i;
      }
    }
    if (best < 0) break;
    passive[best] = true;
    for (int inner = 0; inner < 10 * n + 10; ++inner) {
      std::vector<Eigen::Index> set;
      for (Eigen::Index i = 0; i < n; ++i) {
        if (passive[i]) set.push_back(i);
      }
      Eigen::MatrixXd cs(C.rows(), static_cast<Eigen::Index>(set.size()));
      for (std::size_t k = 0; k < set.size(); ++k) cs.col(k) = C.col(set[k]);
      const Eigen::VectorXd zs = cs.completeOrthogonalDecomposition().solve(d);
      double step = 1.0;
      for (std::size_t k = 0; k < set.size(); ++k) {
        if (zs[k] <= 0.0) step = std::min(step, mu[set[k]] / (mu[set[k]] - zs[k]));
      }
      for (std::size_t k = 0; k < set.size(); ++k) mu[set[k]] += step * (zs[k] - mu[set[k]]);
      if (step == 1.0) break;
      for (std::size_t k = 0; k < set.size(); ++k) {
        if (mu[set[k]] <= 1e-15) {
          mu[set[k]] = 0.0;
          passive[set[k]] = false;
        }
      }
    }
  }
  return mu;
}

// Independent check that p is the minimum-norm plastic impulse: with F = {j : w_j ~ 0}, every
// plastic impulse is p + t with t in null(A_FF), t_j >= -p_j. p has the minimum norm iff no such
// direction decreases |p|, i.e. (Farkas) N^T p = N_Z^T mu for some mu >= 0, where N spans
// null(A_FF) and Z = {j in F : p_j = 0}. Returns the relative residual of that system.
double MinimumNormResidual(const ImpulseExample& example, const std::vector<double>& p,
                           const Eigen::VectorXd& w, double v_ref) {
  const auto c = static_cast<Eigen::Index>(example.rows.size());
  Eigen::MatrixXd A(c, c);
  DelassusDense(example.problem(), A);
  std::vector<Eigen::Index> set, zero;
  for (Eigen::Index j = 0; j < c; ++j) {
    if (w[j] <= 1e-8 * v_ref) set.push_back(j);
  }
  const auto f = static_cast<Eigen::Index>(set.size());
  if (f == 0) return 0.0;
  Eigen::MatrixXd a_ff(f, f);
  Eigen::VectorXd p_f(f);
  double p_max = 0.0;
  for (Eigen::Index i = 0; i < f; ++i) {
    for (Eigen::Index k = 0; k < f; ++k) a_ff(i, k) = A(set[i], set[k]);
    p_f[i] = p[set[i]];
    p_max = std::max(p_max, p_f[i]);
  }
  for (Eigen::Index i = 0; i < f; ++i) {
    if (p_f[i] <= 1e-12 * p_max) zero.push_back(i);
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(a_ff);
  const double lambda_max = eigen.eigenvalues().cwiseAbs().maxCoeff();
  std::vector<Eigen::Index> null_columns;
  for (Eigen::Index k = 0; k < f; ++k) {
    if (std::abs(eigen.eigenvalues()[k]) <= 1e-10 * lambda_max) null_columns.push_back(k);
  }
  if (null_columns.empty() || p_max == 0.0) return 0.0;
  Eigen::MatrixXd N(f, static_cast<Eigen::Index>(null_columns.size()));
  for (std::size_t k = 0; k < null_columns.size(); ++k) {
    N.col(k) = eigen.eigenvectors().col(null_columns[k]);
  }
  const Eigen::VectorXd target = N.transpose() * p_f;
  if (zero.empty()) return target.norm() / p_f.norm();
  Eigen::MatrixXd n_z(N.cols(), static_cast<Eigen::Index>(zero.size()));
  for (std::size_t k = 0; k < zero.size(); ++k) n_z.col(k) = N.row(zero[k]).transpose();
  const Eigen::VectorXd mu = Nnls(n_z, target);
  return (n_z * mu - target).norm() / p_f.norm();
}

// Solves 1000 random groups at scales 1, 0.5, 1/25 and 2 and checks every answer: p >= 0, no
// energy gain, no approach and complementarity after p* (to `approach` of the largest velocity),
// and the minimum norm whenever claimed. Returns through `min_norm` how often the polish was
// accepted.
void CheckRandomGroups(const ImpulseSolverOptions& options, int& min_norm, double approach = 1e-8) {
  std::mt19937_64 rng(29);
  ImpulseSolver solver(24, 6, options);
  std::vector<double> p(24);
  min_norm = 0;
  double worst_energy = 0.0;
  double worst_min_norm = 0.0;
  for (int trial = 0; trial < 1000; ++trial) {
    const ImpulseExample example = RandomGroup(rng);
    const auto c = example.rows.size();
    const double v_ref = MaxAbsVelocity(example);
    const double ke0 = KineticEnergy(example.bodies);
    for (const double scale : {1.0, 0.5, 1.0 / 25.0, 2.0}) {
      const ImpulseSolverStats stats =
          solver.Solve(example.problem(), scale, std::span(p).first(c));
      ASSERT_EQ(stats.error, ImpulseSolverError::kNone)
          << "trial " << trial << ": " << ToString(stats.error);
      const std::vector<double> p_c(p.begin(), p.begin() + c);
      ImpulseExample after = example;
      const Eigen::VectorXd w = ApplySolvedAndMeasure(after, p_c);
      double impulse_sum = 0.0;
      for (std::size_t j = 0; j < c; ++j) {
        ASSERT_GE(p[j], 0.0);
        impulse_sum += p[j];
      }
      // dKE = -(s - s^2/2) p*^T A p* <= 0. Tolerance: rounding of velocity changes of order
      // impulse / mass, 1e-12 (KE0 + v_ref sum p) (s = 2 conserves energy in exact arithmetic)
      const double energy_tol = 1e-12 * (ke0 + v_ref * impulse_sum);
      const double ke1 = KineticEnergy(after.bodies);
      worst_energy = std::max(worst_energy, (ke1 - ke0) / (ke0 + v_ref * impulse_sum));
      ASSERT_LE(ke1, ke0 + energy_tol) << "trial " << trial << " scale " << scale;
      if (scale == 1.0) {
        // no row approaches after the plastic impulse; tolerance `approach` v_ref
        ASSERT_GE(w.minCoeff(), -approach * v_ref) << "trial " << trial;
        // complementarity p_j w_j = 0; tolerance `approach` v_ref times the impulse
        for (std::size_t j = 0; j < c; ++j) {
          ASSERT_LE(p[j] * std::abs(w[j]), approach * v_ref * p[j]) << "trial " << trial;
        }
        if (stats.min_norm) {
          ++min_norm;
          // whenever the solver claims the minimum norm, an independent check agrees;
          // tolerance 1e-7 relative (null space from an eigendecomposition)
          const double residual = MinimumNormResidual(example, p_c, w, v_ref);
          worst_min_norm = std::max(worst_min_norm, residual);
          ASSERT_LE(residual, 1e-7) << "trial " << trial;
        }
      }
    }
  }
  std::printf("minimum norm in %d of 1000; worst energy gain %.3g, min-norm residual %.3g\n",
              min_norm, worst_energy, worst_min_norm);
}

TEST(ImpulseSolver, DensePathIsSafeAndOfMinimumNormOnRandomGroups) {
  int min_norm = 0;
  CheckRandomGroups(PathOptions(false), min_norm);
  // the dense path finds the minimum-norm impulse in all but a few: the polish's candidate is
  // refused when its rounding lets a row approach by more than 10 tolerance v_ref
  // (impulse_solver.h, step 3), as in 1 of these 1000 (a row at -2.4e-9 v_ref under an impulse of
  // 52 N s)
  EXPECT_GE(min_norm, 995);
}

TEST(ImpulseSolver, MatrixFreePathIsSafeOnRandomGroups) {
  int min_norm = 0;
  CheckRandomGroups(PathOptions(true), min_norm);
  // the conjugate-gradient polish only finds the minimum norm when it lies in range(A_FF) without
  // bounds (see impulse_solver.h), which the highly redundant random groups (up to 24 rows on two
  // bodies) miss in about one case in ten
  EXPECT_GE(min_norm, 800);
}

TEST(ImpulseSolver, DefaultOptionsPolishSmallFreeSetsExactly) {
  // default options: MPRGP above 8 rows, the exact dense polish when CG's answer is not >= 0
  int min_norm_default = 0;
  int min_norm_cg = 0;
  CheckRandomGroups(ImpulseSolverOptions{}, min_norm_default);
  CheckRandomGroups(PathOptions(true), min_norm_cg);
  EXPECT_GE(min_norm_default, 995);
  EXPECT_GT(min_norm_default, min_norm_cg);
}

TEST(ImpulseSolver, StalledMprgpFallsBackToTheDenseMethod) {
  // highly degenerate random groups (24 rows on 2 bodies, rank 12) can stall MPRGP; groups that
  // fit the dense buffers are then solved by the dense active set instead of failing
  ImpulseSolverOptions options;
  options.dense_max_rows = 0;
  ImpulseSolver solver(24, 6, options);
  std::mt19937_64 rng(5);  // this stream holds two such groups among its first 2000
  std::vector<double> p(24);
  int fallbacks = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    const ImpulseExample example = RandomGroup(rng);
    const auto c = example.rows.size();
    const ImpulseSolverStats stats = solver.Solve(example.problem(), 1.0, std::span(p).first(c));
    ASSERT_EQ(stats.error, ImpulseSolverError::kNone) << "trial " << trial;
    if (!stats.matrix_free && stats.iterations > 0) ++fallbacks;
  }
  EXPECT_GT(fallbacks, 0);
}

TEST(ImpulseSolver, InteriorPointIsSafeOnRandomGroups) {
  // every random group straight to the interior-point method (no dense active set, no MPRGP
  // iteration): the same checks as for the other paths, on its own answer (no polish runs after
  // it without the dense buffers) ...
  ImpulseSolverOptions options = PathOptions(true);
  options.interior_after_iterations = 0;
  int min_norm = 0;
  // its answer may leave rows approaching at up to a tenth of what Solve's final check accepts
  // (impulse_interior.cc), 1e-7 v_ref: 1.4e-8 v_ref in one of these groups
  const double approach = 0.1 * options.failure_tolerance;
  CheckRandomGroups(options, min_norm, approach);
  // ... and with the dense polish (the only one after the interior point) the minimum norm in
  // all but a few
  options.dense_polish_max_rows = 32;
  CheckRandomGroups(options, min_norm, approach);
  EXPECT_GE(min_norm, 995);
}

// the closed form of StackWithTool(5, 0.05, 1.0, 0.5, -1.0) below: every body at rest after p,
// the tool's row 0.5 N s and each corner row 0.125 N s. Tolerance 1e-9 of the tool's speed, and
// 1e-9 of the tool's momentum for the impulses
void ExpectStackHitStopped(const ImpulseExample& stack, const std::vector<double>& p) {
  ImpulseExample after = stack;
  ApplySolvedAndMeasure(after, p);
  for (const SolverBody& body : after.bodies) {
    EXPECT_LE(body.v_W.norm(), 1e-9);
    EXPECT_LE(body.w_W.norm() * 0.05, 1e-9);
  }
  const int tool = static_cast<int>(stack.bodies.size()) - 1;
  for (std::size_t j = 0; j < stack.rows.size(); ++j) {
    const bool tool_row = stack.rows[j].body_a == tool || stack.rows[j].body_b == tool;
    EXPECT_NEAR(p[j], tool_row ? 0.5 : 0.125, 1e-9 * 0.5) << "row " << j;
  }
}

TEST(ImpulseSolver, InteriorPointStopsAStackHitFromAbove) {
  // closed form: a 0.5 kg tool moving down at 1 m/s onto a column of 5 boxes at rest on the floor.
  // The plastic impulse stops everything: every body ends at rest, the tool's row carries
  // m_t |v| = 0.5 N s, and each of the 4 corner rows under each box a quarter of it (the floor
  // and the boxes carry the tool's momentum down; by symmetry the corners share it equally).
  const ImpulseExample stack = StackWithTool(5, 0.05, 1.0, 0.5, -1.0);
  const auto c = stack.rows.size();
  ImpulseSolverOptions options = PathOptions(true);
  options.interior_after_iterations = 0;
  ImpulseSolver solver(static_cast<int>(c), static_cast<int>(stack.bodies.size()), options);
  std::vector<double> p(c);
  const ImpulseSolverStats stats = solver.Solve(stack.problem(), 1.0, p);
  ASSERT_EQ(stats.error, ImpulseSolverError::kNone) << ToString(stats.error);
  EXPECT_TRUE(stats.interior_point);
  EXPECT_EQ(stats.iterations, 0);  // no MPRGP iteration
  EXPECT_GT(stats.interior_iterations, 0);
  EXPECT_LE(stats.interior_iterations, 40);
  ExpectStackHitStopped(stack, p);
}

TEST(ImpulseSolver, HintSendsALargeGroupToTheInteriorPointAtOnce) {
  // the same closed form as above, with the default budget: MPRGP settles this column by itself,
  // so only the hint sends it to the interior-point method, and the answer is the same
  const ImpulseExample stack = StackWithTool(5, 0.05, 1.0, 0.5, -1.0);
  const auto c = stack.rows.size();
  const int nb = static_cast<int>(stack.bodies.size());
  const ImpulseSolverOptions options = PathOptions(true);  // no dense path: MPRGP from 1 row
  ImpulseSolver solver(static_cast<int>(c), nb, options);
  std::vector<double> p(c);
  const ImpulseSolverStats plain = solver.Solve(stack.problem(), 1.0, p);
  ASSERT_EQ(plain.error, ImpulseSolverError::kNone) << ToString(plain.error);
  ASSERT_FALSE(plain.interior_point);
  ASSERT_GT(plain.iterations, 0);
  const ImpulseSolverStats hinted =
      solver.Solve(stack.problem(), 1.0, p, {}, ImpulseSolveHint{.interior = true});
  ASSERT_EQ(hinted.error, ImpulseSolverError::kNone) << ToString(hinted.error);
  EXPECT_TRUE(hinted.interior_point);
  EXPECT_EQ(hinted.iterations, 0);  // no MPRGP iteration
  EXPECT_GT(hinted.interior_iterations, 0);
  ExpectStackHitStopped(stack, p);

  // where the interior-point method cannot take the group the hint changes nothing: more bodies
  // than it is sized for, or few enough rows for the dense method
  ImpulseSolverOptions small_factor = options;
  small_factor.interior_max_bodies = nb - 1;
  ImpulseSolver no_room(static_cast<int>(c), nb, small_factor);
  const ImpulseSolverStats too_many =
      no_room.Solve(stack.problem(), 1.0, p, {}, ImpulseSolveHint{.interior = true});
  ASSERT_EQ(too_many.error, ImpulseSolverError::kNone) << ToString(too_many.error);
  EXPECT_FALSE(too_many.interior_point);
  EXPECT_EQ(too_many.iterations, plain.iterations);
  ImpulseSolver dense(static_cast<int>(c), nb, PathOptions(false));
  const ImpulseSolverStats small =
      dense.Solve(stack.problem(), 1.0, p, {}, ImpulseSolveHint{.interior = true});
  ASSERT_EQ(small.error, ImpulseSolverError::kNone) << ToString(small.error);
  EXPECT_FALSE(small.interior_point);
  EXPECT_FALSE(small.matrix_free);
}

TEST_P(SolverPath, WarmStartGivesTheSameAnswer) {
  std::mt19937_64 rng(31);
  const bool matrix_free = GetParam();
  ImpulseSolver cold(24, 6, PathOptions(matrix_free));
  ImpulseSolver warm(24, 6, PathOptions(matrix_free));
  std::vector<double> p_cold(24), p_warm(24);
  for (int trial = 0; trial < 200; ++trial) {
    ImpulseExample example = RandomGroup(rng);
    const auto c = example.rows.size();
    // a two-impulse train: the second solve starts from the first plastic impulse
    for (const int remaining : {2, 1}) {
      const double scale = 1.0 / remaining;
      const ImpulseSolverStats s_cold =
          cold.Solve(example.problem(), scale, std::span(p_cold).first(c));
      const ImpulseSolverStats s_warm =
          warm.Solve(example.problem(), scale, std::span(p_warm).first(c), warm.plastic_impulse());
      ASSERT_EQ(s_cold.error, ImpulseSolverError::kNone);
      ASSERT_EQ(s_warm.error, ImpulseSolverError::kNone);
      const double p_max = *std::max_element(p_cold.begin(), p_cold.begin() + c);
      if (s_cold.min_norm && s_warm.min_norm) {
        for (std::size_t j = 0; j < c; ++j) {
          // tolerance: 1e-8 relative, both are the minimum-norm plastic impulse
          ASSERT_NEAR(p_warm[j], p_cold[j], 1e-8 * p_max + 1e-300) << "trial " << trial;
        }
      }
      ApplyImpulses(example.bodies, example.rows, std::span(p_cold).first(c));
    }
  }
}

TEST(ImpulseSolver, LargeGroupMatchesThePlasticConditions) {
  // a 5 x 5 x 4 pile of boxes (100 bodies, 400 rows, 4 per box to the box below) and a tool
  const ImpulseExample pile = BoxGrid(5, 5, 4, 3);
  ASSERT_EQ(pile.rows.size(), 401u);
  const auto c = static_cast<Eigen::Index>(pile.rows.size());
  const double v_ref = MaxAbsVelocity(pile);
  ImpulseSolverStats stats;
  const std::vector<double> p = SolveOk(pile, 1.0, true, &stats);
  EXPECT_TRUE(stats.converged);
  EXPECT_TRUE(stats.min_norm);
  ImpulseExample after = pile;
  const Eigen::VectorXd w = ApplySolvedAndMeasure(after, p);
  double complementarity_J = 0.0;  // sum p_j |w_j|
  for (Eigen::Index j = 0; j < c; ++j) {
    ASSERT_GE(p[j], 0.0);
    complementarity_J += p[j] * std::abs(w[j]);
  }
  // tolerances: 1e-9 v_ref for the approach speed, 1e-9 of the dissipated energy for p . w
  EXPECT_GE(w.minCoeff(), -1e-9 * v_ref);
  const double dissipated_J = KineticEnergy(pile.bodies) - KineticEnergy(after.bodies);
  EXPECT_GT(dissipated_J, 0.0);
  EXPECT_LE(complementarity_J, 1e-9 * dissipated_J);
  // the dense path (exact active set) finds the same minimum-norm impulse; tolerance 1e-8 relative
  const std::vector<double> p_dense = SolveOk(pile, 1.0, false);
  const double p_max = *std::max_element(p_dense.begin(), p_dense.end());
  for (Eigen::Index j = 0; j < c; ++j) EXPECT_NEAR(p[j], p_dense[j], 1e-8 * p_max) << "row " << j;
}

TEST(ImpulseSolver, InfiniteMassRowsAreInertAndGetNoImpulse) {
  // a kinematic body (infinite mass and inertia) moving into the floor: nothing can stop it
  ImpulseExample example = SpherePlane(1.0, 0.1, -Vec3::UnitZ());
  example.bodies[0].inv_mass = 0.0;
  example.bodies[0].inv_inertia_W.setZero();
  // and a normal sphere resting on the floor next to it, approaching at 0.5 m/s
  const ImpulseExample other = SpherePlane(2.0, 0.1, Vec3(0, 0, -0.5));
  example.bodies.push_back(other.bodies[0]);
  example.rows.push_back(other.rows[0]);
  example.rows.back().body_a = 1;
  ImpulseSolver solver(2, 2);
  std::vector<double> p(2);
  const ImpulseSolverStats stats = solver.Solve(example.problem(), 1.0, p);
  EXPECT_EQ(stats.error, ImpulseSolverError::kNone);
  EXPECT_EQ(stats.inert_rows, 1);
  EXPECT_EQ(stats.unresolved_rows, 1);
  EXPECT_EQ(p[0], 0.0);
  EXPECT_NEAR(p[1], 1.0, 1e-12);  // m |v| = 2 * 0.5
}

TEST(ImpulseSolver, ReturnsTheSafeImpulseOnBadInput) {
  const ImpulseExample example = StackWithTool(2, 0.05, 1.0, 0.5, -1.0);  // 2 bodies + tool, 9 rows
  const auto c = example.rows.size();
  std::vector<double> p(c, 1.0);
  auto expect_error = [&](ImpulseSolver& solver, const ImpulseExample& problem, double scale,
                          std::span<double> out, ImpulseSolverError expected) {
    std::fill(out.begin(), out.end(), 1.0);
    const ImpulseSolverStats stats = solver.Solve(problem.problem(), scale, out);
    EXPECT_EQ(stats.error, expected) << ToString(stats.error);
    for (const double value : out) EXPECT_EQ(value, 0.0);
  };
  ImpulseSolver small_rows(static_cast<int>(c) - 1, 3);
  expect_error(small_rows, example, 1.0, p, ImpulseSolverError::kTooManyRows);
  ImpulseSolver small_bodies(static_cast<int>(c), 2);
  expect_error(small_bodies, example, 1.0, p, ImpulseSolverError::kTooManyBodies);

  ImpulseSolver solver(static_cast<int>(c), 3);
  expect_error(solver, example, 1.0, std::span(p).first(c - 1), ImpulseSolverError::kSizeMismatch);
  for (const double scale : {-0.1, 2.5, std::numeric_limits<double>::quiet_NaN()}) {
    expect_error(solver, example, scale, p, ImpulseSolverError::kBadScale);
  }
  ImpulseExample bad = example;
  bad.bodies[1].w_W.y() = std::numeric_limits<double>::infinity();
  expect_error(solver, bad, 1.0, p, ImpulseSolverError::kNonFiniteInput);
  bad = example;
  bad.rows[3].n_W.x() = std::numeric_limits<double>::quiet_NaN();
  expect_error(solver, bad, 1.0, p, ImpulseSolverError::kNonFiniteInput);
  bad = example;
  bad.bodies[0].inv_mass = -1.0;
  expect_error(solver, bad, 1.0, p, ImpulseSolverError::kNonFiniteInput);
  bad = example;
  bad.rows[2].body_b = 7;
  expect_error(solver, bad, 1.0, p, ImpulseSolverError::kBadBodyIndex);
  bad = example;
  bad.rows[2].body_b = bad.rows[2].body_a;
  expect_error(solver, bad, 1.0, p, ImpulseSolverError::kBadBodyIndex);

  // an iteration limit too small to finish: not converged, safe output, for both paths (without
  // the interior-point method, which would take over from MPRGP)
  for (const bool matrix_free : {false, true}) {
    ImpulseSolverOptions options = PathOptions(matrix_free);
    options.max_iterations = 1;
    options.interior_max_bodies = 0;
    ImpulseSolver limited(static_cast<int>(c), 3, options);
    expect_error(limited, example, 1.0, p, ImpulseSolverError::kNotConverged);
  }
  // and the solver still works afterwards
  const ImpulseSolverStats stats = solver.Solve(example.problem(), 1.0, p);
  EXPECT_EQ(stats.error, ImpulseSolverError::kNone);
  EXPECT_GT(p.back(), 0.0);
}

TEST(ImpulseSolver, ConstructorRejectsBadOptions) {
  EXPECT_THROW(ImpulseSolver(-1, 1), Error);
  EXPECT_THROW(ImpulseSolver(1, -1), Error);
  ImpulseSolverOptions options;
  options.tolerance = 0.0;
  EXPECT_THROW(ImpulseSolver(1, 1, options), Error);
  options = {};
  options.regularization = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(ImpulseSolver(1, 1, options), Error);
  options = {};
  options.interior_after_iterations = -1;
  EXPECT_THROW(ImpulseSolver(1, 1, options), Error);
  options = {};
  options.dense_max_rows = -2;
  try {
    ImpulseSolver solver(1, 1, options);
    FAIL() << "expected rigidtouch::Error";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("dense_max_rows = -2"), std::string::npos);
  }
}

TEST(ImpulseSolver, SolveDoesNotAllocate) {
  if (!test::kMallocCounting) GTEST_SKIP() << "malloc is owned by the sanitizer";
  const ImpulseExample pile = BoxGrid(5, 5, 4, 5);
  std::mt19937_64 rng(37);
  std::vector<ImpulseExample> groups;
  for (int k = 0; k < 50; ++k) groups.push_back(RandomGroup(rng));
  ImpulseExample pile_after = pile;
  double energy_J = 0.0;
  // the dense path, the matrix-free path, and the interior-point method at once
  for (const int path : {0, 1, 2}) {
    const bool matrix_free = path > 0;
    ImpulseSolverOptions options = PathOptions(matrix_free);
    if (path == 2) options.interior_after_iterations = 0;
    ImpulseSolver solver(401, 101, options);
    std::vector<double> p(401);
    {
      // the allocation counter must see allocations at all (or the test proves nothing)
      test::LimitMalloc probe_guard;
      void* (*volatile allocate)(std::size_t) = std::malloc;
      void* probe = allocate(64);
      std::free(probe);
      ASSERT_GT(probe_guard.allocations(), 0);
    }
    test::LimitMalloc guard;
    int failures = 0;
    for (const ImpulseExample& group : groups) {
      const auto c = group.rows.size();
      failures += solver.Solve(group.problem(), 1.0, std::span(p).first(c)).error !=
                  ImpulseSolverError::kNone;
      failures +=
          solver.Solve(group.problem(), 0.5, std::span(p).first(c), solver.plastic_impulse())
              .error != ImpulseSolverError::kNone;
    }
    if (path == 2) {
      const ImpulseSolverStats stats = solver.Solve(pile.problem(), 1.0, p);
      failures += stats.error != ImpulseSolverError::kNone || !stats.interior_point;
    }
    if (path == 1) {
      failures += solver.Solve(pile.problem(), 1.0, p).error != ImpulseSolverError::kNone;
      // the loop-side helpers too
      energy_J += KineticEnergy(pile_after.bodies);
      ApplyImpulses(pile_after.bodies, pile_after.rows, p);
      energy_J -= KineticEnergy(pile_after.bodies);
      energy_J += NormalVelocity(pile_after.problem(), 0);
    }
    EXPECT_EQ(guard.allocations(), 0) << "path " << path;
    EXPECT_EQ(failures, 0);
  }
  EXPECT_TRUE(std::isfinite(energy_J));
}

}  // namespace
}  // namespace rigidtouch::contact
