// The production impulse solver: the non-negative, perfectly plastic impulse of a contact group,
// scaled for Eq. 5 (single impulse) or Eq. 8 (one impulse of a train).
//
// Problem. With A = Jc M^-1 Jc^T (c x c, symmetric positive semi-definite) and b = Jc v0
// (impulse_math.h), the solver computes the plastic impulse
//
//     p* = argmin_{p >= 0} 1/2 p^T A p + b^T p                                    (plastic QP)
//
// whose optimality conditions are the frictionless LCP with e = 0: p >= 0, w = A p + b >= 0,
// p . w = 0, where w = Jc v+ is the relative normal velocity after the impulse. It returns
// p_out = scale p*, with scale = (1 + e) / (N - i + 1) chosen by the caller (Eq. 5: N = 1,
// scale = 1 + e; Eq. 8: e = 0, scale = 1 / (N - i + 1)). Impulses never pull: this is how the
// implementation settles the method's open point about adhesive components of Eq. 5 / Eq. 8
// (docs/decisions.md).
//
// Minimum norm. When A is singular (redundant rows: a box face on a plane gives 4 rows of rank
// 3) the minimisers form the set S = {p >= 0 : A p = A p*}; A p*, hence w and the velocity change
// M^-1 Jc^T p*, is the same for all of them. The solver returns the minimum-norm element p' of S.
// Because b = Jc v0 lies in range(Jc) = range(A), the unconstrained minimisers are
// -A^# b + null(A); when the reference answer -A^# b (impulse_reference.h) is >= 0 it lies in S
// and is its minimum-norm element, so the solver then returns exactly the reference impulse.
//
// Energy. At the plastic solution p* . w* = 0, i.e. p*^T A p* = -b^T p*. An impulse s p* changes
// the kinetic energy by dKE = s b^T p* + s^2/2 p*^T A p* = -(s - s^2/2) p*^T A p*, which is <= 0
// for s in [0, 2] because A is positive semi-definite: s = 2 (e = 1) conserves energy, any other
// s in [0, 2) dissipates. Solve therefore rejects scale outside [0, 2]. Numerically p* . w* is a
// residual at the solver's tolerance; if it comes out positive, Solve scales p* by the exact line
// search factor gamma = -b^T p* / p*^T A p* (slightly below 1), which makes p* . w* = 0 again, so
// that even s = 2 cannot add energy beyond rounding.
//
// Method, in four steps (all buffers are sized in the constructor; Solve never allocates).
// 1. Pack. Each row keeps its two Jacobian blocks [n; r x n] and the columns M^-1 Jc^T (24
//    doubles), so A x = Jc (M^-1 Jc^T x) costs O(c) through body space: rows couple only through
//    shared bodies. A row with A_jj <= kInertRowThreshold * max_k A_kk (e.g. between two
//    infinite-mass bodies) is inert: nothing can change its velocity, it gets p = 0 and, if it
//    approaches, is counted in ImpulseSolverStats::unresolved_rows.
// 2. Active set. Small groups (c <= options.dense_max_rows, 8 by default): the primal
//    active-set method of Lawson and Hanson (NNLS), written for the QP, on A + E with
//    E = options.regularization * diag(A) (1e-10 by default, relative per row so that light and
//    heavy bodies are regularised alike). E makes the QP strictly convex, so every free-set
//    Cholesky factor exists (redundant rows would otherwise give zero pivots), and the method
//    terminates: the objective strictly decreases whenever the free set changes, so no free set
//    repeats. The factor grows by one row per added index (O(f^2)) and is refactored when indices
//    leave (rare); a few steps of iterative refinement with the same factor then remove most of
//    E's bias. It costs O(c^3) at worst.
//    Larger groups: MPRGP (Dostal and Schoberl 2005, modified proportioning with reduced gradient
//    projections), a conjugate-gradient method for bound-constrained QPs that adds and drops many
//    bounds per iteration. It runs on the Jacobi-scaled problem (unknowns q_j = sqrt(A_jj) p_j,
//    unit diagonal; the bounds p >= 0 are unchanged) without regularisation, needs only the O(c)
//    products of step 1, and stops when the projected gradient (a velocity) is below
//    options.tolerance * v_ref, with v_ref the largest |b_j|. Its expansion step length starts at
//    1.9 and is halved whenever an expansion fails to decrease the objective, down to the safe
//    1.9 / (Gershgorin bound of the scaled A). MPRGP can stall on highly degenerate groups (many
//    more rows than the bodies' 6 b degrees of freedom); a group that fits the dense buffers
//    (c <= options.dense_polish_max_rows) then falls back to the dense method.
//    Why: on box piles MPRGP beat the dense method from about 8 rows on (25 rows: 2.7 us against
//    18 us; 73 rows: 24 us against 160 us), and a dense factorisation of a 400-row group costs
//    ~2e7 flops per solve. Projected Gauss-Seidel converges linearly with a rate that degrades
//    with stack height and mass ratio, too slowly for the accuracy the minimum-norm polish needs.
//    Large degenerate groups: a group too large for the dense buffers that MPRGP has not settled
//    after options.interior_after_iterations (100) iterations goes to a primal-dual
//    interior-point method on the velocity problem whose dual is the plastic QP
//    (impulse_interior.cc). Each of its iterations (12-25 on a kicked pile) factors
//    M + Jc^T (Z / S) Jc over the group's bodies (a block-sparse 6 x 6 Cholesky), so its cost
//    does not grow with the condition of A. Its answer z > 0 is cleaned of the traces it leaves
//    on open rows (those with z_j A_jj <= w_j).
//    Why: nearly redundant rows make A's condition 1e9 to 1e11 on its range in a kicked box pile,
//    where MPRGP took up to 3176 iterations (28 ms at 439 rows) or failed at its limit (65 ms),
//    and the interior-point method 12-21 iterations (0.4-2.0 ms at 140-439 rows). A caller that
//    knows the group's last solve went there (ImpulseSolveHint) sends it there at once.
// 3. Minimum-norm polish. Let F = {j : w_j <= options.polish_threshold * v_ref} after step 2. w is
//    the same for every plastic impulse, so F contains the support of p', and p' is the
//    minimum-norm solution of {A_FF p = -b_F, p >= 0} (rows outside F carry no impulse).
//    - Conjugate gradients (first choice after MPRGP): CG on A_FF x = -b_F from x = 0, whose
//      iterates stay in range(A_FF), so the limit is the minimum-norm solution. If it is >= 0 it
//      is p'. If not, p' has zeros inside F (a degenerate, redundant contact set).
//    - Dense (first choice after the dense method, and the fallback when CG's answer has
//      negative entries; only if F has at most options.dense_polish_max_rows rows): a diagonally
//      pivoted Cholesky of the Jacobi-scaled A_FF, truncated at kRankThreshold, gives A_FF = G G^T
//      with G f x r of full column rank, and the constraint becomes G^T p = beta
//      (G_1 beta = -b_F). A primal active-set method for min 1/2 |p|^2 subject to G^T p = beta,
//      p >= 0 starts from the step-2 answer (feasible); each subproblem on the rows K outside its
//      working set W has the solution x = G_K u with (G_K^T G_K) u = beta, and the bound
//      multipliers are -(G_W u). Its first subproblem is the unconstrained minimum-norm
//      solution, which is the answer whenever it is >= 0 (in particular when the reference
//      answer is >= 0). This handles the degenerate case exactly.
//    A candidate is accepted only if it is >= 0, no row approaches by more than
//    10 * options.tolerance * v_ref and rows with impulse have |w_j| below that. Otherwise the
//    step-2 answer is kept: a valid plastic impulse, not necessarily of minimum norm.
//    stats.min_norm tells whether the polish was accepted.
// 4. Check. p* . w* > 0 is corrected by the line-search factor above. If some row still
//    approaches faster than options.failure_tolerance * v_ref after p*, the answer is rejected
//    (error code, p_out = 0).
//
// Errors. Solve never throws. Exceeded capacities, bad indices, non-finite input, a bad scale, a
// missed iteration limit or a failed check return an error code in the stats and p_out = 0, the
// safe impulse (no energy is added; penalty feedback still acts).
#pragma once

