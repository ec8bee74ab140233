#include "contact/impulse_solver.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace rigidtouch::contact {
namespace {

// MPRGP's proportioning constant: a proportioning step is taken when the chopped gradient (bounds
// that should be released) outweighs the free gradient by more than this factor
constexpr double kProportioning = 1.0;

bool AllFinite(const Vec3& v) {
  return v.allFinite();
}

// Diagonally pivoted Cholesky of the symmetric positive semi-definite top-left n x n block of
// `work` (full storage; rows and columns are swapped together, and `order` with them). Stops when
// the largest remaining Schur-complement diagonal is <= threshold; returns the rank r. On return
// the first r columns hold G, lower trapezoidal, with P W P^T ~= G G^T.
int PivotedCholesky(Eigen::MatrixXd& work, int n, Eigen::VectorXi& order, double threshold) {
  for (int k = 0; k < n; ++k) {
    int q = k;
    for (int i = k + 1; i < n; ++i) {
      if (work(i, i) > work(q, q)) q = i;
    }
    if (!(work(q, q) > threshold)) return k;
    if (q != k) {
      work.row(k).head(n).swap(work.row(q).head(n));
      work.col(k).head(n).swap(work.col(q).head(n));
      std::swap(order[k], order[q]);
    }
    const double l_kk = std::sqrt(work(k, k));
    work(k, k) = l_kk;
    for (int i = k + 1; i < n; ++i) work(i, k) /= l_kk;
    for (int j = k + 1; j < n; ++j) {
      for (int i = j; i < n; ++i) {
        work(i, j) -= work(i, k) * work(j, k);
        work(j, i) = work(i, j);
      }
    }
  }
  return n;
}

}  // namespace

const char* ToString(ImpulseSolverError error) {
  switch (error) {
    case ImpulseSolverError::kNone:
      return "none";
    case ImpulseSolverError::kTooManyRows:
      return "too_many_rows";
    case ImpulseSolverError::kTooManyBodies:
      return "too_many_bodies";
    case ImpulseSolverError::kSizeMismatch:
      return "size_mismatch";
    case ImpulseSolverError::kBadBodyIndex:
      return "bad_body_index";
    case ImpulseSolverError::kNonFiniteInput:
      return "non_finite_input";
    case ImpulseSolverError::kBadScale:
      return "bad_scale";
    case ImpulseSolverError::kNotConverged:
      return "not_converged";
    case ImpulseSolverError::kResidualTooLarge:
      return "residual_too_large";
  }
  return "unknown";
}

ImpulseSolver::ImpulseSolver(int max_rows, int max_bodies, const ImpulseSolverOptions& options)
    : max_rows_(max_rows), max_bodies_(max_bodies), options_(options) {
  if (max_rows < 0 || max_bodies < 0) {
    throw Error("ImpulseSolver: max_rows = " + std::to_string(max_rows) +
                " and max_bodies = " + std::to_string(max_bodies) + " must be >= 0");
  }
  if (options.dense_max_rows < 0 || options.dense_polish_max_rows < 0) {
    throw Error("ImpulseSolverOptions::dense_max_rows = " + std::to_string(options.dense_max_rows) +
                " and dense_polish_max_rows = " + std::to_string(options.dense_polish_max_rows) +
                " must be >= 0");
  }
  if (options.max_iterations < 0) {
    throw Error("ImpulseSolverOptions::max_iterations = " + std::to_string(options.max_iterations) +
                " must be >= 0 (0 = automatic)");
  }
  const struct {
    const char* name;
    double value;
  } tolerances[] = {{"regularization", options.regularization},
                    {"tolerance", options.tolerance},
                    {"polish_threshold", options.polish_threshold},
                    {"failure_tolerance", options.failure_tolerance}};
  for (const auto& t : tolerances) {
    if (!(std::isfinite(t.value) && t.value > 0.0 && t.value < 1.0)) {
      throw Error(std::string("ImpulseSolverOptions::") + t.name + " = " + std::to_string(t.value) +
                  " must be in (0, 1)");
    }
  }

  dense_path_rows_ = std::min(max_rows, options.dense_max_rows);
  dense_polish_rows_ = std::min(max_rows, options.dense_polish_max_rows);
  max_dense_ = std::max(dense_path_rows_, dense_polish_rows_);
  rows_.resize(static_cast<std::size_t>(max_rows));
  body_dv_.resize(static_cast<std::size_t>(max_bodies), Vec6::Zero());
  body_row_count_.setZero(max_bodies);
  diag_.setZero(max_rows);
  b_mps_.setZero(max_rows);
  inert_.setZero(max_rows);
  p_.setZero(max_rows);
  p_last_.setZero(max_rows);
  w_mps_.setZero(max_rows);
  x_.setZero(max_rows);
  g_.setZero(max_rows);
  d_.setZero(max_rows);
  ad_.setZero(max_rows);
  tmp_.setZero(max_rows);
  row_scale_.setZero(max_rows);
  sqrt_diag_.setZero(max_rows);
  in_set_.setZero(max_rows);
  a_dense_.setZero(max_dense_, max_dense_);
  l_dense_.setZero(max_dense_, max_dense_);
  h_dense_.setZero(max_dense_, max_dense_);
  free_.setZero(max_dense_);
  blocked_.setZero(max_dense_);
  set_rows_.setZero(max_dense_);
  h_order_.setZero(max_dense_);
  working_.setZero(max_dense_);
  z_.setZero(max_dense_);
  rhs_.setZero(max_dense_);
  u_.setZero(max_dense_);
  beta_.setZero(max_dense_);
  p_set_.setZero(max_dense_);
  x_set_.setZero(max_dense_);
}

