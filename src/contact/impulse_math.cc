#include "contact/impulse_math.h"

#include <Eigen/Cholesky>
#include <cassert>

namespace rigidtouch::contact {
namespace {

// one side of a row: the body it acts on, the sign of its Jacobian block and the lever r x n
struct ImpulseRowSide {
  int body = -1;
  double sign = 0.0;
  Vec3 lever_W = Vec3::Zero();  // r x n  [m]
};

ImpulseRowSide SideA(const SolverRow& row) {
  return {row.body_a, 1.0, RowJacobian(row.n_W, row.r_a_W).tail<3>()};
}
ImpulseRowSide SideB(const SolverRow& row) {
  return {row.body_b, -1.0, RowJacobian(row.n_W, row.r_b_W).tail<3>()};
}

// contribution of one shared body to A_ij = J_i M^-1 J_j^T
double Coupling(const SolverBody& body, const SolverRow& row_i, const ImpulseRowSide& side_i,
                const SolverRow& row_j, const ImpulseRowSide& side_j) {
  return side_i.sign * side_j.sign *
         (body.inv_mass * row_i.n_W.dot(row_j.n_W) +
          side_i.lever_W.dot(body.inv_inertia_W * side_j.lever_W));
}

}  // namespace

double NormalVelocity(const ImpulseProblem& problem, int row) {
  assert(row >= 0 && static_cast<std::size_t>(row) < problem.rows.size());
  const SolverRow& r = problem.rows[row];
  Vec3 v_rel_W = Vec3::Zero();  // velocity of the contact point on a relative to b
  if (r.body_a >= 0) {
    const SolverBody& a = problem.bodies[r.body_a];
    v_rel_W += a.v_W + a.w_W.cross(r.r_a_W);
  }
  if (r.body_b >= 0) {
    const SolverBody& b = problem.bodies[r.body_b];
    v_rel_W -= b.v_W + b.w_W.cross(r.r_b_W);
  }
  return r.n_W.dot(v_rel_W);
}

double KineticEnergy(std::span<const SolverBody> bodies) {
  double energy_J = 0.0;
  for (const SolverBody& body : bodies) {
    if (body.inv_mass > 0.0) energy_J += 0.5 * body.v_W.squaredNorm() / body.inv_mass;
    if (!body.inv_inertia_W.isZero(0.0)) {
      // 1/2 w^T I w with I = (I^-1)^-1; fixed-size LDLT lives on the stack, and its solve uses
      // the pseudo-inverse of D for zero pivots (infinite inertia about those axes)
      const Eigen::LDLT<Mat3> inv_inertia_ldlt(body.inv_inertia_W);
      const Vec3 angular_momentum = inv_inertia_ldlt.solve(body.w_W);
      energy_J += 0.5 * body.w_W.dot(angular_momentum);
    }
  }
  return energy_J;
}

void ApplyImpulses(std::span<SolverBody> bodies, std::span<const SolverRow> rows,
                   std::span<const double> p) {
  assert(p.size() == rows.size());
  for (std::size_t j = 0; j < rows.size(); ++j) {
    const SolverRow& row = rows[j];
    // Eq. 2: M dv = Jc^T p, one row at a time
    if (row.body_a >= 0) {
      SolverBody& a = bodies[row.body_a];
      const Vec3 lever_W = RowJacobian(row.n_W, row.r_a_W).tail<3>();
      a.v_W += a.inv_mass * p[j] * row.n_W;
      a.w_W += a.inv_inertia_W * (lever_W * p[j]);
    }
    if (row.body_b >= 0) {
      SolverBody& b = bodies[row.body_b];
      const Vec3 lever_W = RowJacobian(row.n_W, row.r_b_W).tail<3>();
      b.v_W -= b.inv_mass * p[j] * row.n_W;
      b.w_W -= b.inv_inertia_W * (lever_W * p[j]);
    }
  }
}

void DelassusDense(const ImpulseProblem& problem, Eigen::Ref<Eigen::MatrixXd> A) {
  const auto c = static_cast<Eigen::Index>(problem.rows.size());
  assert(A.rows() == c && A.cols() == c);
  for (Eigen::Index i = 0; i < c; ++i) {
    const SolverRow& row_i = problem.rows[i];
    const ImpulseRowSide sides_i[2] = {SideA(row_i), SideB(row_i)};
    for (Eigen::Index j = 0; j <= i; ++j) {
      const SolverRow& row_j = problem.rows[j];
      const ImpulseRowSide sides_j[2] = {SideA(row_j), SideB(row_j)};
      double a_ij = 0.0;
      for (const ImpulseRowSide& si : sides_i) {
        if (si.body < 0) continue;
        for (const ImpulseRowSide& sj : sides_j) {
          if (sj.body != si.body) continue;
          a_ij += Coupling(problem.bodies[si.body], row_i, si, row_j, sj);
        }
      }
      A(i, j) = a_ij;
      A(j, i) = a_ij;
    }
  }
}

void JcV(const ImpulseProblem& problem, Eigen::Ref<Eigen::VectorXd> b) {
  assert(b.size() == static_cast<Eigen::Index>(problem.rows.size()));
  for (Eigen::Index j = 0; j < b.size(); ++j) b[j] = NormalVelocity(problem, static_cast<int>(j));
}

}  // namespace rigidtouch::contact
