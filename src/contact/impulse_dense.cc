// The dense active-set method of ImpulseSolver (step 2 of impulse_solver.h for groups of at most
// options.dense_max_rows rows): Lawson and Hanson's primal active set (NNLS), written for the
// plastic QP, on A + regularization * diag(A), with a Cholesky factor of the free rows that grows
// a row at a time.
#include <algorithm>
#include <cmath>
#include <limits>

#include "contact/impulse_solver.h"

namespace rigidtouch::contact {

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

}  // namespace rigidtouch::contact
