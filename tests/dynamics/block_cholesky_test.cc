// The sparse block Cholesky over 6 x 6 blocks against Eigen's dense LLT of the same matrix, on
// random SPD block systems: a chain, a 3-D lattice and random sparsity. The systems are sums of
// random 6 x 12 edge terms G^T G plus an SPD diagonal block per node (condition numbers of order
// 1e2 to 1e3), so the factors agree to rounding: tolerance 1e-12 relative to the largest entry of
// L for the factor (the Cholesky factor of an SPD matrix is unique), 1e-12 relative to |x| for
// the solution. An indefinite system must make Factor report failure.
#include "dynamics/block_cholesky.h"

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <utility>
#include <vector>

namespace rigidtouch::dynamics {
namespace {

constexpr double kFactorTol = 1e-12;
constexpr double kSolveTol = 1e-12;

using Edges = std::vector<std::pair<int, int>>;

// the edges as Analyse takes them: packed, smaller node first, sorted and unique
std::vector<std::uint64_t> Packed(const Edges& edges) {
  std::vector<std::uint64_t> packed;
  for (auto [i, j] : edges) packed.push_back(PackEdge(std::min(i, j), std::max(i, j)));
  std::sort(packed.begin(), packed.end());
  packed.erase(std::unique(packed.begin(), packed.end()), packed.end());
  return packed;
}

// a random SPD matrix over n nodes of 6 x 6 blocks, coupled only along the edges
Eigen::MatrixXd RandomSpd(int n, const Edges& edges, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  auto random6 = [&] { return Mat6::NullaryExpr([&] { return u(rng); }); };
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(6 * n, 6 * n);
  for (int i = 0; i < n; ++i) {
    const Mat6 R = random6();
    A.block<6, 6>(6 * i, 6 * i) = R * R.transpose() + Mat6::Identity();
  }
  for (auto [i, j] : edges) {
    Eigen::Matrix<double, 6, 12> G;
    G << random6(), random6();
    const Eigen::Matrix<double, 12, 12> GtG = G.transpose() * G;
    A.block<6, 6>(6 * i, 6 * i) += GtG.topLeftCorner<6, 6>();
    A.block<6, 6>(6 * j, 6 * j) += GtG.bottomRightCorner<6, 6>();
    A.block<6, 6>(6 * i, 6 * j) += GtG.topRightCorner<6, 6>();
    A.block<6, 6>(6 * j, 6 * i) += GtG.bottomLeftCorner<6, 6>();
  }
  return A;
}

// writes the dense A (node order) into the factor's blocks (position order)
void Load(BlockCholesky& f, int n, const Eigen::MatrixXd& A) {
  f.ZeroOffDiagonal(n);
  for (int i = 0; i < n; ++i) {
    f.diag[f.pos[i]] = A.block<6, 6>(6 * i, 6 * i);
    for (int j = 0; j < n; ++j) {
      const int pi = f.pos[i], pj = f.pos[j];
      if (pi <= pj || A.block<6, 6>(6 * i, 6 * j).isZero(0.0)) continue;
      f.Lower(pi, pj) = A.block<6, 6>(6 * i, 6 * j);
    }
  }
}

// A permuted to elimination order: P A P^T with node i at position pos[i]
Eigen::MatrixXd Permuted(const BlockCholesky& f, int n, const Eigen::MatrixXd& A) {
  Eigen::MatrixXd B(6 * n, 6 * n);
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      B.block<6, 6>(6 * f.pos[i], 6 * f.pos[j]) = A.block<6, 6>(6 * i, 6 * j);
    }
  }
  return B;
}

// the factor as a dense lower-triangular matrix, by position
Eigen::MatrixXd DenseFactor(const BlockCholesky& f, int n) {
  Eigen::MatrixXd L = Eigen::MatrixXd::Zero(6 * n, 6 * n);
  for (int k = 0; k < n; ++k) {
    L.block<6, 6>(6 * k, 6 * k) = f.diag[k].triangularView<Eigen::Lower>();
    for (int e = f.col_start[k]; e < f.col_start[k + 1]; ++e) {
      L.block<6, 6>(6 * f.col_row[e], 6 * k) = f.off[e];
    }
  }
  return L;
}