std::span<const double> ImpulseSolver::plastic_impulse() const {
  return {p_last_.data(), static_cast<std::size_t>(last_num_rows_)};
}

ImpulseSolverStats ImpulseSolver::Solve(const ImpulseProblem& problem, double scale,
                                        std::span<double> p_out, std::span<const double> p_warm) {
  ImpulseSolverStats stats;
  std::fill(p_out.begin(), p_out.end(), 0.0);  // the safe answer until a solve succeeds
  if (p_out.size() != problem.rows.size()) {
    stats.error = ImpulseSolverError::kSizeMismatch;
    return stats;
  }
  if (problem.rows.size() > static_cast<std::size_t>(max_rows_)) {
    stats.error = ImpulseSolverError::kTooManyRows;
    return stats;
  }
  if (problem.bodies.size() > static_cast<std::size_t>(max_bodies_)) {
    stats.error = ImpulseSolverError::kTooManyBodies;
    return stats;
  }
  if (!(scale >= 0.0 && scale <= 2.0)) {
    stats.error = ImpulseSolverError::kBadScale;
    return stats;
  }
  stats.error = Pack(problem);
  if (stats.error != ImpulseSolverError::kNone) return stats;

  const int c = num_rows_;
  p_.head(c).setZero();
  bool any_approach = false;
  for (int j = 0; j < c; ++j) {
    if (inert_[j]) {
      ++stats.inert_rows;
      if (b_mps_[j] < 0.0) ++stats.unresolved_rows;
    } else if (b_mps_[j] < 0.0) {
      any_approach = true;
    }
  }
  const bool warm = p_warm.size() == static_cast<std::size_t>(c);

  if (!any_approach) {
    // w = b >= 0 at p = 0: the plastic impulse is zero (and zero is the minimum-norm minimiser)
    stats.converged = true;
    stats.min_norm = true;
  } else {
    stats.matrix_free = c > dense_path_rows_;
    const std::span<const double> start = p_warm.first(warm ? c : 0);
    stats.converged = stats.matrix_free ? SolveMprgp(start, stats) : SolveDense(start, stats);
    if (!stats.converged && stats.matrix_free && c <= max_dense_) {
      // MPRGP can stall on highly degenerate groups; the finite dense method settles them
      p_.head(c).setZero();
      stats.matrix_free = false;
      stats.iterations = 0;
      stats.converged = SolveDense(start, stats);
    }
    if (!stats.converged) {
      stats.error = ImpulseSolverError::kNotConverged;
      return stats;
    }
    stats.min_norm = Polish(stats);
  }

  // final check on the unscaled plastic impulse: p* >= 0 and no row approaches afterwards
  for (int j = 0; j < c; ++j) p_[j] = std::max(p_[j], 0.0);
  MultiplyA(p_.data(), w_mps_.data(), nullptr);
  double p_w_J = 0.0;   // p . w, zero at the exact plastic solution  [J]
  double p_ap_J = 0.0;  // p^T A p  [J]
  for (int j = 0; j < c; ++j) {
    p_ap_J += p_[j] * w_mps_[j];
    w_mps_[j] += b_mps_[j];
    p_w_J += p_[j] * w_mps_[j];
  }
  if (p_w_J > 0.0 && p_ap_J > 0.0) {
    // an inexact p with p . w > 0 would let the impulse 2 p (e = 1) add energy 2 p . w; the
    // exact line search along p, gamma = -b.p / p^T A p < 1, restores p . w = 0
    const double gamma = std::max((p_ap_J - p_w_J) / p_ap_J, 0.0);
    for (int j = 0; j < c; ++j) {
      p_[j] *= gamma;
      w_mps_[j] = gamma * (w_mps_[j] - b_mps_[j]) + b_mps_[j];
    }
  }
  double max_approach_mps = 0.0;
  for (int j = 0; j < c; ++j) {
    if (!inert_[j]) max_approach_mps = std::max(max_approach_mps, -w_mps_[j]);
  }
  stats.max_approach_mps = max_approach_mps;
  if (!std::isfinite(max_approach_mps) ||
      max_approach_mps > options_.failure_tolerance * v_ref_mps_) {
    stats.error = ImpulseSolverError::kResidualTooLarge;
    return stats;
  }
  for (int j = 0; j < c; ++j) p_out[j] = scale * p_[j];
  p_last_.head(c) = p_.head(c);
  last_num_rows_ = c;
  return stats;
}

