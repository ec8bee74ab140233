// The minimum-norm polish of ImpulseSolver (step 3 of impulse_solver.h): conjugate gradients
// on the free set's equations, and the exact dense method (a rank-revealing factor and a primal
// active set for the minimum-norm non-negative solution).
#include <algorithm>
#include <cmath>

#include "contact/impulse_solver.h"
#include "contact/pivoted_cholesky.h"

namespace rigidtouch::contact {

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
  // a group MPRGP could not settle in its budget is too ill-conditioned for conjugate gradients
  // too: after the interior point they found the minimum norm in 2 of 1544 solves of a kicked
  // 100-box pile, and took half the time
  if (stats.interior_point) return dense_fits && PolishDense(f, stats);
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
