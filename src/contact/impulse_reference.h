// The reference impulse solver: METHOD.md Eq. 5 and Eq. 8 exactly, with a pseudo-inverse.
//
//   p = -(1 + e) (Jc M^-1 Jc^T)^# Jc v0 / remaining                              Eq. 5, Eq. 8
//
// With A = Jc M^-1 Jc^T and b = Jc v0, b lies in range(A) when every body has finite mass
// (range(Jc) = range(A)), so p0 = -A^# b solves A p0 = -b: after the plastic impulse p0 every row,
// including the separating ones, has exactly zero relative normal velocity, and p0 is the
// minimum-norm impulse that does so (redundant rows share it evenly in the least-squares sense).
// Consequences a reader should know:
// - p may have negative (adhesive) components: a row that separates fast enough is pulled back
//   to zero relative velocity. That is why the production solver (impulse_solver.h) solves the
//   non-negative plastic problem instead; the two agree whenever this answer is non-negative.
// - Energy: with s = (1 + e) / remaining and w0 = A p0 + b = 0, the kinetic energy change of the
//   impulse s p0 is s p0^T b + s^2/2 p0^T A p0 = -(s - s^2/2) p0^T A p0 <= 0 for s in [0, 2], so
//   the reference never adds energy, even with adhesive components (it is an M-orthogonal
//   projection of the velocity). This needs b in range(A); a body with inv_mass 0 but non-zero
//   inv_inertia can break it.
#pragma once

#include <Eigen/Core>

#include "contact/impulse.h"

namespace rigidtouch::contact {

/// Relative threshold of the pseudo-inverse: a pivot of the rank-revealing QR of A counts as zero
/// when |pivot| <= kReferencePinvThreshold * |largest pivot|.
inline constexpr double kReferencePinvThreshold = 1e-10;

/// Returns the impulse of Eq. 5 / Eq. 8, p = -(1 + e) A^# Jc v0 / remaining (N s, one per row),
/// computed with Eigen::CompleteOrthogonalDecomposition::solve (the minimum-norm least-squares
/// solution) at threshold kReferencePinvThreshold. `restitution` is e in [0, 1];
/// `remaining_impulses` is N - i + 1 >= 1 (1 for the single impulse of Eq. 5). Allocates; throws
/// rigidtouch::Error for e outside [0, 1], remaining_impulses < 1, a row whose body index is out of
/// range or which names the same body (or static geometry) twice, or non-finite input. For tests,
/// comparisons and offline use; the haptic loop uses ImpulseSolver.
Eigen::VectorXd ReferenceImpulse(const ImpulseProblem& problem, double restitution,
                                 int remaining_impulses);

}  // namespace rigidtouch::contact
