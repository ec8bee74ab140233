// Helpers on a packed impulse problem (impulse.h): contact Jacobian products, the Delassus matrix
// and kinetic energy. They are shared by the reference solver, the production solver's tests and
// the engine.
//
// Notation (Eq. 1-3, docs/method.md): a group of b dynamic bodies with block-diagonal mass matrix
// M = diag(m_i I3, I_i) and velocity v = (v_i, w_i), and c frictionless contact rows. Row j of the
// contact Jacobian Jc (c x 6b) is, for body a of the contact, [n^T, (r_a x n)^T] and, for body b,
// -[n^T, (r_b x n)^T], so that (Jc v)_j = n . (v_a + w_a x r_a - v_b - w_b x r_b) is the relative
// normal velocity (negative = approaching). Static geometry (index -1) has no columns.
//
// None of these functions allocates or throws; body indices are assumed valid (checked by the
// callers that face user input: ReferenceImpulse and ImpulseSolver::Solve).
#pragma once

#include <Eigen/Core>
#include <span>

#include "contact/impulse.h"

namespace rigidtouch::contact {

using Vec6 = Eigen::Matrix<double, 6, 1>;

/// One side's block of a contact row of Jc (Eq. 3): [n; r x n] for the unit normal n_W and the
/// contact point r_W from the body's centre of mass. Body a's block is RowJacobian(n, r_a), body
/// b's is -RowJacobian(n, r_b).
inline Vec6 RowJacobian(const Vec3& n_W, const Vec3& r_W) {
  Vec6 jac;
  jac << n_W, r_W.cross(n_W);
  return jac;
}

/// Relative normal velocity (Jc v)_row of one row in m/s; negative means the contact approaches.
double NormalVelocity(const ImpulseProblem& problem, int row);

/// Kinetic energy in J of the bodies, 1/2 m |v|^2 + 1/2 w^T I w. A body with inv_mass 0 has
/// infinite mass and contributes no translational energy; a zero inv_inertia_W means infinite
/// inertia and contributes no rotational energy. A singular but non-zero inv_inertia_W is treated
/// through its pseudo-inverse (infinite inertia about its null directions). Does not allocate.
double KineticEnergy(std::span<const SolverBody> bodies);

/// Applies normal impulses p (N s, one per row) to the bodies' velocities, Eq. 2 with Jc^T p:
/// v_a += inv_mass_a n p, w_a += invI_a (r_a x n) p, and the opposite for body b.
void ApplyImpulses(std::span<SolverBody> bodies, std::span<const SolverRow> rows,
                   std::span<const double> p);

/// Writes the Delassus matrix A = Jc M^-1 Jc^T (c x c, in 1/kg) into `A`, which must be c x c.
/// A_ij is the change of row i's normal velocity per unit impulse on row j; it is symmetric
/// positive semi-definite, and singular for redundant rows (a face on a plane).
void DelassusDense(const ImpulseProblem& problem, Eigen::Ref<Eigen::MatrixXd> A);

/// Writes b = Jc v (c, m/s), the relative normal velocity of every row, into `b` (size c).
void JcV(const ImpulseProblem& problem, Eigen::Ref<Eigen::VectorXd> b);

}  // namespace rigidtouch::contact
