#include "contact/impulse_reference.h"

#include <Eigen/QR>
#include <cmath>
#include <string>

#include "contact/impulse_math.h"

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

}  // namespace rigidtouch::contact
