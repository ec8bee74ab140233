// Sparse Cholesky factorisation of a symmetric positive definite system over 6 x 6 blocks (one
// block row per rigid body), A = L L^T.
//
// Only nodes joined by an edge couple. Analyse orders the nodes by minimum degree on the edge
// graph (a chain factors without fill-in; a 3-D lattice keeps the fill small) and numbers the
// factor's non-zero blocks; the caller then writes A into the diagonal blocks and the numbered
// below-diagonal blocks, by elimination position, and calls Factor, which overwrites them with L.
// Solve applies (L L^T)^-1. The kernels are fixed-size 6 x 6 loops; nothing allocates after
// Reserve.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace rigidtouch::dynamics {

using Mat6 = Eigen::Matrix<double, 6, 6>;
using Vec6 = Eigen::Matrix<double, 6, 1>;

/// An edge of the block graph for BlockCholesky::Analyse: nodes i < j packed as i << 32 | j.
inline std::uint64_t PackEdge(int i, int j) {
  return static_cast<std::uint64_t>(i) << 32 | static_cast<std::uint64_t>(j);
}

/// One elimination position of a factor L: its diagonal block, 1 / its diagonal, and the
/// below-diagonal blocks of its column (`count` of them) with their rows.
struct FactorColumn {
  const Mat6& diag;
  const Vec6& diag_inv;
  const int* row;
  const Mat6* off;
  int count;
};

namespace detail {

// y <- L^-1 y for a lower triangular 6 x 6 block
inline void ForwardSubstitute(const Mat6& L, const Vec6& inv, Vec6& y) {
#pragma GCC unroll 6
  for (int j = 0; j < 6; ++j) {
    double s = y(j);
#pragma GCC unroll 6
    for (int m = 0; m < j; ++m) s -= L(j, m) * y(m);
    y(j) = s * inv(j);
  }
}

// y <- L^-T y
inline void BackSubstitute(const Mat6& L, const Vec6& inv, Vec6& y) {
#pragma GCC unroll 6
  for (int j = 5; j >= 0; --j) {
    double s = y(j);
#pragma GCC unroll 6
    for (int m = j + 1; m < 6; ++m) s -= L(m, j) * y(m);
    y(j) = s * inv(j);
  }
}

}  // namespace detail

/// y <- (L L^T)^-1 y, by position, for a factor of n positions given column by column
/// (`column(k)` returns position k's FactorColumn), wherever it is stored; false unless the
/// result is finite.
template <class Columns>
bool SolveByColumns(int n, std::span<Vec6> y, const Columns& column) {
  for (int k = 0; k < n; ++k) {  // L z = y
    const FactorColumn c = column(k);
    detail::ForwardSubstitute(c.diag, c.diag_inv, y[k]);
    for (int e = 0; e < c.count; ++e) y[c.row[e]].noalias() -= c.off[e] * y[k];
  }
  for (int k = n - 1; k >= 0; --k) {  // L^T y = z
    const FactorColumn c = column(k);
    for (int e = 0; e < c.count; ++e) y[k].noalias() -= c.off[e].transpose() * y[c.row[e]];
    detail::BackSubstitute(c.diag, c.diag_inv, y[k]);
  }
  for (int k = 0; k < n; ++k) {
    if (!y[k].allFinite()) return false;
  }
  return true;
}

/// The structure, ordering and factor of one block-sparse SPD system, sized once by Reserve and
/// reused. Nodes are numbered 0..n-1 by the caller; blocks are stored by elimination position
/// pos[node].
struct BlockCholesky {
  int max_nodes = 0, max_edges = 0, max_blocks = 0;
  // per position: the diagonal block of A (lower triangle read), then of L; 1 / diag(L)
  std::vector<Mat6> diag;
  std::vector<Vec6> diag_inv;
  std::vector<int> pos;  // node -> elimination position
  // the factor's below-diagonal blocks, column by column (CSR over positions): rows ascending
  std::vector<int> col_start, col_row;
  std::vector<Mat6> off;    // (max_blocks) blocks of A below the diagonal, then of L
  std::vector<int> block;   // (max_nodes^2) block index of (i, j), i > j positions
  std::vector<char> adj;    // (max_nodes^2) elimination graph over nodes
  std::vector<int> degree;  // (max_nodes)
  std::vector<char> eliminated;
  // the edges and node count the analysis above was made for: reused while they are equal
  std::vector<std::uint64_t> analysed_edges;  // (max_edges)
  int analysed_nedges = -1, analysed_n = -1;

  /// Sizes every buffer: up to `max_nodes` nodes, `max_edges` edges and `max_blocks` non-zero
  /// blocks of L below the diagonal (original couplings plus fill-in).
  void Reserve(int max_nodes, int max_edges, int max_blocks);

  /// Orders n nodes by minimum degree on `edges` (PackEdge, sorted, unique; ties go to the lowest
  /// node, so the order is deterministic) and records the factor's non-zero blocks. Keeps the
  /// previous analysis if n and the edges are unchanged. False if n, the edges or the fill-in
  /// exceed the capacity (then no analysis is valid).
  bool Analyse(int n, std::span<const std::uint64_t> edges);

  /// The below-diagonal block at positions (i, j), i > j, which the analysis must have recorded.
  Mat6& Lower(int i, int j) { return off[block[static_cast<std::size_t>(i) * analysed_n + j]]; }

  /// Sets the analysed below-diagonal blocks to zero, before A is written into them.
  void ZeroOffDiagonal(int n);

  /// Factors A = L L^T in place (right-looking block Cholesky over the analysed structure); the
  /// factor stays in diag, diag_inv and off until A is written again. False unless A is
  /// positive definite (a non-positive pivot; then the factor is garbage).
  bool Factor(int n);

  /// y <- (L L^T)^-1 y, by position; false unless the result is finite.
  bool Solve(int n, std::span<Vec6> y) const;
};

}  // namespace rigidtouch::dynamics