#include <Eigen/Core>
#include <span>
#include <vector>

#include "contact/impulse.h"
#include "dynamics/block_cholesky.h"

namespace rigidtouch::contact {

/// A row is inert when its Delassus diagonal is at most this fraction of the group's largest one.
inline constexpr double kInertRowThreshold = 1e-12;
/// Rank threshold of the dense minimum-norm polish: on the Jacobi-scaled A_FF (unit diagonal)
/// and relative to the largest diagonal of G_K^T G_K; the value of the reference pseudo-inverse.
inline constexpr double kRankThreshold = 1e-10;

/// Why a solve returned the safe impulse p_out = 0.
enum class ImpulseSolverError {
  kNone = 0,          ///< Success.
  kTooManyRows,       ///< The problem has more rows than the solver's max_rows.
  kTooManyBodies,     ///< The problem has more bodies than the solver's max_bodies.
  kSizeMismatch,      ///< p_out does not have one entry per row.
  kBadBodyIndex,      ///< A row's body index is outside [-1, bodies) or both sides are equal.
  kNonFiniteInput,    ///< NaN or infinity in the problem, or a negative inv_mass or inertia.
  kBadScale,          ///< scale is not a finite number in [0, 2].
  kNotConverged,      ///< The active-set method reached its iteration limit.
  kResidualTooLarge,  ///< A row still approaches after the impulse (failed final check).
};

/// Short name of an error code, e.g. "too_many_rows", for logs and traces.
const char* ToString(ImpulseSolverError error);

/// What one solve did. Plain data, written by Solve without allocating.
struct ImpulseSolverStats {
  ImpulseSolverError error = ImpulseSolverError::kNone;  ///< kNone when p_out holds the answer.
  bool converged = false;         ///< The active-set method met its stopping test.
  bool matrix_free = false;       ///< The answer came from MPRGP, not from the dense active set.
  bool min_norm = false;          ///< The minimum-norm polish was accepted (see the file comment).
  int iterations = 0;             ///< Free-set changes (dense path) or MPRGP iterations.
  int polish_iterations = 0;      ///< Conjugate-gradient plus dense active-set polish iterations.
  bool interior_point = false;    ///< The answer came from the body-space interior-point method.
  int interior_iterations = 0;    ///< Its iterations (one factorisation each).
  int inert_rows = 0;             ///< Rows with no effective mass; they get p = 0.
  int unresolved_rows = 0;        ///< Inert rows that approach; no impulse can stop them.
  double max_approach_mps = 0.0;  ///< Largest approach speed -w_j left after p* (0 if none).
};

/// Tuning of ImpulseSolver. Tolerances are relative: to each row's Delassus diagonal
/// (regularization) or to v_ref, the largest |relative normal velocity| of the group (the rest).
struct ImpulseSolverOptions {
  /// Groups with at most this many rows use the dense active-set path, larger ones MPRGP
  /// (measured on box piles: MPRGP is faster from about 8 rows on, see the file comment).
  int dense_max_rows = 8;
  /// Free sets with at most this many rows can use the exact dense polish (see the file comment,
  /// step 3); groups this small also fall back to the dense active set if MPRGP stalls.
  int dense_polish_max_rows = 32;
  /// Relative regularisation of the dense path, A + regularization * diag(A).
  double regularization = 1e-10;
  /// Stopping tolerance of the active-set methods, as a velocity relative to v_ref.
  double tolerance = 1e-10;
  /// Rows with w_j <= polish_threshold * v_ref form the polish's free set F.
  double polish_threshold = 1e-8;
  /// Largest approach speed after p*, relative to v_ref, that Solve accepts.
  double failure_tolerance = 1e-6;
  /// Iteration limit of the active-set methods; 0 means 4 c + 50 (dense) or 20 c + 200 (MPRGP).
  int max_iterations = 0;
  /// Groups of up to this many bodies (and more rows than the dense buffers hold) go to the
  /// body-space interior-point method when MPRGP has not converged in interior_after_iterations;
  /// 0: never. Its factor takes about 5 min(this, max_bodies)^2 bytes.
  int interior_max_bodies = 1024;
  /// MPRGP iterations before such a group goes to the interior-point method (0: at once). On
  /// groups of a kicked 100-box pile (140-439 rows) one interior-point solve cost as much as
  /// 100-240 MPRGP iterations; MPRGP settled some within 34-72 and the others took 191-3176.
  int interior_after_iterations = 100;
};

/// What the caller knows of a group from its earlier solves.
struct ImpulseSolveHint {
  /// The group's last solve needed the interior-point method: if it is still too large for the
  /// dense path and the interior-point method can take it, it goes there without MPRGP's
  /// budget (options.interior_after_iterations). On a kicked 100-box pile 98% of the solves of
  /// more than 100 rows needed it, and the budget cost 0.5-0.6 ms of each.
  bool interior = false;
};

/// Production solver of the non-negative plastic impulse; see the file comment for the method.
/// One instance per thread; Solve reuses the buffers sized by the constructor.
class ImpulseSolver {
 public:
  /// Sizes every buffer for groups of up to `max_rows` rows and `max_bodies` bodies. Throws
  /// rigidtouch::Error if max_rows or max_bodies is negative, or an option is out of range
  /// (dense_max_rows, dense_polish_max_rows, max_iterations, interior_max_bodies or
  /// interior_after_iterations < 0, a tolerance outside (0, 1)).
  ImpulseSolver(int max_rows, int max_bodies, const ImpulseSolverOptions& options = {});

