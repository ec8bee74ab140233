// Dry joint friction of kinematic trees (src/dynamics/tree.h, TreeFrictionImpulse) and the step's
// velocity update that applies it (docs/decisions.md, "Dry joint friction").
#include <algorithm>
#include <cmath>

#include "dynamics/tree.h"

namespace rigidtouch::dynamics {

int TreeFrictionImpulse(const TreeModel& model, TreeData& data, double h_s) {
  const std::vector<int>& F = model.friction_dofs;
  const int nf = static_cast<int>(F.size());
  data.friction_sweeps = 0;
  if (nf == 0 || !data.factored) return 0;
  Eigen::MatrixXd& A = data.friction_A;
  Eigen::VectorXd& lambda = data.friction_lambda;
  // A = (M + h D)^-1 on F x F, one solve per friction dof with the kept factor
  for (int c = 0; c < nf; ++c) {
    data.scratch_v.setZero();
    data.scratch_v[F[c]] = 1.0;
    TreeSolve(data, data.scratch_v);
    for (int r = 0; r < nf; ++r) A(r, c) = data.scratch_v[F[r]];
    data.friction_v[c] = data.qvel[F[c]];
  }
  // projected Gauss-Seidel on min 1/2 l^T A l + l^T v over the box |l_i| <= h f_i, from l = 0
  lambda.setZero();
  bool converged = false;
  while (!converged && data.friction_sweeps < kFrictionMaxSweeps) {
    ++data.friction_sweeps;
    converged = true;
    for (int i = 0; i < nf; ++i) {
      const double bound = h_s * model.joint(model.dof_joint[F[i]]).frictionloss;
      const double velocity = data.friction_v[i] + A.row(i).dot(lambda);  // dof i's after l
      const double next = std::clamp(lambda[i] - velocity / A(i, i), -bound, bound);
      if (std::abs(next - lambda[i]) > 1e-12 * bound) converged = false;
      lambda[i] = next;
    }
  }
  // qvel += (M + h D)^-1 l, l placed on the friction dofs
  data.scratch_w.setZero();
  for (int i = 0; i < nf; ++i) data.scratch_w[F[i]] = lambda[i];
  TreeSolve(data, data.scratch_w);
  data.qvel += data.scratch_w;
  if (converged) {
    // a dof that sticks (impulse inside its bound) has zero velocity at the minimum: make it exact
    // so that a held joint does not creep by rounding
    for (int i = 0; i < nf; ++i) {
      const double bound = h_s * model.joint(model.dof_joint[F[i]]).frictionloss;
      if (std::abs(lambda[i]) < bound) data.qvel[F[i]] = 0.0;
    }
  }
  return data.friction_sweeps;
}

void TreeFreeVelocity(const TreeModel& model, TreeData& data, double h_s,
                      const Eigen::Ref<const Eigen::VectorXd>& tau) {
  // (M + h D) dv = h (tau - bias + passive): backward Euler on the damper, explicit on the rest
  data.scratch_w = h_s * (tau - data.bias + data.passive);
  TreeSolve(data, data.scratch_w);
  data.qvel += data.scratch_w;
  TreeFrictionImpulse(model, data, h_s);
}

}  // namespace rigidtouch::dynamics
