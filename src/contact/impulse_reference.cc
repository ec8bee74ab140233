#include "contact/impulse_reference.h"

#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <string>

#include "contact/impulse_math.h"
#include "contact/pivoted_cholesky.h"

namespace rigidtouch::contact {
namespace {

void CheckProblem(const ImpulseProblem& problem) {
  const auto num_bodies = static_cast<int>(problem.bodies.size());
  for (std::size_t k = 0; k < problem.bodies.size(); ++k) {
    const SolverBody& body = problem.bodies[k];
    if (!std::isfinite(body.inv_mass) || body.inv_mass < 0.0 || !body.inv_inertia_W.allFinite() ||
        !body.v_W.allFinite() || !body.w_W.allFinite()) {
      throw Error("ReferenceImpulse: body " + std::to_string(k) +
                  " has a negative or non-finite inv_mass, inv_inertia_W, v_W or w_W");
    }
  }
  for (std::size_t j = 0; j < problem.rows.size(); ++j) {
    const SolverRow& row = problem.rows[j];
    const bool a_ok = row.body_a >= -1 && row.body_a < num_bodies;
    const bool b_ok = row.body_b >= -1 && row.body_b < num_bodies;
    if (!a_ok || !b_ok || row.body_a == row.body_b) {
      throw Error("ReferenceImpulse: row " + std::to_string(j) +
                  " has body_a = " + std::to_string(row.body_a) +
                  ", body_b = " + std::to_string(row.body_b) + "; each must be in [-1, " +
                  std::to_string(num_bodies - 1) + "] and they must differ");
    }
    if (!row.n_W.allFinite() || !row.r_a_W.allFinite() || !row.r_b_W.allFinite()) {
      throw Error("ReferenceImpulse: row " + std::to_string(j) + " has a non-finite n_W or r_W");
    }
  }
}

}  // namespace

Eigen::VectorXd ReferenceImpulse(const ImpulseProblem& problem, double restitution,
                                 int remaining_impulses) {
  if (!(restitution >= 0.0 && restitution <= 1.0)) {
    throw Error("ReferenceImpulse: restitution = " + std::to_string(restitution) +
                " is outside [0, 1]");
  }
  if (remaining_impulses < 1) {
    throw Error("ReferenceImpulse: remaining_impulses = " + std::to_string(remaining_impulses) +
                " must be >= 1");
  }
  CheckProblem(problem);
  const auto c = static_cast<Eigen::Index>(problem.rows.size());
  if (c == 0) return Eigen::VectorXd();

  Eigen::MatrixXd A(c, c);  // Jc M^-1 Jc^T
  Eigen::VectorXd b(c);     // Jc v0
  DelassusDense(problem, A);
  JcV(problem, b);

  // solve() of the complete orthogonal decomposition is the minimum-norm least-squares solution,
  // i.e. A^# b, without forming the pseudo-inverse
  Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> cod;
  cod.setThreshold(kReferencePinvThreshold);
  cod.compute(A);
  const double scale = (1.0 + restitution) / static_cast<double>(remaining_impulses);
  return -scale * cod.solve(b);  // Eq. 5, Eq. 8
}

ReferenceSolver::ReferenceSolver(int max_rows, int max_bodies)
    : max_rows_(max_rows), max_bodies_(max_bodies) {
  if (max_rows < 0 || max_bodies < 0) {
    throw Error("ReferenceSolver: max_rows = " + std::to_string(max_rows) +
                " and max_bodies = " + std::to_string(max_bodies) + " must be >= 0");
  }
  // rank(A) <= rank(Jc) <= 6 bodies: L never has more columns
  const int max_rank = static_cast<int>(std::min<long>(max_rows, 6L * max_bodies));
  a_.setZero(max_rows, max_rows);
  l_.setZero(max_rows, max_rank);
  order_.setZero(max_rows);
  b_.setZero(max_rows);
  sqrt_d_.setZero(max_rows);
  tau_.setZero(max_rank);
  t_.setZero(max_rows);
  x_.setZero(max_rows);
}

bool ReferenceSolver::Valid(const ImpulseProblem& problem) const {
  // the conditions under which ReferenceImpulse throws (CheckProblem), as a test
  const auto num_bodies = static_cast<int>(problem.bodies.size());
  for (const SolverBody& body : problem.bodies) {
    if (!std::isfinite(body.inv_mass) || body.inv_mass < 0.0 || !body.inv_inertia_W.allFinite() ||
        !body.v_W.allFinite() || !body.w_W.allFinite()) {
      return false;
    }
  }
  for (const SolverRow& row : problem.rows) {
    const bool a_ok = row.body_a >= -1 && row.body_a < num_bodies;
    const bool b_ok = row.body_b >= -1 && row.body_b < num_bodies;
    if (!a_ok || !b_ok || row.body_a == row.body_b) return false;
    if (!row.n_W.allFinite() || !row.r_a_W.allFinite() || !row.r_b_W.allFinite()) return false;
  }
  return true;
}

bool ReferenceSolver::Solve(const ImpulseProblem& problem, double restitution,
                            int remaining_impulses, std::span<double> p) noexcept {
  std::fill(p.begin(), p.end(), 0.0);
  if (!(restitution >= 0.0 && restitution <= 1.0) || remaining_impulses < 1) return false;
  if (p.size() != problem.rows.size() || problem.rows.size() > std::size_t(max_rows_) ||
      problem.bodies.size() > std::size_t(max_bodies_) || !Valid(problem)) {
    return false;
  }
  const auto c = static_cast<int>(problem.rows.size());
  if (c == 0) return true;
  DelassusDense(problem, a_.topLeftCorner(c, c));
  JcV(problem, b_.head(c));
  if (!a_.topLeftCorner(c, c).allFinite() || !b_.head(c).allFinite()) return false;
  const int r = Factor(c);
  if (r > l_.cols()) return false;  // more than 6 per body: rounding, not a rank
  MinimumNormSolve(c, r);
  const double scale = (1.0 + restitution) / static_cast<double>(remaining_impulses);
  for (int j = 0; j < c; ++j) {
    if (!std::isfinite(x_[j])) {
      std::fill(p.begin(), p.end(), 0.0);
      return false;
    }
    p[j] = -scale * x_[j];  // Eq. 5, Eq. 8
  }
  return true;
}

int ReferenceSolver::Factor(int c) {
  // Jacobi scaling to a unit diagonal makes the rank threshold independent of the bodies' masses;
  // a row without effective mass (A_jj = 0) is a zero row of A and stays out of the factor
  for (int j = 0; j < c; ++j) {
    const double d = a_(j, j);
    sqrt_d_[j] = d > 0.0 ? std::sqrt(d) : 0.0;
    order_[j] = j;
  }
  for (int j = 0; j < c; ++j) {
    for (int i = 0; i < c; ++i) {
      const double d = sqrt_d_[i] * sqrt_d_[j];
      a_(i, j) = d > 0.0 ? a_(i, j) / d : 0.0;
    }
  }
  // P S A S P^T ~= G G^T, so A ~= L L^T with row order[i] of L = sqrt(A_jj) G_i (G lower
  // trapezoidal: its entries above the diagonal are left over from the factorisation)
  const int r = PivotedCholesky(a_, c, order_, kReferencePinvThreshold);
  if (r > l_.cols()) return r;
  for (int i = 0; i < c; ++i) {
    const int row = order_[i];
    for (int k = 0; k < r; ++k) l_(row, k) = k <= i ? sqrt_d_[row] * a_(i, k) : 0.0;
  }
  return r;
}

void ReferenceSolver::ApplyReflectors(int c, int r, bool transpose) {
  // Q = H_0 ... H_(r-1), H_k = I - tau_k v_k v_k^T with v_k = [0; 1; l_(k+1:c, k)]
  for (int step = 0; step < r; ++step) {
    const int k = transpose ? step : r - 1 - step;
    double w = t_[k];
    for (int i = k + 1; i < c; ++i) w += l_(i, k) * t_[i];
    w *= tau_[k];
    t_[k] -= w;
    for (int i = k + 1; i < c; ++i) t_[i] -= w * l_(i, k);
  }
}

void ReferenceSolver::MinimumNormSolve(int c, int r) {
  // Householder QR of L in place (LAPACK's dlarfg convention): R on and above the diagonal,
  // the reflectors' vectors below it
  for (int k = 0; k < r; ++k) {
    double sigma = 0.0;
    for (int i = k + 1; i < c; ++i) sigma += l_(i, k) * l_(i, k);
    const double alpha = l_(k, k);
    const double norm = std::sqrt(alpha * alpha + sigma);
    if (norm == 0.0) {
      tau_[k] = 0.0;  // a zero column: R_kk = 0, and the solve below gives a non-finite result
      continue;
    }
    const double beta = alpha >= 0.0 ? -norm : norm;
    const double v0 = alpha - beta;
    for (int i = k + 1; i < c; ++i) l_(i, k) /= v0;
    tau_[k] = (beta - alpha) / beta;
    l_(k, k) = beta;
    for (int j = k + 1; j < r; ++j) {
      double w = l_(k, j);
      for (int i = k + 1; i < c; ++i) w += l_(i, k) * l_(i, j);
      w *= tau_[k];
      l_(k, j) -= w;
      for (int i = k + 1; i < c; ++i) l_(i, j) -= w * l_(i, k);
    }
  }
  // A^# b = Q R^-T R^-1 Q^T b: t = Q^T b, then R^-1 and R^-T on its first r entries
  t_.head(c) = b_.head(c);
  ApplyReflectors(c, r, true);
  for (int k = r - 1; k >= 0; --k) {
    double sum = t_[k];
    for (int m = k + 1; m < r; ++m) sum -= l_(k, m) * t_[m];
    t_[k] = sum / l_(k, k);
  }
  for (int k = 0; k < r; ++k) {
    double sum = t_[k];
    for (int m = 0; m < k; ++m) sum -= l_(m, k) * t_[m];
    t_[k] = sum / l_(k, k);
  }
  for (int i = r; i < c; ++i) t_[i] = 0.0;
  ApplyReflectors(c, r, false);
  x_.head(c) = t_.head(c);
}

}  // namespace rigidtouch::contact