  /// Computes p_out = scale * p* (N s, one per row) for the group `problem`; scale must be in
  /// [0, 2], normally (1 + e) / (N - i + 1). `p_warm`, if it has one entry per row, is a guess of
  /// p* (e.g. plastic_impulse() of the previous impulse of the same rows) that starts the
  /// active-set method; otherwise it starts from p = 0. `hint` may skip MPRGP for a group known
  /// to be hard (ImpulseSolveHint). Never allocates or throws; on error p_out is 0 and
  /// stats.error says why.
  ImpulseSolverStats Solve(const ImpulseProblem& problem, double scale, std::span<double> p_out,
                           std::span<const double> p_warm = {}, const ImpulseSolveHint& hint = {});

  /// The unscaled plastic impulse p* of the last successful Solve (one entry per row).
  std::span<const double> plastic_impulse() const;

  /// Capacity in rows.
  int max_rows() const { return max_rows_; }
  /// Capacity in bodies.
  int max_bodies() const { return max_bodies_; }
  /// The options given to the constructor.
  const ImpulseSolverOptions& options() const { return options_; }

 private:
  using Vec6 = Eigen::Matrix<double, 6, 1>;

  // one row packed for the O(c) products: Jacobian blocks and M^-1 Jc^T columns of both sides
  struct PackedRow {
    int body_a = -1;
    int body_b = -1;
    Vec6 jac_a = Vec6::Zero();  // [n; r_a x n]
    Vec6 jac_b = Vec6::Zero();  // -[n; r_b x n]
    Vec6 minv_jt_a = Vec6::Zero();
    Vec6 minv_jt_b = Vec6::Zero();
  };