// factors and solves a random system on the graph and compares with Eigen's LLT
void CheckAgainstLlt(int n, const Edges& edges, unsigned seed, int max_blocks) {
  std::mt19937 rng(seed);
  const Eigen::MatrixXd A = RandomSpd(n, edges, rng);
  const std::vector<std::uint64_t> packed = Packed(edges);
  BlockCholesky f;
  f.Reserve(n, static_cast<int>(packed.size()), max_blocks);
  ASSERT_TRUE(f.Analyse(n, packed));
  Load(f, n, A);
  ASSERT_TRUE(f.Factor(n));

  const Eigen::LLT<Eigen::MatrixXd> llt(Permuted(f, n, A));
  ASSERT_EQ(llt.info(), Eigen::Success);
  const Eigen::MatrixXd L_ref = llt.matrixL();
  const Eigen::MatrixXd L = DenseFactor(f, n);
  const double l_max = L_ref.cwiseAbs().maxCoeff();
  EXPECT_LE((L - L_ref).cwiseAbs().maxCoeff(), kFactorTol * l_max) << "seed " << seed;
  // blocks outside the analysed structure stay zero in the exact factor too
  for (int k = 0; k < n; ++k) {
    for (int e = f.col_start[k]; e < f.col_start[k + 1]; ++e) EXPECT_GT(f.col_row[e], k);
  }

  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const Eigen::VectorXd b = Eigen::VectorXd::NullaryExpr(6 * n, [&] { return u(rng); });
  const Eigen::VectorXd x_ref = A.llt().solve(b);
  std::vector<Vec6> y(n);
  for (int i = 0; i < n; ++i) y[f.pos[i]] = b.segment<6>(6 * i);
  ASSERT_TRUE(f.Solve(n, y));
  Eigen::VectorXd x(6 * n);
  for (int i = 0; i < n; ++i) x.segment<6>(6 * i) = y[f.pos[i]];
  EXPECT_LE((x - x_ref).norm(), kSolveTol * x_ref.norm()) << "seed " << seed;
}

Edges Chain(int n) {
  Edges edges;
  for (int i = 0; i + 1 < n; ++i) edges.emplace_back(i, i + 1);
  return edges;
}

Edges Lattice(int nx, int ny, int nz) {
  auto id = [&](int x, int y, int z) { return (z * ny + y) * nx + x; };
  Edges edges;
  for (int z = 0; z < nz; ++z) {
    for (int y = 0; y < ny; ++y) {
      for (int x = 0; x < nx; ++x) {
        if (x + 1 < nx) edges.emplace_back(id(x, y, z), id(x + 1, y, z));
        if (y + 1 < ny) edges.emplace_back(id(x, y, z), id(x, y + 1, z));
        if (z + 1 < nz) edges.emplace_back(id(x, y, z), id(x, y, z + 1));
      }
    }
  }
  return edges;
}

int Full(int n) {
  return n * (n - 1) / 2;
}

TEST(BlockCholesky, ChainMatchesLltWithoutFillIn) {
  constexpr int kNodes = 20;
  for (unsigned seed = 1; seed <= 5; ++seed) CheckAgainstLlt(kNodes, Chain(kNodes), seed, kNodes);
  // a chain eliminated from its ends needs exactly one block below each diagonal but the last
  BlockCholesky f;
  f.Reserve(kNodes, kNodes, kNodes);
  ASSERT_TRUE(f.Analyse(kNodes, Packed(Chain(kNodes))));
  EXPECT_EQ(f.col_start[kNodes], kNodes - 1);
}

TEST(BlockCholesky, LatticeMatchesLlt) {
  for (unsigned seed = 1; seed <= 3; ++seed) {
    CheckAgainstLlt(27, Lattice(3, 3, 3), seed, Full(27));
    CheckAgainstLlt(64, Lattice(4, 4, 4), seed, Full(64));
  }
}

