#include "dynamics/block_cholesky.h"

#include <algorithm>
#include <cmath>

namespace rigidtouch::dynamics {
namespace {

// --- 6 x 6 kernels (column-major, fixed size, unrolled: GCC leaves triangular loops rolled
// otherwise, measured at twice the instructions; no allocation) ---

// in-place lower Cholesky factor of a symmetric block (reads the lower triangle); inv gets
// 1 / L(j, j). False unless positive definite.
bool Cholesky6(Mat6& A, Vec6& inv) {
#pragma GCC unroll 6
  for (int j = 0; j < 6; ++j) {
    double d = A(j, j);
#pragma GCC unroll 6
    for (int m = 0; m < j; ++m) d -= A(j, m) * A(j, m);
    if (!(d > 0.0)) return false;
    const double l = std::sqrt(d);
    A(j, j) = l;
    inv(j) = 1.0 / l;
#pragma GCC unroll 6
    for (int i = j + 1; i < 6; ++i) {
      double s = A(i, j);
#pragma GCC unroll 6
      for (int m = 0; m < j; ++m) s -= A(i, m) * A(j, m);
      A(i, j) = s * inv(j);
    }
  }
  return true;
}

// X <- X L^-T (L lower triangular): column c of X L^T = B is (B_c - sum_{m<c} X_m L(c,m)) / L(c,c)
void SolveRightTransposed(const Mat6& L, const Vec6& inv, Mat6& X) {
#pragma GCC unroll 6
  for (int c = 0; c < 6; ++c) {
    Vec6 x = X.col(c);  // accumulated in registers, stored once
#pragma GCC unroll 6
    for (int m = 0; m < c; ++m) x -= L(c, m) * X.col(m);
    X.col(c) = x * inv(c);
  }
}

// D -= L L^T on the lower triangle of a diagonal block, each column from its first even row so
// that whole SSE pairs are updated (the extra entries are above the diagonal, which nothing reads):
// 144 multiply-adds instead of the full product's 216
template <int kFirstRow>
[[gnu::always_inline]] inline void SubtractOuterColumn(Mat6& D, const Mat6& L, int j) {
  constexpr int kRows = 6 - kFirstRow;
  Eigen::Matrix<double, kRows, 1> d = D.col(j).tail<kRows>();  // in registers, stored once
#pragma GCC unroll 6
  for (int m = 0; m < 6; ++m) d -= L(j, m) * L.col(m).tail<kRows>();
  D.col(j).tail<kRows>() = d;
}
void SubtractOuterLower(Mat6& D, const Mat6& L) {
  SubtractOuterColumn<0>(D, L, 0);
  SubtractOuterColumn<0>(D, L, 1);
  SubtractOuterColumn<2>(D, L, 2);
  SubtractOuterColumn<2>(D, L, 3);
  SubtractOuterColumn<4>(D, L, 4);
  SubtractOuterColumn<4>(D, L, 5);
}

}  // namespace

void BlockCholesky::Reserve(int max_nodes_in, int max_edges_in, int max_blocks_in) {
  max_nodes = max_nodes_in;
  max_edges = max_edges_in;
  max_blocks = max_blocks_in;
  const auto n2 = static_cast<std::size_t>(max_nodes) * max_nodes;
  diag.assign(max_nodes, Mat6::Zero());
  diag_inv.assign(max_nodes, Vec6::Zero());
  pos.assign(max_nodes, 0);
  col_start.assign(max_nodes + 1, 0);
  col_row.assign(max_blocks, 0);
  off.assign(max_blocks, Mat6::Zero());
  block.assign(n2, -1);
  adj.assign(n2, 0);
  degree.assign(max_nodes, 0);
  eliminated.assign(max_nodes, 0);
  analysed_edges.assign(max_edges, 0);
  analysed_nedges = analysed_n = -1;
}

bool BlockCholesky::Analyse(int n, std::span<const std::uint64_t> edges) {
  const int nedges = static_cast<int>(edges.size());
  if (n == analysed_n && nedges == analysed_nedges &&
      std::equal(edges.begin(), edges.end(), analysed_edges.begin())) {
    return true;
  }
  analysed_n = -1;  // stays invalid if the analysis fails
  if (n > max_nodes || nedges > max_edges) return false;
  auto adjacent = [&](int i, int j) -> char& { return adj[static_cast<std::size_t>(i) * n + j]; };
  std::fill(adj.begin(), adj.begin() + static_cast<std::ptrdiff_t>(n) * n, 0);
  std::fill(degree.begin(), degree.begin() + n, 0);
  std::fill(eliminated.begin(), eliminated.begin() + n, 0);
  for (const std::uint64_t edge : edges) {
    const auto a = static_cast<int>(edge >> 32), b = static_cast<int>(edge & 0xffffffffU);
    if (adjacent(a, b)) continue;
    adjacent(a, b) = adjacent(b, a) = 1;
    ++degree[a];
    ++degree[b];
  }
  int nnz = 0;
  for (int p = 0; p < n; ++p) {
    int v = -1;
    for (int i = 0; i < n; ++i) {
      if (!eliminated[i] && (v < 0 || degree[i] < degree[v])) v = i;
    }
    pos[v] = p;
    eliminated[v] = 1;
    col_start[p] = nnz;
    for (int i = 0; i < n; ++i) {
      if (!adjacent(v, i) || eliminated[i]) continue;
      if (nnz == max_blocks) return false;
      col_row[nnz++] = i;  // a node for now; a position once every node has one
      --degree[i];
    }
    // eliminating v connects its remaining neighbours (the fill-in)
    for (int k = col_start[p]; k < nnz; ++k) {
      for (int l = k + 1; l < nnz; ++l) {
        const int i = col_row[k], j = col_row[l];
        if (adjacent(i, j)) continue;
        adjacent(i, j) = adjacent(j, i) = 1;
        ++degree[i];
        ++degree[j];
      }
    }
  }
  col_start[n] = nnz;
  for (int p = 0; p < n; ++p) {
    const auto begin = col_row.begin() + col_start[p];
    const auto end = col_row.begin() + col_start[p + 1];
    for (auto it = begin; it != end; ++it) *it = pos[*it];
    std::sort(begin, end);
    for (int k = col_start[p]; k < col_start[p + 1]; ++k) {
      block[static_cast<std::size_t>(col_row[k]) * n + p] = k;
    }
  }
  std::copy(edges.begin(), edges.end(), analysed_edges.begin());
  analysed_nedges = nedges;
  analysed_n = n;
  return true;
}

void BlockCholesky::ZeroOffDiagonal(int n) {
  for (int e = 0; e < col_start[n]; ++e) off[e].setZero();
}

bool BlockCholesky::Factor(int n) {
  for (int k = 0; k < n; ++k) {
    if (!Cholesky6(diag[k], diag_inv[k])) return false;
    const int begin = col_start[k], end = col_start[k + 1];
    for (int e = begin; e < end; ++e) SolveRightTransposed(diag[k], diag_inv[k], off[e]);
    // Schur complement: A_ij -= L_ik L_jk^T for every pair of rows i >= j of column k
    for (int e = begin; e < end; ++e) {
      const int i = col_row[e];
      const Mat6& Lik = off[e];
      SubtractOuterLower(diag[i], Lik);
      for (int f = begin; f < e; ++f) {
        const int j = col_row[f];
        off[block[static_cast<std::size_t>(i) * n + j]].noalias() -= Lik * off[f].transpose();
      }
    }
  }
  return true;
}

bool BlockCholesky::Solve(int n, std::span<Vec6> y) const {
  return SolveByColumns(n, y, [this](int k) {
    return FactorColumn{diag[k], diag_inv[k], col_row.data() + col_start[k],
                        off.data() + col_start[k], col_start[k + 1] - col_start[k]};
  });
}

}  // namespace rigidtouch::dynamics
