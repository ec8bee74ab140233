// The reference impulse solver: Eq. 5 and Eq. 8 exactly, with a pseudo-inverse.
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
#include <span>

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

/// The impulse of ReferenceImpulse on preallocated buffers, for the haptic loop: Solve never
/// allocates or throws. Method: A = Jc M^-1 Jc^T, Jacobi-scaled to a unit diagonal, gets a
/// diagonally pivoted Cholesky factor truncated where the largest remaining pivot is at most
/// kReferencePinvThreshold, A ~= L L^T with L (c x r) of full column rank. Then
/// A^# = L^+T L^+, and with the Householder QR L = Q R (Q c x r), L^+ = R^-1 Q^T, so
///   A^# b = Q R^-T R^-1 Q^T b,
/// two triangular solves between two applications of Q. It agrees with the complete orthogonal
/// decomposition of ReferenceImpulse to rounding wherever the rank is clear (redundant rows are
/// exactly dependent; near-dependent ones may be ranked differently by the two thresholds).
class ReferenceSolver {
 public:
  /// Sizes every buffer for groups of up to `max_rows` rows and `max_bodies` bodies (memory:
  /// about max_rows * (max_rows + min(max_rows, 6 max_bodies)) doubles). Throws rigidtouch::Error
  /// if either is negative.
  ReferenceSolver(int max_rows, int max_bodies);

  /// Writes p = -(1 + e) A^# Jc v0 / remaining (Eq. 5, Eq. 8; N s, one per row) into `p` and
  /// returns true. Returns false, with p set to 0 where it has one entry per row, for e outside
  /// [0, 1], remaining_impulses < 1, p without one entry per row, more rows or bodies than the
  /// capacity, a row whose body index is out of range or which names the same body (or static
  /// geometry) twice, a negative inv_mass, non-finite input, or a non-finite result.
  bool Solve(const ImpulseProblem& problem, double restitution, int remaining_impulses,
             std::span<double> p) noexcept;

  /// Capacity in rows.
  int max_rows() const { return max_rows_; }
  /// Capacity in bodies.
  int max_bodies() const { return max_bodies_; }

 private:
  bool Valid(const ImpulseProblem& problem) const;
  int Factor(int c);                                   // A -> L (c x r) in l_; returns r
  void MinimumNormSolve(int c, int r);                 // x_ = A^# b_ from the factor
  void ApplyReflectors(int c, int r, bool transpose);  // t_ <- Q^T t_ or Q t_

  int max_rows_ = 0;
  int max_bodies_ = 0;
  Eigen::MatrixXd a_;       // (max_rows^2) A, then its pivoted Cholesky factor G
  Eigen::MatrixXd l_;       // (max_rows x max rank) L, then its Householder QR
  Eigen::VectorXi order_;   // pivot order of the Cholesky factor
  Eigen::VectorXd b_;       // Jc v0
  Eigen::VectorXd sqrt_d_;  // sqrt(A_jj), 0 for a row without effective mass
  Eigen::VectorXd tau_;     // Householder coefficients
  Eigen::VectorXd t_, x_;   // work vector, solution A^# b
};

}  // namespace rigidtouch::contact