ImpulseSolverError ImpulseSolver::Pack(const ImpulseProblem& problem) {
  num_rows_ = static_cast<int>(problem.rows.size());
  num_bodies_ = static_cast<int>(problem.bodies.size());
  for (int k = 0; k < num_bodies_; ++k) {
    const SolverBody& body = problem.bodies[k];
    if (!std::isfinite(body.inv_mass) || body.inv_mass < 0.0 || !body.inv_inertia_W.allFinite() ||
        (body.inv_inertia_W.diagonal().array() < 0.0).any() || !AllFinite(body.v_W) ||
        !AllFinite(body.w_W)) {
      return ImpulseSolverError::kNonFiniteInput;
    }
    body_row_count_[k] = 0;
  }

  double max_diag = 0.0;
  for (int j = 0; j < num_rows_; ++j) {
    const SolverRow& row = problem.rows[j];
    if (row.body_a < -1 || row.body_a >= num_bodies_ || row.body_b < -1 ||
        row.body_b >= num_bodies_ || row.body_a == row.body_b) {
      return ImpulseSolverError::kBadBodyIndex;
    }
    if (!AllFinite(row.n_W) || !AllFinite(row.r_a_W) || !AllFinite(row.r_b_W)) {
      return ImpulseSolverError::kNonFiniteInput;
    }
    PackedRow& packed = rows_[j];
    packed.body_a = row.body_a;
    packed.body_b = row.body_b;
    double diag = 0.0;
    double b_mps = 0.0;
    if (row.body_a >= 0) {
      const SolverBody& a = problem.bodies[row.body_a];
      const Vec3 lever = row.r_a_W.cross(row.n_W);
      packed.jac_a.head<3>() = row.n_W;
      packed.jac_a.tail<3>() = lever;
      packed.minv_jt_a.head<3>() = a.inv_mass * row.n_W;
      packed.minv_jt_a.tail<3>() = a.inv_inertia_W * lever;
      diag += packed.jac_a.dot(packed.minv_jt_a);
      b_mps += row.n_W.dot(a.v_W) + lever.dot(a.w_W);
      ++body_row_count_[row.body_a];
    }
    if (row.body_b >= 0) {
      const SolverBody& b = problem.bodies[row.body_b];
      const Vec3 lever = row.r_b_W.cross(row.n_W);
      packed.jac_b.head<3>() = -row.n_W;
      packed.jac_b.tail<3>() = -lever;
      packed.minv_jt_b.head<3>() = -b.inv_mass * row.n_W;
      packed.minv_jt_b.tail<3>() = -(b.inv_inertia_W * lever);
      diag += packed.jac_b.dot(packed.minv_jt_b);
      b_mps += packed.jac_b.head<3>().dot(b.v_W) + packed.jac_b.tail<3>().dot(b.w_W);
      ++body_row_count_[row.body_b];
    }
    if (!std::isfinite(diag) || !std::isfinite(b_mps)) return ImpulseSolverError::kNonFiniteInput;
    diag_[j] = diag;
    b_mps_[j] = b_mps;
    max_diag = std::max(max_diag, diag);
  }

  v_ref_mps_ = 0.0;
  for (int j = 0; j < num_rows_; ++j) {
    // a non-positive diagonal can only come from an indefinite inverse inertia: treat as inert
    inert_[j] = !(diag_[j] > kInertRowThreshold * max_diag) ? 1 : 0;
    if (!inert_[j]) v_ref_mps_ = std::max(v_ref_mps_, std::abs(b_mps_[j]));
  }
  return ImpulseSolverError::kNone;
}

void ImpulseSolver::MultiplyA(const double* x, double* y, const double* row_scale) {
  // M^-1 Jc^T x gathered per body, then Jc of it: O(rows + bodies), no c x c matrix
  std::vector<Vec6>& dv = body_dv_;
  for (int k = 0; k < num_bodies_; ++k) dv[k].setZero();
  for (int j = 0; j < num_rows_; ++j) {
    const double xj = row_scale != nullptr ? row_scale[j] * x[j] : x[j];
    if (xj == 0.0) continue;
    const PackedRow& row = rows_[j];
    if (row.body_a >= 0) dv[row.body_a] += xj * row.minv_jt_a;
    if (row.body_b >= 0) dv[row.body_b] += xj * row.minv_jt_b;
  }
  for (int j = 0; j < num_rows_; ++j) {
    const PackedRow& row = rows_[j];
    double yj = 0.0;
    if (row.body_a >= 0) yj += row.jac_a.dot(dv[row.body_a]);
    if (row.body_b >= 0) yj += row.jac_b.dot(dv[row.body_b]);
    y[j] = row_scale != nullptr ? row_scale[j] * yj : yj;
  }
}

