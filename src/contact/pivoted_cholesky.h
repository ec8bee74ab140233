// A rank-revealing, diagonally pivoted Cholesky factorisation of a symmetric positive
// semi-definite matrix, in place in a preallocated buffer (no allocation, no throw).
#pragma once

#include <Eigen/Core>

namespace rigidtouch::contact {

/// Diagonally pivoted Cholesky of the symmetric positive semi-definite top-left n x n block W of
/// `work` (full storage; rows and columns are swapped together, and `order` with them). Stops
/// when the largest remaining Schur-complement diagonal is <= threshold; returns the rank r. On
/// return the first r columns hold G, lower trapezoidal, with P W P^T ~= G G^T.
int PivotedCholesky(Eigen::MatrixXd& work, int n, Eigen::VectorXi& order, double threshold);

}  // namespace rigidtouch::contact
