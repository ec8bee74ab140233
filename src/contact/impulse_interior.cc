// The body-space interior-point method of ImpulseSolver (step 2 of impulse_solver.h, for groups
// MPRGP does not settle within its budget): the plastic impulse as the multipliers of the
// velocity problem
//
//     v+ = argmin_v 1/2 (v - v0)^T M (v - v0)   subject to   Jc v >= 0,
//
// whose dual is the plastic QP. A primal-dual method with Mehrotra's predictor-corrector steps
// on the slacks s = Jc v and multipliers z >= 0 (Nocedal and Wright 2006, sections 16.6 and
// 14.2). Each iteration factors the 6 x 6 block-sparse matrix M + Jc^T (Z / S) Jc over the
// group's bodies (BlockCholesky: one block row per body, coupled where two bodies share a
// contact), so its cost does not depend on how redundant or nearly redundant the rows are:
// the objective is strongly convex in v whatever the rank of Jc, where MPRGP's conjugate
// gradients in impulse space slow down with the condition of A (1e9 to 1e11 on its range in
// the groups of a 100-box pile). The answer p = z is an interior limit: on redundant rows it
// spreads the impulse rather than picking a vertex.
#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <limits>

#include "contact/impulse_solver.h"

namespace rigidtouch::contact {
namespace {

// Mehrotra's step back from the boundary of s, z > 0
constexpr double kStepToBoundary = 0.99;

// the largest step in (0, 1] along dx that keeps x > 0 (x > 0 on entry)
double MaxStep(const Eigen::VectorXd& x, const Eigen::VectorXd& dx, const Eigen::VectorXi& skip,
               int n) {
  double step = 1.0;
  for (int j = 0; j < n; ++j) {
    if (!skip[j] && dx[j] < 0.0) step = std::min(step, -x[j] / dx[j]);
  }
  return step;
}

}  // namespace

bool ImpulseSolver::InteriorStructure(const ImpulseProblem& problem) {
  const int nb = num_bodies_;
  const int c = num_rows_;
  if (nb > interior_.factor.max_nodes) return false;
  for (int k = 0; k < nb; ++k) {
    const SolverBody& body = problem.bodies[k];
    // M_k = diag(m, I_W): a body of infinite mass or inertia has no such block
    const Eigen::LLT<Mat3> llt(body.inv_inertia_W);
    if (!(body.inv_mass > 0.0) || llt.info() != Eigen::Success) return false;
    interior_.mass_kg[k] = 1.0 / body.inv_mass;
    interior_.inertia_W[k] = llt.solve(Mat3::Identity());
    if (!interior_.inertia_W[k].allFinite()) return false;
    interior_.v0[k] << body.v_W, body.w_W;
  }
  int nedges = 0;
  for (int j = 0; j < c; ++j) {
    const PackedRow& row = rows_[j];
    if (inert_[j] || row.body_a < 0 || row.body_b < 0) continue;
    interior_.edges[nedges++] =
        dynamics::PackEdge(std::min(row.body_a, row.body_b), std::max(row.body_a, row.body_b));
  }
  const auto begin = interior_.edges.begin(), end = begin + nedges;
  std::sort(begin, end);
  nedges = static_cast<int>(std::unique(begin, end) - begin);
  return interior_.factor.Analyse(nb, {interior_.edges.data(), static_cast<std::size_t>(nedges)});
}

bool ImpulseSolver::InteriorFactor() {
  // M + sum_j (z_j / s_j) J_j^T J_j, written by elimination position
  dynamics::BlockCholesky& f = interior_.factor;
  const int nb = num_bodies_;
  f.ZeroOffDiagonal(nb);
  for (int k = 0; k < nb; ++k) {
    dynamics::Mat6& d = f.diag[f.pos[k]];
    d.setZero();
    d.topLeftCorner<3, 3>().diagonal().setConstant(interior_.mass_kg[k]);
    d.bottomRightCorner<3, 3>() = interior_.inertia_W[k];
  }
  for (int j = 0; j < num_rows_; ++j) {
    if (inert_[j]) continue;
    const PackedRow& row = rows_[j];
    const double weight = interior_.z[j] / interior_.s[j];
    const Vec6 wa = weight * row.jac_a, wb = weight * row.jac_b;
    if (row.body_a >= 0) f.diag[f.pos[row.body_a]].noalias() += wa * row.jac_a.transpose();
    if (row.body_b >= 0) f.diag[f.pos[row.body_b]].noalias() += wb * row.jac_b.transpose();
    if (row.body_a >= 0 && row.body_b >= 0) {
      const int pa = f.pos[row.body_a], pb = f.pos[row.body_b];
      if (pa > pb) {
        f.Lower(pa, pb).noalias() += wa * row.jac_b.transpose();
      } else {
        f.Lower(pb, pa).noalias() += wb * row.jac_a.transpose();
      }
    }
  }
  return f.Factor(nb);
}

bool ImpulseSolver::InteriorDirection() {
  // the Newton step for the complementarity target rc (in interior_.rc): with
  // D = Z / S, (M + J^T D J) dv = -r_d - J^T S^-1 (rc + Z r_p); ds = J dv + r_p;
  // dz = -S^-1 (rc + Z ds)
  InteriorScratch& ip = interior_;
  const int nb = num_bodies_;
  const int c = num_rows_;
  for (int k = 0; k < nb; ++k) ip.dv[ip.factor.pos[k]] = -ip.rd[k];
  for (int j = 0; j < c; ++j) {
    if (inert_[j]) continue;
    const PackedRow& row = rows_[j];
    const double t = (ip.rc[j] + ip.z[j] * ip.rp[j]) / ip.s[j];
    if (row.body_a >= 0) ip.dv[ip.factor.pos[row.body_a]] -= t * row.jac_a;
    if (row.body_b >= 0) ip.dv[ip.factor.pos[row.body_b]] -= t * row.jac_b;
  }
  if (!ip.factor.Solve(nb, {ip.dv.data(), static_cast<std::size_t>(nb)})) return false;
  for (int k = 0; k < nb; ++k) ip.body_step[k] = ip.dv[ip.factor.pos[k]];
  for (int j = 0; j < c; ++j) {
    if (inert_[j]) continue;
    ip.ds[j] = RowVelocity(j, ip.body_step) + ip.rp[j];
    ip.dz[j] = -(ip.rc[j] + ip.z[j] * ip.ds[j]) / ip.s[j];
  }
  return true;
}

void ImpulseSolver::InteriorCleanUp(double max_trace_mps) {
  // an interior answer leaves a trace of impulse on every row: open rows (z_j A_jj <= w_j) whose
  // impulse alone gives them at most max_trace_mps get none; the polish and the final check then
  // judge the answer. Leaves A p in w_mps_ for the cleaned p
  const int c = num_rows_;
  MultiplyA(p_.data(), w_mps_.data(), nullptr);
  bool changed = false;
  for (int j = 0; j < c; ++j) {
    const double own_mps = p_[j] * diag_[j];
    if (p_[j] > 0.0 && own_mps <= w_mps_[j] + b_mps_[j] && own_mps <= max_trace_mps) {
      p_[j] = 0.0;
      changed = true;
    }
  }
  if (changed) MultiplyA(p_.data(), w_mps_.data(), nullptr);
}

void ImpulseSolver::InteriorResidual(double& approach_mps, double& split_mps) {
  // the answer if the method stopped here: p = z, whose velocities are v0 + M^-1 J^T z
  const int c = num_rows_;
  const InteriorScratch& ip = interior_;
  for (int j = 0; j < c; ++j) p_[j] = ip.z[j];
  MultiplyA(p_.data(), w_mps_.data(), nullptr);
  // the residual, as a velocity. A row is closed when its impulse alone would change its speed
  // by more than it separates (z_j A_jj > w_j), open otherwise (the indicator of El-Bakry et
  // al. 1994); it counts how fast a row approaches (with the scaling by
  // gamma = 1 - p.w / p^T A p of Solve's final check, which makes closed rows approach at
  // (1 - gamma) (A p)_j), how fast a closed row separates, and the speed an open row's impulse
  // gives it (InteriorCleanUp removes that impulse). The last two are at most
  // sqrt(w_j z_j A_jj), so they vanish with the complementarity products
  double az_max_mps = 0.0, p_w_J = 0.0, p_ap_J = 0.0;
  approach_mps = 0.0;
  split_mps = 0.0;  // closed rows' separation and open rows' impulse, as speeds
  for (int j = 0; j < c; ++j) {
    if (inert_[j]) continue;
    const double w = w_mps_[j] + b_mps_[j];
    const double own_mps = ip.z[j] * diag_[j];
    approach_mps = std::max(approach_mps, -w);
    split_mps = std::max(split_mps, own_mps > w ? w : own_mps);
    az_max_mps = std::max(az_max_mps, std::abs(w_mps_[j]));
    p_w_J += ip.z[j] * w;
    p_ap_J += ip.z[j] * w_mps_[j];
  }
  if (p_w_J > 0.0 && p_ap_J > 0.0) approach_mps += p_w_J / p_ap_J * az_max_mps;
}

bool ImpulseSolver::SolveInterior(const ImpulseProblem& problem, ImpulseSolverStats& stats) {
  InteriorScratch& ip = interior_;
  const int nb = num_bodies_;
  const int c = num_rows_;
  if (!InteriorStructure(problem)) return false;
  const double tol_mps = options_.tolerance * v_ref_mps_;
  // a start well inside: slacks at least v_ref, multipliers a tenth of the impulse that stops
  // v_ref on its row alone
  int m = 0;
  for (int j = 0; j < c; ++j) {
    if (inert_[j]) {
      ip.s[j] = ip.z[j] = 0.0;
      continue;
    }
    ip.s[j] = std::max(b_mps_[j], 0.0) + v_ref_mps_;
    ip.z[j] = 0.1 * v_ref_mps_ / diag_[j];
    ++m;
  }
  for (int k = 0; k < nb; ++k) ip.v[k] = ip.v0[k];
  // of the iterates that approach at most a tenth of what Solve's final check accepts, the one
  // of least residual: the answer if rounding stops the method short of tol_mps (the weights
  // z / s of the matrix then span 1e20 and more, and its factorisation fails) or it runs out of
  // iterations. Cleaned up only if no row then approaches faster than that: nearly degenerate
  // rows (both w_j and z_j A_jj about 1e-7 v_ref) may keep their traces, whose removal would
  // make others approach
  const double usable_mps = 0.1 * options_.failure_tolerance * v_ref_mps_;
  double best_residual_mps = std::numeric_limits<double>::infinity();  // of such an iterate
  auto best = [&]() {
    if (!std::isfinite(best_residual_mps)) return false;
    p_.head(c) = ip.z_best.head(c);
    InteriorCleanUp(std::numeric_limits<double>::infinity());
    double approach_mps = 0.0;
    for (int j = 0; j < c; ++j) {
      if (!inert_[j]) approach_mps = std::max(approach_mps, -(w_mps_[j] + b_mps_[j]));
    }
    if (approach_mps > usable_mps) {
      // only the traces too small to matter
      p_.head(c) = ip.z_best.head(c);
      InteriorCleanUp(tol_mps);
    }
    return true;
  };
  for (int it = 0; it < kMaxInteriorIterations; ++it) {
    double approach_mps = 0.0, split_mps = 0.0;
    InteriorResidual(approach_mps, split_mps);
    if (approach_mps <= tol_mps && split_mps <= tol_mps) {
      InteriorCleanUp(std::numeric_limits<double>::infinity());
      return true;
    }
    const double residual_mps = std::max(approach_mps, split_mps);
    if (approach_mps <= usable_mps && residual_mps < best_residual_mps) {
      best_residual_mps = residual_mps;
      ip.z_best.head(c) = ip.z.head(c);
    }
    ++stats.interior_iterations;
    // residuals: r_d = M (v - v0) - J^T z per body, r_p = J v - s per row; mu = s.z / m
    for (int k = 0; k < nb; ++k) {
      const Vec6 dv = ip.v[k] - ip.v0[k];
      ip.rd[k] << interior_.mass_kg[k] * dv.head<3>(), interior_.inertia_W[k] * dv.tail<3>();
    }
    double mu = 0.0;
    for (int j = 0; j < c; ++j) {
      if (inert_[j]) continue;
      const PackedRow& row = rows_[j];
      if (row.body_a >= 0) ip.rd[row.body_a] -= ip.z[j] * row.jac_a;
      if (row.body_b >= 0) ip.rd[row.body_b] -= ip.z[j] * row.jac_b;
      ip.rp[j] = RowVelocity(j, ip.v) - ip.s[j];
      mu += ip.s[j] * ip.z[j];
    }
    mu /= std::max(m, 1);
    if (!InteriorFactor()) return best();
    // predictor (affine scaling): rc = s z
    for (int j = 0; j < c; ++j) ip.rc[j] = ip.s[j] * ip.z[j];
    if (!InteriorDirection()) return best();
    const double alpha_s = MaxStep(ip.s, ip.ds, inert_, c);
    const double alpha_z = MaxStep(ip.z, ip.dz, inert_, c);
    double mu_affine = 0.0;
    for (int j = 0; j < c; ++j) {
      if (inert_[j]) continue;
      mu_affine += (ip.s[j] + alpha_s * ip.ds[j]) * (ip.z[j] + alpha_z * ip.dz[j]);
    }
    mu_affine /= std::max(m, 1);
    const double centring = mu > 0.0 ? std::pow(mu_affine / mu, 3) : 0.0;
    // corrector: rc = s z + ds dz - sigma mu, on the same factor
    for (int j = 0; j < c; ++j) {
      ip.rc[j] = ip.s[j] * ip.z[j] + ip.ds[j] * ip.dz[j] - centring * mu;
    }
    if (!InteriorDirection()) return best();
    const double step = kStepToBoundary *
                        std::min(MaxStep(ip.s, ip.ds, inert_, c), MaxStep(ip.z, ip.dz, inert_, c));
    if (!(step > 0.0)) return best();
    for (int k = 0; k < nb; ++k) ip.v[k] += step * ip.body_step[k];
    for (int j = 0; j < c; ++j) {
      if (inert_[j]) continue;
      ip.s[j] += step * ip.ds[j];
      ip.z[j] += step * ip.dz[j];
    }
  }
  return best();
}

}  // namespace rigidtouch::contact