double ImpulseSolver::CouplingOf(int i, int j) const {
  const PackedRow& ri = rows_[i];
  const PackedRow& rj = rows_[j];
  double a_ij = 0.0;
  if (ri.body_a >= 0) {
    if (ri.body_a == rj.body_a) a_ij += ri.jac_a.dot(rj.minv_jt_a);
    if (ri.body_a == rj.body_b) a_ij += ri.jac_a.dot(rj.minv_jt_b);
  }
  if (ri.body_b >= 0) {
    if (ri.body_b == rj.body_a) a_ij += ri.jac_b.dot(rj.minv_jt_a);
    if (ri.body_b == rj.body_b) a_ij += ri.jac_b.dot(rj.minv_jt_b);
  }
  return a_ij;
}

// ---------------------------------------------------------------------------------------------
// dense path: Lawson-Hanson active set on A + regularization * diag(A)

bool ImpulseSolver::DenseAppend(int row) {
  // new factor row l solves L l = A_F,row; its pivot is the Schur complement, >= eps_row in
  // exact arithmetic because A + E >= E (E = regularization * diag(A)). The factor is stored
  // transposed (column k of l_dense_ is row k of L) so that the substitutions run contiguously.
  const int n = num_free_;
  double* lt = l_dense_.data();
  const Eigen::Index ld = l_dense_.rows();
  double* l_new = lt + n * ld;  // row n of L
  for (int k = 0; k < n; ++k) {
    const double* l_k = lt + k * ld;
    double sum = a_dense_(free_[k], row);
    for (int m = 0; m < k; ++m) sum -= l_k[m] * l_new[m];
    l_new[k] = sum / l_k[k];
  }
  const double eps = options_.regularization * diag_[row];
  double pivot = a_dense_(row, row) + eps;
  for (int m = 0; m < n; ++m) pivot -= l_new[m] * l_new[m];
  if (!(pivot > 0.5 * eps)) return false;
  l_new[n] = std::sqrt(pivot);
  free_[n] = row;
  num_free_ = n + 1;
  return true;
}

void ImpulseSolver::DenseRefactor() {
  // rebuild the factor for the current free list; a row that no longer fits is dropped (p = 0
  // keeps the iterate feasible)
  const int n = num_free_;
  num_free_ = 0;
  for (int k = 0; k < n; ++k) {
    const int row = free_[k];
    if (!DenseAppend(row)) p_[row] = 0.0;
  }
}

void ImpulseSolver::DenseSolveFree(const double* rhs, double* z) const {
  const int n = num_free_;
  const double* lt = l_dense_.data();
  const Eigen::Index ld = l_dense_.rows();
  for (int k = 0; k < n; ++k) {  // L y = rhs, row k of L is contiguous
    const double* l_k = lt + k * ld;
    double sum = rhs[k];
    for (int m = 0; m < k; ++m) sum -= l_k[m] * z[m];
    z[k] = sum / l_k[k];
  }
  for (int k = n - 1; k >= 0; --k) {  // L^T z = y, column-oriented: subtract as each z is known
    z[k] /= lt[k * ld + k];
    const double* l_k = lt + k * ld;
    for (int m = 0; m < k; ++m) z[m] -= l_k[m] * z[k];
  }
}

void ImpulseSolver::RefineDense() {
  // iterative refinement on the final free set with the regularised factor: each step shrinks
  // the regularisation's bias w_F = -E p_F by E / (A + E) per eigendirection, which matters for
  // nearly singular groups
  const double tol_mps = options_.tolerance * v_ref_mps_;
  double previous_max_mps = std::numeric_limits<double>::infinity();
  for (int step = 0; step < 30; ++step) {
    double residual_max_mps = 0.0;
    for (int k = 0; k < num_free_; ++k) {
      double residual_mps = -b_mps_[free_[k]];
      for (int m = 0; m < num_free_; ++m)
        residual_mps -= a_dense_(free_[k], free_[m]) * p_[free_[m]];
      rhs_[k] = residual_mps;
      residual_max_mps = std::max(residual_max_mps, std::abs(residual_mps));
    }
    // stop when converged, or stalled (rounding dominates)
    if (residual_max_mps <= tol_mps || residual_max_mps > 0.9 * previous_max_mps) return;
    previous_max_mps = residual_max_mps;
    DenseSolveFree(rhs_.data(), z_.data());
    for (int k = 0; k < num_free_; ++k) {
      if (!(p_[free_[k]] + z_[k] > 0.0)) return;  // would leave the feasible set: stop here
    }
    for (int k = 0; k < num_free_; ++k) p_[free_[k]] += z_[k];
  }
}