TEST(BlockCholesky, RandomSparsityMatchesLlt) {
  std::mt19937 rng(7);
  for (unsigned seed = 1; seed <= 20; ++seed) {
    const int n = 2 + static_cast<int>(rng() % 30);
    std::bernoulli_distribution coupled(0.15);
    Edges edges;
    for (int i = 0; i < n; ++i) {
      for (int j = i + 1; j < n; ++j) {
        if (coupled(rng)) edges.emplace_back(j, i);  // either order: Analyse takes them packed
      }
    }
    CheckAgainstLlt(n, edges, seed, Full(n));
  }
}

TEST(BlockCholesky, SingleNodeAndNoEdges) {
  CheckAgainstLlt(1, {}, 3, 0);
  CheckAgainstLlt(5, {}, 4, 0);  // five uncoupled blocks
}

TEST(BlockCholesky, IndefiniteSystemFails) {
  // each diagonal block is positive definite, but the coupling makes the whole indefinite:
  // [[I, 2I], [2I, I]] has eigenvalues 3 and -1, so the second pivot block, I - 4I, fails
  const Edges edges = {{0, 1}};
  BlockCholesky f;
  f.Reserve(2, 1, 1);
  ASSERT_TRUE(f.Analyse(2, Packed(edges)));
  Eigen::MatrixXd A(12, 12);
  A << Mat6::Identity(), 2.0 * Mat6::Identity(), 2.0 * Mat6::Identity(), Mat6::Identity();
  Load(f, 2, A);
  EXPECT_FALSE(f.Factor(2));
  // an indefinite diagonal block fails at once
  A.topLeftCorner<6, 6>()(3, 3) = -1.0;
  Load(f, 2, A);
  EXPECT_FALSE(f.Factor(2));
  // a semi-definite (singular) one too: a zero pivot is not positive
  A.topLeftCorner<6, 6>()(3, 3) = 0.0;
  Load(f, 2, A);
  EXPECT_FALSE(f.Factor(2));
}

TEST(BlockCholesky, SolveRejectsNonFiniteResults) {
  const Edges edges = Chain(3);
  std::mt19937 rng(5);
  const Eigen::MatrixXd A = RandomSpd(3, edges, rng);
  BlockCholesky f;
  f.Reserve(3, 2, 3);
  ASSERT_TRUE(f.Analyse(3, Packed(edges)));
  Load(f, 3, A);
  ASSERT_TRUE(f.Factor(3));
  std::vector<Vec6> y(3, Vec6::Ones());
  y[1](2) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(f.Solve(3, y));
}

TEST(BlockCholesky, AnalyseRespectsCapacityAndReusesItsAnalysis) {
  // a complete graph on five nodes fills every block below the diagonal: 10 blocks
  Edges edges;
  for (int i = 0; i < 5; ++i) {
    for (int j = i + 1; j < 5; ++j) edges.emplace_back(i, j);
  }
  BlockCholesky f;
  f.Reserve(5, 10, 9);
  EXPECT_FALSE(f.Analyse(5, Packed(edges)));
  f.Reserve(5, 10, 10);
  ASSERT_TRUE(f.Analyse(5, Packed(edges)));
  EXPECT_EQ(f.col_start[5], 10);
  EXPECT_FALSE(f.Analyse(6, Packed(edges)));  // more nodes than reserved
  // the failed call invalidated the analysis; the same graph again is analysed afresh, to the
  // same structure
  ASSERT_TRUE(f.Analyse(5, Packed(edges)));
  EXPECT_EQ(f.analysed_n, 5);
  EXPECT_EQ(f.col_start[5], 10);
  // minimum degree with ties to the lowest node: a star's leaves go first, until the centre's
  // degree falls to that of the last leaf and the centre, the lower node, wins the tie
  const Edges star = {{2, 0}, {2, 1}, {2, 3}, {2, 4}};
  ASSERT_TRUE(f.Analyse(5, Packed(star)));
  EXPECT_EQ(f.pos[0], 0);
  EXPECT_EQ(f.pos[1], 1);
  EXPECT_EQ(f.pos[3], 2);
  EXPECT_EQ(f.pos[2], 3);
  EXPECT_EQ(f.pos[4], 4);
  EXPECT_EQ(f.col_start[5], 4);  // no fill-in
}

}  // namespace
}  // namespace rigidtouch::dynamics