  ImpulseSolverError Pack(const ImpulseProblem& problem);
  // y = S A S x over the packed rows (S = diag(row_scale), or identity when row_scale is null)
  void MultiplyA(const double* x, double* y, const double* row_scale);
  double CouplingOf(int i, int j) const;  // A_ij from the packed rows
  bool SolveDense(std::span<const double> p_warm, ImpulseSolverStats& stats);
  void RefineDense();
  // step 2 for groups of more than dense_path_rows_ rows: MPRGP, then the dense method or the
  // interior-point method (at once when `to_interior` and the group is one it takes)
  bool SolveLarge(const ImpulseProblem& problem, std::span<const double> start, bool to_interior,
                  ImpulseSolverStats& stats);
  bool SolveMprgp(std::span<const double> p_warm, ImpulseSolverStats& stats, int max_iterations);
  bool SolveInterior(const ImpulseProblem& problem, ImpulseSolverStats& stats);
  bool InteriorStructure(const ImpulseProblem& problem);  // masses, edges, analysis
  bool InteriorFactor();                                  // M + J^T (Z / S) J = L L^T
  bool InteriorDirection();                               // the Newton step for interior_.rc
  void InteriorResidual(double& approach_mps, double& split_mps);  // of p = z, as speeds
  void InteriorCleanUp(double max_trace_mps);                      // no impulse on open rows
  double RowVelocity(int j, const std::vector<Vec6>& v) const {    // J_j v
    const PackedRow& row = rows_[j];
    double w = 0.0;
    if (row.body_a >= 0) w += row.jac_a.dot(v[row.body_a]);
    if (row.body_b >= 0) w += row.jac_b.dot(v[row.body_b]);
    return w;
  }
  void MprgpGradient();  // g = S A S x + S b
  void MprgpExpand(double feasible_step, double min_step_bar, double& step_bar,
                   double& inv_step_bar);
  bool MprgpProportion();  // false if a released direction has no curvature
  bool Polish(ImpulseSolverStats& stats);
  bool PolishDense(int f, ImpulseSolverStats& stats);
  bool PolishCg(ImpulseSolverStats& stats);
  bool AcceptPolish();
  void DenseRefactor();
  bool DenseAppend(int row);
  void DenseSolveFree(const double* rhs, double* z) const;