bool ImpulseSolver::SolveDense(std::span<const double> p_warm, ImpulseSolverStats& stats) {
  const int c = num_rows_;
  for (int i = 0; i < c; ++i) {
    for (int j = 0; j <= i; ++j) {
      const double a_ij = CouplingOf(i, j);
      a_dense_(i, j) = a_ij;
      a_dense_(j, i) = a_ij;
    }
    blocked_[i] = 0;
  }
  const double tol_mps = options_.tolerance * v_ref_mps_;
  const int max_iterations = options_.max_iterations > 0 ? options_.max_iterations : 4 * c + 50;

  num_free_ = 0;
  for (std::size_t j = 0; j < p_warm.size(); ++j) {
    if (!inert_[j] && std::isfinite(p_warm[j]) && p_warm[j] > 0.0) {
      p_[j] = p_warm[j];
      free_[num_free_++] = static_cast<int>(j);
    }
  }
  DenseRefactor();
  int added = -1;  // the row added by the last outer step, -1 after a warm start
  bool solve_free = num_free_ > 0;

  for (;;) {
    // inner loop: move towards the unconstrained minimiser on the free set, dropping rows
    // whose impulse would turn negative
    while (solve_free && num_free_ > 0) {
      for (int k = 0; k < num_free_; ++k) rhs_[k] = -b_mps_[free_[k]];
      DenseSolveFree(rhs_.data(), z_.data());
      int k_min = -1;
      double step = 1.0;
      for (int k = 0; k < num_free_; ++k) {
        if (z_[k] > 0.0) continue;
        const double p_k = p_[free_[k]];
        const double denominator = p_k - z_[k];
        const double step_k = denominator > 0.0 ? p_k / denominator : 0.0;
        if (k_min < 0 || step_k < step) {
          step = step_k;
          k_min = k;
        }
      }
      if (k_min < 0) {
        for (int k = 0; k < num_free_; ++k) p_[free_[k]] = z_[k];
        break;
      }
      if (added >= 0 && free_[num_free_ - 1] == added && z_[num_free_ - 1] <= 0.0 &&
          p_[added] == 0.0) {
        // exact arithmetic forbids this (w_added < 0 implies z_added > 0); rounding at the
        // tolerance can cause it, and re-adding the row would cycle
        --num_free_;
        blocked_[added] = 1;
        added = -1;
        continue;
      }
      for (int k = 0; k < num_free_; ++k) {
        double& p_k = p_[free_[k]];
        p_k += step * (z_[k] - p_k);
      }
      p_[free_[k_min]] = 0.0;
      int kept = 0;
      for (int k = 0; k < num_free_; ++k) {
        if (p_[free_[k]] > 0.0) free_[kept++] = free_[k];
      }
      num_free_ = kept;
      DenseRefactor();
      added = -1;
      if (++stats.iterations >= max_iterations) return false;
    }

    // outer step: add the most approaching row that carries no impulse
    int best = -1;
    double best_w_mps = -tol_mps;
    for (int j = 0; j < c; ++j) {
      if (inert_[j] || blocked_[j] || p_[j] > 0.0) continue;
      double w_mps = b_mps_[j];
      for (int k = 0; k < num_free_; ++k) w_mps += a_dense_(j, free_[k]) * p_[free_[k]];
      if (w_mps < best_w_mps) {
        best_w_mps = w_mps;
        best = j;
      }
    }
    if (best < 0) {
      RefineDense();
      return true;
    }
    if (++stats.iterations >= max_iterations) return false;
    if (!DenseAppend(best)) {
      blocked_[best] = 1;
      continue;
    }
    added = best;
    solve_free = true;
  }
}

// ---------------------------------------------------------------------------------------------
// minimum-norm polish (step 3 of the header comment)

bool ImpulseSolver::Polish(ImpulseSolverStats& stats) {
  const int c = num_rows_;
  MultiplyA(p_.data(), w_mps_.data(), nullptr);
  const double threshold_mps = options_.polish_threshold * v_ref_mps_;
  int f = 0;
  for (int j = 0; j < c; ++j) {
    w_mps_[j] += b_mps_[j];
    in_set_[j] = !inert_[j] && w_mps_[j] <= threshold_mps ? 1 : 0;
    if (in_set_[j] && f < dense_polish_rows_) set_rows_[f] = j;
    f += in_set_[j];
  }
  if (f == 0) return false;
  const bool dense_fits = f <= dense_polish_rows_;
  // after the dense active set the dense polish costs about as much again, so it goes first;
  // after MPRGP the O(c)-per-iteration conjugate gradients usually suffice and are cheaper
  if (!stats.matrix_free) return dense_fits ? PolishDense(f, stats) : PolishCg(stats);
  return PolishCg(stats) || (dense_fits && PolishDense(f, stats));
}

