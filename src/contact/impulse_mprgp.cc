// MPRGP, the matrix-free active-set method of ImpulseSolver (step 2 of impulse_solver.h for
// groups of more than options.dense_max_rows rows): Dostal and Schoberl 2005, modified
// proportioning with reduced gradient projections, on the Jacobi-scaled problem.
#include <algorithm>
#include <cmath>
#include <limits>

#include "contact/impulse_solver.h"

namespace rigidtouch::contact {
namespace {

// MPRGP's proportioning constant: a proportioning step is taken when the chopped gradient (bounds
// that should be released) outweighs the free gradient by more than this factor
constexpr double kProportioning = 1.0;

}  // namespace

void ImpulseSolver::MprgpGradient() {
  // g = A_hat x + S b
  const double* s = row_scale_.data();
  MultiplyA(x_.data(), g_.data(), s);
  for (int j = 0; j < num_rows_; ++j) g_[j] += s[j] * b_mps_[j];
}

void ImpulseSolver::MprgpExpand(double feasible_step, double min_step_bar, double& step_bar,
                                double& inv_step_bar) {
  // to the boundary along d, then a projected gradient step of length step_bar, halved while it
  // fails to decrease the objective
  const int c = num_rows_;
  const double* s = row_scale_.data();
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
    MprgpGradient();
    double objective = 0.0;
    for (int j = 0; j < c; ++j) objective += 0.5 * x_[j] * (g_[j] + s[j] * b_mps_[j]);
    if (objective <= objective_half || step_bar <= min_step_bar) break;
    step_bar = std::max(0.5 * step_bar, min_step_bar);
    inv_step_bar = 1.0 / step_bar;
  }
}

bool ImpulseSolver::MprgpProportion() {
  // release bounds whose gradient points into the feasible set
  const int c = num_rows_;
  const double* s = row_scale_.data();
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
  return true;
}

bool ImpulseSolver::SolveMprgp(std::span<const double> p_warm, ImpulseSolverStats& stats,
                               int max_iterations) {
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

  // x = S^-1 p, g = A_hat x + S b
  for (int j = 0; j < c; ++j) {
    const bool use_warm = !p_warm.empty() && s[j] > 0.0 && std::isfinite(p_warm[j]);
    x_[j] = use_warm ? std::max(p_warm[j], 0.0) / s[j] : 0.0;
  }
  auto free_gradient = [&](int j) { return x_[j] > 0.0 ? g_[j] : 0.0; };
  MprgpGradient();
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
      MprgpGradient();  // confirm with a gradient free of recurrence drift
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
        MprgpExpand(feasible_step, min_step_bar, step_bar, inv_step_bar);
        for (int j = 0; j < c; ++j) d_[j] = free_gradient(j);
        fresh_gradient = true;
      }
    } else {
      // proportioning: release bounds whose gradient points into the feasible set
      if (!MprgpProportion()) return false;
      for (int j = 0; j < c; ++j) d_[j] = free_gradient(j);
    }
  }
}

}  // namespace rigidtouch::contact