  int max_rows_ = 0;
  int max_bodies_ = 0;
  int dense_path_rows_ = 0;    // groups up to this size use the dense active set
  int dense_polish_rows_ = 0;  // free sets up to this size use the exact dense polish
  int max_dense_ = 0;          // size of the dense buffers
  ImpulseSolverOptions options_;

  // problem-dependent sizes and scales, set by Pack
  int num_rows_ = 0;
  int num_bodies_ = 0;
  double v_ref_mps_ = 0.0;  // largest |b_j| over non-inert rows

  // packed problem (max_rows, max_bodies)
  std::vector<PackedRow> rows_;
  std::vector<Vec6> body_dv_;       // body-space accumulator of M^-1 Jc^T x
  Eigen::VectorXi body_row_count_;  // rows touching each body
  Eigen::VectorXd diag_;            // A_jj  [1/kg]
  Eigen::VectorXd b_mps_;           // Jc v0
  Eigen::VectorXi inert_;           // 1 for inert rows

  // iterates (max_rows)
  Eigen::VectorXd p_;                     // plastic impulse p* being computed  [N s]
  Eigen::VectorXd p_last_;                // p* of the last successful solve
  Eigen::VectorXd w_mps_;                 // A p + b
  Eigen::VectorXd x_, g_, d_, ad_, tmp_;  // method-specific work vectors
  Eigen::VectorXd row_scale_;             // 1 / sqrt(A_jj) of MPRGP's Jacobi scaling
  Eigen::VectorXd sqrt_diag_;             // sqrt(A_jj)
  Eigen::VectorXi in_set_;                // 1 for rows of the polish's free set F
  int last_num_rows_ = 0;

  // body-space interior point (impulse_interior.cc): per body (max_bodies, factor up to
  // interior_max_bodies) and per row (max_rows)
  static constexpr int kMaxInteriorIterations = 60;
  struct InteriorScratch {
    dynamics::BlockCholesky factor;
    std::vector<double> mass_kg;
    std::vector<Mat3> inertia_W;
    std::vector<Vec6> v0, v, rd, dv, body_step;
    std::vector<std::uint64_t> edges;
    Eigen::VectorXd s, z, ds, dz, rp, rc, z_best;
  };
  InteriorScratch interior_;

  // dense path (max_dense)
  Eigen::MatrixXd a_dense_;   // A (unregularised)
  Eigen::MatrixXd l_dense_;   // L^T of the free block (row k of L in column k); the polish's G
  Eigen::MatrixXd h_dense_;   // G_K^T G_K of the polish
  Eigen::VectorXi free_;      // free rows in factor order
  Eigen::VectorXi blocked_;   // rows the dense path must not add again
  Eigen::VectorXi set_rows_;  // rows of the polish's free set F, in pivot order
  Eigen::VectorXi h_order_;   // pivot order of G_K^T G_K
  Eigen::VectorXi working_;   // 1 for bounds p_i = 0 in the polish's working set
  Eigen::VectorXd z_, rhs_, u_, beta_, p_set_, x_set_;
  int num_free_ = 0;
};

}  // namespace rigidtouch::contact