bool ImpulseSolver::PolishDense(int f, ImpulseSolverStats& stats) {
  // 1. a rank-revealing factor A_FF = G G^T (G is f x r): pivoted Cholesky of the Jacobi-scaled
  // block (unit diagonal, so the rank threshold is scale-free), rows scaled back afterwards
  auto& g = l_dense_;
  for (int i = 0; i < f; ++i) {
    for (int k = 0; k <= i; ++k) {
      const int row_i = set_rows_[i];
      const int row_k = set_rows_[k];
      g(i, k) = CouplingOf(row_i, row_k) / std::sqrt(diag_[row_i] * diag_[row_k]);
      g(k, i) = g(i, k);
    }
  }
  const int r = PivotedCholesky(g, f, set_rows_, kRankThreshold);
  if (r == 0) return false;
  for (int i = 0; i < f; ++i) g.row(i).head(r) *= std::sqrt(diag_[set_rows_[i]]);
  // G_1 beta = y_1 with y = -b_F (the first r rows of G are lower triangular)
  for (int k = 0; k < r; ++k) {
    double sum = -b_mps_[set_rows_[k]];
    for (int m = 0; m < k; ++m) sum -= g(k, m) * beta_[m];
    beta_[k] = sum / g(k, k);
  }

  // 2. primal active-set method for min 1/2 |p|^2 s.t. G^T p = beta, p >= 0, from the feasible
  // step-2 answer with an empty working set W; each equality-constrained subproblem on the rows
  // outside W has the solution x = G_K u, (G_K^T G_K) u = beta (u: any solution, x is unique)
  for (int i = 0; i < f; ++i) {
    p_set_[i] = std::max(p_[set_rows_[i]], 0.0);
    working_[i] = 0;
  }
  const int max_iterations = 4 * f + 20;
  for (int it = 0;; ++it) {
    if (it >= max_iterations) return false;
    ++stats.polish_iterations;
    // H = G_K^T G_K, basic solution u of H u = beta through a pivoted Cholesky
    auto& h = h_dense_;
    for (int a = 0; a < r; ++a) {
      for (int b = 0; b <= a; ++b) {
        double sum = 0.0;
        for (int i = a; i < f; ++i)
          sum += working_[i] ? 0.0 : g(i, a) * g(i, b);  // G_ia = 0 for i < a
        h(a, b) = sum;
        h(b, a) = sum;
      }
      h_order_[a] = a;
    }
    double h_max = 0.0;
    for (int a = 0; a < r; ++a) h_max = std::max(h_max, h(a, a));
    if (!(h_max > 0.0)) return false;
    const int s = PivotedCholesky(h, r, h_order_, kRankThreshold * h_max);
    for (int a = 0; a < s; ++a) {
      double sum = beta_[h_order_[a]];
      for (int m = 0; m < a; ++m) sum -= h(a, m) * u_[m];
      u_[a] = sum / h(a, a);
    }
    for (int a = s - 1; a >= 0; --a) {
      double sum = u_[a];
      for (int m = a + 1; m < s; ++m) sum -= h(m, a) * u_[m];
      u_[a] = sum / h(a, a);
    }
    for (int a = 0; a < r; ++a) z_[a] = 0.0;
    for (int a = 0; a < s; ++a) z_[h_order_[a]] = u_[a];
    // x_i = (G z)_i on K; also the bound multipliers mu_i = -(G z)_i on W
    for (int i = 0; i < f; ++i) {
      double gz = 0.0;
      for (int a = 0; a < std::min(i + 1, r); ++a) gz += g(i, a) * z_[a];
      x_set_[i] = working_[i] ? -gz : gz;
    }
    // step from p towards x until a bound blocks
    int blocking = -1;
    double step = 1.0;
    for (int i = 0; i < f; ++i) {
      if (working_[i] || x_set_[i] >= 0.0) continue;
      const double step_i = p_set_[i] / (p_set_[i] - x_set_[i]);  // x_i < 0 <= p_i
      if (step_i < step) {
        step = step_i;
        blocking = i;
      }
    }
    if (blocking >= 0) {
      for (int i = 0; i < f; ++i) {
        if (!working_[i]) p_set_[i] = std::max(p_set_[i] + step * (x_set_[i] - p_set_[i]), 0.0);
      }
      p_set_[blocking] = 0.0;
      working_[blocking] = 1;
      continue;
    }
    double p_max = 0.0;
    for (int i = 0; i < f; ++i) {
      if (!working_[i]) p_set_[i] = x_set_[i];
      p_max = std::max(p_max, p_set_[i]);
    }
    // optimal when every bound in W pushes (mu >= 0); else release the most negative one
    int release = -1;
    double mu_min = -1e-10 * p_max;
    for (int i = 0; i < f; ++i) {
      if (working_[i] && x_set_[i] < mu_min) {
        mu_min = x_set_[i];
        release = i;
      }
    }
    if (release < 0) break;
    working_[release] = 0;
  }
  tmp_.head(num_rows_).setZero();
  for (int i = 0; i < f; ++i) tmp_[set_rows_[i]] = working_[i] ? 0.0 : p_set_[i];
  return AcceptPolish();
}

// ---------------------------------------------------------------------------------------------
// matrix-free path: MPRGP on the Jacobi-scaled problem

