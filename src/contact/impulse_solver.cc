#include "contact/impulse_solver.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "contact/impulse_math.h"

namespace rigidtouch::contact {
namespace {

bool AllFiniteVec3(const Vec3& v) {
  return v.allFinite();
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
  if (options.interior_max_bodies < 0 || options.interior_after_iterations < 0) {
    throw Error("ImpulseSolverOptions::interior_max_bodies = " +
                std::to_string(options.interior_max_bodies) + " and interior_after_iterations = " +
                std::to_string(options.interior_after_iterations) + " must be >= 0");
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
  const int interior_bodies = std::min(max_bodies, options.interior_max_bodies);
  interior_.factor.Reserve(interior_bodies, max_rows, 32 * interior_bodies);
  interior_.mass_kg.assign(static_cast<std::size_t>(max_bodies), 0.0);
  interior_.inertia_W.assign(static_cast<std::size_t>(max_bodies), Mat3::Zero());
  for (auto* v :
       {&interior_.v0, &interior_.v, &interior_.rd, &interior_.dv, &interior_.body_step}) {
    v->assign(static_cast<std::size_t>(max_bodies), Vec6::Zero());
  }
  interior_.edges.assign(static_cast<std::size_t>(max_rows), 0);
  for (auto* v : {&interior_.s, &interior_.z, &interior_.ds, &interior_.dz, &interior_.rp,
                  &interior_.rc, &interior_.z_best}) {
    v->setZero(max_rows);
  }
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
                                        std::span<double> p_out, std::span<const double> p_warm,
                                        const ImpulseSolveHint& hint) {
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
    stats.converged = stats.matrix_free ? SolveLarge(problem, start, hint.interior, stats)
                                        : SolveDense(start, stats);
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

bool ImpulseSolver::SolveLarge(const ImpulseProblem& problem, std::span<const double> start,
                               bool to_interior, ImpulseSolverStats& stats) {
  const int c = num_rows_;
  const int limit = options_.max_iterations > 0 ? options_.max_iterations : 20 * c + 200;
  // a group too large for the dense fallback goes to the interior-point method once MPRGP has
  // had interior_after_iterations without converging (when the factor can hold its bodies),
  // or at once when the caller says the group's last solve went there (MPRGP then only checks
  // whether p = start already solves it)
  const bool interior = c > max_dense_ && options_.interior_max_bodies > 0 &&
                        num_bodies_ <= interior_.factor.max_nodes;
  const int after = to_interior ? 0 : options_.interior_after_iterations;
  const int budget = interior ? std::min(limit, after) : limit;
  if (SolveMprgp(start, stats, budget)) return true;
  if (c <= max_dense_) {
    // MPRGP can stall on highly degenerate groups; the finite dense method settles them
    p_.head(c).setZero();
    stats.matrix_free = false;
    stats.iterations = 0;
    return SolveDense(start, stats);
  }
  if (!interior) return false;
  stats.interior_point = true;
  if (SolveInterior(problem, stats)) return true;
  // no interior answer (a body of infinite inertia, or a factor too full): MPRGP to its limit
  stats.interior_point = false;
  if (budget >= limit) return false;
  p_.head(c).setZero();
  return SolveMprgp(start, stats, limit);
}

ImpulseSolverError ImpulseSolver::Pack(const ImpulseProblem& problem) {
  num_rows_ = static_cast<int>(problem.rows.size());
  num_bodies_ = static_cast<int>(problem.bodies.size());
  for (int k = 0; k < num_bodies_; ++k) {
    const SolverBody& body = problem.bodies[k];
    if (!std::isfinite(body.inv_mass) || body.inv_mass < 0.0 || !body.inv_inertia_W.allFinite() ||
        (body.inv_inertia_W.diagonal().array() < 0.0).any() || !AllFiniteVec3(body.v_W) ||
        !AllFiniteVec3(body.w_W)) {
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
    if (!AllFiniteVec3(row.n_W) || !AllFiniteVec3(row.r_a_W) || !AllFiniteVec3(row.r_b_W)) {
      return ImpulseSolverError::kNonFiniteInput;
    }
    PackedRow& packed = rows_[j];
    packed.body_a = row.body_a;
    packed.body_b = row.body_b;
    double diag = 0.0;
    double b_mps = 0.0;
    if (row.body_a >= 0) {
      const SolverBody& a = problem.bodies[row.body_a];
      packed.jac_a = RowJacobian(row.n_W, row.r_a_W);
      const Vec3 lever = packed.jac_a.tail<3>();
      packed.minv_jt_a.head<3>() = a.inv_mass * row.n_W;
      packed.minv_jt_a.tail<3>() = a.inv_inertia_W * lever;
      diag += packed.jac_a.dot(packed.minv_jt_a);
      b_mps += row.n_W.dot(a.v_W) + lever.dot(a.w_W);
      ++body_row_count_[row.body_a];
    }
    if (row.body_b >= 0) {
      const SolverBody& b = problem.bodies[row.body_b];
      packed.jac_b = -RowJacobian(row.n_W, row.r_b_W);
      const Vec3 lever = -packed.jac_b.tail<3>();
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
    const double yj = RowVelocity(j, dv);
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

}  // namespace rigidtouch::contact