bool ImpulseSolver::SolveMprgp(std::span<const double> p_warm, ImpulseSolverStats& stats) {
  const int c = num_rows_;
  const double* s = row_scale_.data();
  // |A_hat_ij| <= 1 (unit diagonal, positive semi-definite), so Gershgorin bounds ||A_hat|| by
  // the number of rows touching a plus those touching b
  int max_neighbours = 1;
  for (int j = 0; j < c; ++j) {
    const PackedRow& row = rows_[j];
    sqrt_diag_[j] = inert_[j] ? 0.0 : std::sqrt(diag_[j]);
    row_scale_[j] = inert_[j] ? 0.0 : 1.0 / sqrt_diag_[j];
    int neighbours = 0;
    if (row.body_a >= 0) neighbours += body_row_count_[row.body_a];
    if (row.body_b >= 0) neighbours += body_row_count_[row.body_b];
    max_neighbours = std::max(max_neighbours, neighbours);
  }
  // the expansion step length (at most 2 / ||A_hat|| in the theory): start from 1.9
  // (||A_hat|| >= 1) and halve it whenever an expansion step fails to decrease the objective,
  // down to the always-safe 1.9 / max_neighbours
  const double min_step_bar = 1.9 / max_neighbours;
  double step_bar = 1.9;
  double inv_step_bar = 1.0 / step_bar;
  const double* sqrt_diag = sqrt_diag_.data();  // 1 / s: scaled gradient to velocity
  const double tol_mps = options_.tolerance * v_ref_mps_;
  const int max_iterations = options_.max_iterations > 0 ? options_.max_iterations : 20 * c + 200;

  // x = S^-1 p, g = A_hat x + S b
  for (int j = 0; j < c; ++j) {
    const bool use_warm = !p_warm.empty() && s[j] > 0.0 && std::isfinite(p_warm[j]);
    x_[j] = use_warm ? std::max(p_warm[j], 0.0) / s[j] : 0.0;
  }
  auto full_gradient = [&] {
    MultiplyA(x_.data(), g_.data(), s);
    for (int j = 0; j < c; ++j) g_[j] += s[j] * b_mps_[j];
  };
  auto free_gradient = [&](int j) { return x_[j] > 0.0 ? g_[j] : 0.0; };
  full_gradient();
  for (int j = 0; j < c; ++j) d_[j] = free_gradient(j);

  bool fresh_gradient = true;  // g was just recomputed, not updated by recurrence
  for (int it = 0;; ++it) {
    // projected gradient (in velocity units), chopped and reduced free gradients
    double projected_max_mps = 0.0;
    double chopped_sq = 0.0;
    double reduced_free = 0.0;
    for (int j = 0; j < c; ++j) {
      if (s[j] == 0.0) continue;
      double projected;
      if (x_[j] > 0.0) {
        projected = g_[j];
        reduced_free += std::min(x_[j] * inv_step_bar, g_[j]) * g_[j];
      } else {
        projected = std::min(g_[j], 0.0);
        chopped_sq += projected * projected;
      }
      projected_max_mps = std::max(projected_max_mps, std::abs(projected) * sqrt_diag[j]);
    }
    if (projected_max_mps <= tol_mps) {
      if (fresh_gradient) {
        for (int j = 0; j < c; ++j) p_[j] = s[j] * x_[j];
        return true;
      }
      full_gradient();  // confirm with a gradient free of recurrence drift
      for (int j = 0; j < c; ++j) d_[j] = free_gradient(j);
      fresh_gradient = true;
      continue;
    }
    if (it >= max_iterations) return false;
    ++stats.iterations;
    fresh_gradient = false;

    if (chopped_sq <= kProportioning * kProportioning * reduced_free) {
      MultiplyA(d_.data(), ad_.data(), s);
      double d_ad = 0.0;
      double g_d = 0.0;
      double feasible_step = std::numeric_limits<double>::infinity();
      for (int j = 0; j < c; ++j) {
        d_ad += d_[j] * ad_[j];
        g_d += g_[j] * d_[j];
        if (d_[j] > 0.0) feasible_step = std::min(feasible_step, x_[j] / d_[j]);
      }
      const double cg_step = d_ad > 0.0 ? g_d / d_ad : std::numeric_limits<double>::infinity();
      if (cg_step <= feasible_step) {
        // conjugate gradient step
        double phi_ad = 0.0;
        for (int j = 0; j < c; ++j) {
          x_[j] = std::max(x_[j] - cg_step * d_[j], 0.0);
          g_[j] -= cg_step * ad_[j];
          phi_ad += free_gradient(j) * ad_[j];
        }
        const double beta = phi_ad / d_ad;
        for (int j = 0; j < c; ++j) d_[j] = free_gradient(j) - beta * d_[j];
      } else {
        // expansion: to the boundary, then a projected gradient step of length step_bar
        const double step = std::isfinite(feasible_step) ? feasible_step : 0.0;
        double objective_half = 0.0;  // 1/2 x^T (g + b_hat) at the boundary point
        for (int j = 0; j < c; ++j) {
          x_[j] = std::max(x_[j] - step * d_[j], 0.0);
          g_[j] -= step * ad_[j];
          tmp_[j] = x_[j];  // keep the boundary point and its gradient for a retry
          ad_[j] = g_[j];
          objective_half += 0.5 * x_[j] * (g_[j] + s[j] * b_mps_[j]);
        }
        for (;;) {
          for (int j = 0; j < c; ++j) {
            x_[j] = std::max(tmp_[j] - step_bar * (tmp_[j] > 0.0 ? ad_[j] : 0.0), 0.0);
          }
          full_gradient();
          double objective = 0.0;
          for (int j = 0; j < c; ++j) objective += 0.5 * x_[j] * (g_[j] + s[j] * b_mps_[j]);
          if (objective <= objective_half || step_bar <= min_step_bar) break;
          step_bar = std::max(0.5 * step_bar, min_step_bar);
          inv_step_bar = 1.0 / step_bar;
        }
        for (int j = 0; j < c; ++j) d_[j] = free_gradient(j);
        fresh_gradient = true;
      }
    } else {
      // proportioning: release bounds whose gradient points into the feasible set
      for (int j = 0; j < c; ++j) tmp_[j] = x_[j] > 0.0 ? 0.0 : std::min(g_[j], 0.0);
      MultiplyA(tmp_.data(), ad_.data(), s);
      double t_at = 0.0;
      double g_t = 0.0;
      for (int j = 0; j < c; ++j) {
        t_at += tmp_[j] * ad_[j];
        g_t += g_[j] * tmp_[j];
      }
      if (!(t_at > 0.0)) return false;  // a released direction without curvature: unbounded
      const double step = g_t / t_at;
      for (int j = 0; j < c; ++j) {
        x_[j] = std::max(x_[j] - step * tmp_[j], 0.0);
        g_[j] -= step * ad_[j];
      }
      for (int j = 0; j < c; ++j) d_[j] = free_gradient(j);
    }
  }
}

bool ImpulseSolver::PolishCg(ImpulseSolverStats& stats) {
  const int c = num_rows_;
  int f = 0;
  for (int j = 0; j < c; ++j) f += in_set_[j];
  // conjugate gradients on A_FF x = -b_F from x = 0: iterates stay in range(A_FF), so the limit
  // is the minimum-norm solution
  const double tol_mps = options_.tolerance * v_ref_mps_;
  const int max_iterations = 2 * f + 50;
  double r_sq = 0.0;
  for (int j = 0; j < c; ++j) {
    x_[j] = 0.0;
    g_[j] = in_set_[j] ? -b_mps_[j] : 0.0;  // residual
    d_[j] = g_[j];
    r_sq += g_[j] * g_[j];
  }
  for (int it = 0; it < max_iterations; ++it) {
    double r_max_mps = 0.0;
    for (int j = 0; j < c; ++j) r_max_mps = std::max(r_max_mps, std::abs(g_[j]));
    if (r_max_mps <= tol_mps) break;
    ++stats.polish_iterations;
    MultiplyA(d_.data(), ad_.data(), nullptr);
    double d_ad = 0.0;
    for (int j = 0; j < c; ++j) d_ad += in_set_[j] ? d_[j] * ad_[j] : 0.0;
    if (!(d_ad > 0.0)) break;
    const double step = r_sq / d_ad;
    double r_sq_new = 0.0;
    for (int j = 0; j < c; ++j) {
      if (!in_set_[j]) continue;
      x_[j] += step * d_[j];
      g_[j] -= step * ad_[j];
      r_sq_new += g_[j] * g_[j];
    }
    const double beta = r_sq_new / r_sq;
    r_sq = r_sq_new;
    for (int j = 0; j < c; ++j) d_[j] = in_set_[j] ? g_[j] + beta * d_[j] : 0.0;
  }
  tmp_.head(c) = x_.head(c);
  return AcceptPolish();
}

bool ImpulseSolver::AcceptPolish() {
  // the candidate x (in tmp_) is in S, hence the minimum-norm plastic impulse, if it is >= 0
  // (up to rounding) and satisfies w >= 0 with w = 0 where it carries impulse
  const int c = num_rows_;
  double x_max = 0.0;
  for (int j = 0; j < c; ++j) x_max = std::max(x_max, tmp_[j]);
  for (int j = 0; j < c; ++j) {
    if (!std::isfinite(tmp_[j]) || tmp_[j] < -1e-9 * x_max) return false;
    tmp_[j] = std::max(tmp_[j], 0.0);
  }
  MultiplyA(tmp_.data(), ad_.data(), nullptr);
  const double accept_mps = 10.0 * options_.tolerance * v_ref_mps_;
  for (int j = 0; j < c; ++j) {
    if (inert_[j]) continue;
    const double w_mps = ad_[j] + b_mps_[j];
    if (w_mps < -accept_mps || (tmp_[j] > 0.0 && w_mps > accept_mps)) return false;
  }
  p_.head(c) = tmp_.head(c);
  return true;
}

}  // namespace rigidtouch::contact
