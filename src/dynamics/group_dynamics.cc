#include "dynamics/group_dynamics.h"

#include <algorithm>
#include <bit>
#include <cmath>

#include "dynamics/rigid_body.h"

namespace rigidtouch::dynamics {
namespace {

constexpr int kMaxPasses = 4;
// the lagged factorisation's refinement: at most this many corrections, until the velocity error
// in the kinetic-energy norm is below this fraction of the step's momentum scale
constexpr int kMaxRefinements = 2;
constexpr double kRefineTolerance = 1e-10;
// after a failed refinement the kept factor is not tried for 1, 3, 7, ... solves, at most this
// many: on the stack a failed try costs about 60% of a factorised solve
constexpr int kMaxBackoff = 63;

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

// y <- L^-1 y
void ForwardSubstitute(const Mat6& L, const Vec6& inv, Vec6& y) {
#pragma GCC unroll 6
  for (int j = 0; j < 6; ++j) {
    double s = y(j);
#pragma GCC unroll 6
    for (int m = 0; m < j; ++m) s -= L(j, m) * y(m);
    y(j) = s * inv(j);
  }
}

// y <- L^-T y
void BackSubstitute(const Mat6& L, const Vec6& inv, Vec6& y) {
#pragma GCC unroll 6
  for (int j = 5; j >= 0; --j) {
    double s = y(j);
#pragma GCC unroll 6
    for (int m = j + 1; m < 6; ++m) s -= L(m, j) * y(m);
    y(j) = s * inv(j);
  }
}

// --- the group's block structure ---

// the group's structure: the pairs of group slots that share a contact (smaller slot in the high
// half), sorted and unique. Equal lists give equal analyses, so a group whose bodies keep touching
// the same neighbours is analysed once, whatever order its contacts come in and whichever body of
// a manifold is its reference.
void StructureOf(GroupSolverScratch& s, std::span<const int> slot,
                 std::span<const ImplicitContact> contacts) {
  s.npairs = 0;
  int last_a = -1, last_b = -1;  // the bodies of the previous two-body contact
  for (const ImplicitContact& c : contacts) {
    if (c.body_a < 0 || c.body_b < 0) continue;
    if (c.body_a == last_a && c.body_b == last_b) continue;  // the manifold's next point
    last_a = c.body_a;
    last_b = c.body_b;
    const auto a = static_cast<std::uint64_t>(std::min(slot[c.body_a], slot[c.body_b]));
    const auto b = static_cast<std::uint64_t>(std::max(slot[c.body_a], slot[c.body_b]));
    if (a != b) s.pairs[s.npairs++] = a << 32 | b;
  }
  const auto begin = s.pairs.begin(), end = begin + s.npairs;
  std::sort(begin, end);
  s.npairs = static_cast<int>(std::unique(begin, end) - begin);
}

// orders the group's bodies by minimum degree on the graph of bodies that share a contact
// (ties: lowest slot, so the order is deterministic), records the factor's non-zero blocks
// (original couplings and fill-in) column by column, and numbers them. False if the fill-in
// would exceed the scratch.
bool Analyse(GroupSolverScratch& s, int nb) {
  auto adj = [&](int i, int j) -> char& { return s.adj[static_cast<std::size_t>(i) * nb + j]; };
  std::fill(s.adj.begin(), s.adj.begin() + static_cast<std::ptrdiff_t>(nb) * nb, 0);
  std::fill(s.degree.begin(), s.degree.begin() + nb, 0);
  std::fill(s.eliminated.begin(), s.eliminated.begin() + nb, 0);
  for (int e = 0; e < s.npairs; ++e) {
    const auto a = static_cast<int>(s.pairs[e] >> 32),
               b = static_cast<int>(s.pairs[e] & 0xffffffffU);
    if (adj(a, b)) continue;
    adj(a, b) = adj(b, a) = 1;
    ++s.degree[a];
    ++s.degree[b];
  }
  int nnz = 0;
  for (int p = 0; p < nb; ++p) {
    int v = -1;
    for (int i = 0; i < nb; ++i) {
      if (!s.eliminated[i] && (v < 0 || s.degree[i] < s.degree[v])) v = i;
    }
    s.pos[v] = p;
    s.eliminated[v] = 1;
    s.col_start[p] = nnz;
    for (int i = 0; i < nb; ++i) {
      if (!adj(v, i) || s.eliminated[i]) continue;
      if (nnz == s.max_blocks) return false;
      s.col_row[nnz++] = i;  // a slot for now; a position once every body has one
      --s.degree[i];
    }
    // eliminating v connects its remaining neighbours (the fill-in)
    for (int k = s.col_start[p]; k < nnz; ++k) {
      for (int l = k + 1; l < nnz; ++l) {
        const int i = s.col_row[k], j = s.col_row[l];
        if (adj(i, j)) continue;
        adj(i, j) = adj(j, i) = 1;
        ++s.degree[i];
        ++s.degree[j];
      }
    }
  }
  s.col_start[nb] = nnz;
  for (int p = 0; p < nb; ++p) {
    const auto begin = s.col_row.begin() + s.col_start[p];
    const auto end = s.col_row.begin() + s.col_start[p + 1];
    for (auto it = begin; it != end; ++it) *it = s.pos[*it];
    std::sort(begin, end);
    for (int k = s.col_start[p]; k < s.col_start[p + 1]; ++k) {
      s.block[static_cast<std::size_t>(s.col_row[k]) * nb + p] = k;
    }
  }
  return true;
}

// --- assembly ---

// A += sum_points J_p^T C J_q for the point Jacobians J_r = [I, -[r]x] and one 3 x 3
// C = ct I + dc n n^T (ct = c_t for a sticking contact, t1 t1^T + t2 t2^T = I - n n^T; dc =
// c_n - ct), from the points' moments P = sum p, Q = sum q, S = sum p q^T:
//   [[count C, -C [Q]x], [[P]x C, ct ((tr S) I - S^T) + dc [n]x S [n]x^T]]
// with C [Q]x = ct [Q]x + dc n (n x Q)^T and [P]x C = ct [P]x + dc (P x n) n^T
// (-[p]x [q]x = (p.q) I - q p^T and -[p]x n n^T [q]x = [n]x p q^T [n]x^T), so a manifold of k
// points costs k small outer products and one block update instead of 3 k rank-1 updates.
// kDiagonal: A is a diagonal block, of which the factorisation reads only the lower triangle, so
// only that is updated.
template <bool kDiagonal>
void AddPatchBlock(Mat6& A, int count, double ct, double dc, const Vec3& n, const Vec3& P,
                   const Vec3& Q, const Mat3& S) {
  // written out in scalars: Eigen's 3-vector cross products on matrix rows cost twice as much
  const double nx = n.x(), ny = n.y(), nz = n.z();
  const double kct = count * ct, kdc = count * dc;
  // top left: count C
  const double c_nn[3][3] = {
      {nx * nx, nx * ny, nx * nz}, {ny * nx, ny * ny, ny * nz}, {nz * nx, nz * ny, nz * nz}};
  for (int j = 0; j < 3; ++j) {
    for (int i = kDiagonal ? j : 0; i < 3; ++i) A(i, j) += kdc * c_nn[i][j];
    A(j, j) += kct;
  }
  // bottom left: [P]x C = ct [P]x + dc (P x n) n^T
  const double pn[3] = {dc * (P.y() * nz - P.z() * ny), dc * (P.z() * nx - P.x() * nz),
                        dc * (P.x() * ny - P.y() * nx)};
  for (int j = 0; j < 3; ++j) {
    for (int i = 0; i < 3; ++i) A(3 + i, j) += pn[i] * n(j);
  }
  A(3, 1) -= ct * P.z();
  A(3, 2) += ct * P.y();
  A(4, 0) += ct * P.z();
  A(4, 2) -= ct * P.x();
  A(5, 0) -= ct * P.y();
  A(5, 1) += ct * P.x();
  // top right: -C [Q]x = -ct [Q]x - dc n (n x Q)^T (a diagonal block's upper triangle is unread)
  if constexpr (!kDiagonal) {
    const double nq[3] = {dc * (ny * Q.z() - nz * Q.y()), dc * (nz * Q.x() - nx * Q.z()),
                          dc * (nx * Q.y() - ny * Q.x())};
    for (int j = 0; j < 3; ++j) {
      for (int i = 0; i < 3; ++i) A(i, 3 + j) -= n(i) * nq[j];
    }
    A(0, 4) += ct * Q.z();
    A(0, 5) -= ct * Q.y();
    A(1, 3) -= ct * Q.z();
    A(1, 5) += ct * Q.x();
    A(2, 3) += ct * Q.y();
    A(2, 4) -= ct * Q.x();
  }
  // bottom right: ct ((tr S) I - S^T) + dc [n]x S [n]x^T; U = [n]x S a column at a time, then
  // row i of U [n]x^T is (n x U_i)^T
  double U[3][3];
  for (int j = 0; j < 3; ++j) {
    U[0][j] = ny * S(2, j) - nz * S(1, j);
    U[1][j] = nz * S(0, j) - nx * S(2, j);
    U[2][j] = nx * S(1, j) - ny * S(0, j);
  }
  const double tr = ct * (S(0, 0) + S(1, 1) + S(2, 2));
  for (int i = 0; i < 3; ++i) {
    const double nsn[3] = {ny * U[i][2] - nz * U[i][1], nz * U[i][0] - nx * U[i][2],
                           nx * U[i][1] - ny * U[i][0]};
    for (int j = 0; j <= (kDiagonal ? i : 2); ++j) A(3 + i, 3 + j) += dc * nsn[j] - ct * S(j, i);
    A(3 + i, 3 + i) += tr;
  }
}

// true if contacts i and j share their blocks' assembly: same bodies, normal and coefficients
bool SamePatch(const ImplicitContact& i, const ImplicitContact& j) {
  return i.body_a == j.body_a && i.body_b == j.body_b && i.n_W == j.n_W &&
         i.c_n_Ns_per_m == j.c_n_Ns_per_m && i.stick == j.stick &&
         (!i.stick || i.c_t_Ns_per_m == j.c_t_Ns_per_m);
}

// adds contacts [begin, end) (one patch, all active) to the assembled system:
// h sum c J^T d d^T J to the blocks, h sum phi J^T d to the right-hand side. The points' moments
// are summed once, about a's centre of mass (b's if a is static): with d = x_a - x_b, b's offsets
// are r_b = r_a + d, so P_b = P_a + k d, S_ab = S_aa + P_a d^T, S_bb = S_ab + d P_b^T and b's
// torque is -(T_a + d x F) for the total force F.
void AssemblePatch(GroupSolverScratch& s, const Data& data, std::span<const int> slot,
                   std::span<const ImplicitContact> contacts, int begin, int end, double h,
                   int nb) {
  const ImplicitContact& first = contacts[begin];
  const int pa = first.body_a >= 0 ? s.pos[slot[first.body_a]] : -1;
  const int pb = first.body_b >= 0 ? s.pos[slot[first.body_b]] : -1;
  const Vec3& origin = data.bodies[pa >= 0 ? first.body_a : first.body_b].x_W;
  Vec3 F = Vec3::Zero(), T = Vec3::Zero(), P = Vec3::Zero();
  double sxx = 0.0, syy = 0.0, szz = 0.0, sxy = 0.0, sxz = 0.0, syz = 0.0;  // S, symmetric
  for (int k = begin; k < end; ++k) {
    const ImplicitContact& c = contacts[k];
    Vec3 f = c.phi_n_N * c.n_W;
    if (c.stick) f += c.phi_t_W;
    const Vec3 r = c.p_W - origin;
    F += f;
    T += r.cross(f);
    P += r;
    sxx += r.x() * r.x();
    syy += r.y() * r.y();
    szz += r.z() * r.z();
    sxy += r.x() * r.y();
    sxz += r.x() * r.z();
    syz += r.y() * r.z();
  }
  F *= h;
  T *= h;
  Mat3 S;
  S << sxx, sxy, sxz, sxy, syy, syz, sxz, syz, szz;
  const int count = end - begin;
  const Vec3& n = first.n_W;
  const double ct = first.stick ? h * first.c_t_Ns_per_m : 0.0;
  const double dc = h * first.c_n_Ns_per_m - ct;
  if (pa < 0 || pb < 0) {  // against the static world: one block, moments about its own centre
    const int p = pa >= 0 ? pa : pb;
    const double sign = pa >= 0 ? 1.0 : -1.0;
    s.b[p].head<3>() += sign * F;
    s.b[p].tail<3>() += sign * T;
    AddPatchBlock<true>(s.diag_A[p], count, ct, dc, n, P, P, S);
    return;
  }
  const Vec3 d = origin - data.bodies[first.body_b].x_W;
  const Vec3 Pb = P + count * d;
  const Mat3 Sab = S + P * d.transpose();
  const Mat3 Sbb = Sab + d * Pb.transpose();
  s.b[pa].head<3>() += F;
  s.b[pa].tail<3>() += T;
  s.b[pb].head<3>() -= F;
  s.b[pb].tail<3>() -= T + d.cross(F);
  AddPatchBlock<true>(s.diag_A[pa], count, ct, dc, n, P, P, S);
  AddPatchBlock<true>(s.diag_A[pb], count, ct, dc, n, Pb, Pb, Sbb);
  // the coupling H_ab = -h sum J_a^T C J_b; only the lower block (larger position first) is
  // stored. Both points on one body: J = J_a - J_b adds both couplings to the diagonal.
  if (pa == pb) {
    AddPatchBlock<true>(s.diag_A[pa], count, -ct, -dc, n, P, Pb, Sab);
    AddPatchBlock<true>(s.diag_A[pa], count, -ct, -dc, n, Pb, P, Sab.transpose());
  } else if (pa > pb) {
    AddPatchBlock<false>(s.off_A[s.block[static_cast<std::size_t>(pa) * nb + pb]], count, -ct, -dc,
                         n, P, Pb, Sab);
  } else {
    AddPatchBlock<false>(s.off_A[s.block[static_cast<std::size_t>(pb) * nb + pa]], count, -ct, -dc,
                         n, Pb, P, Sab.transpose());
  }
}

// factors the assembled blocks in place (right-looking block Cholesky over the analysed
// structure): the factor stays in diag_A, diag_inv and off_A until the next assembly
bool Factor(GroupSolverScratch& s, int nb) {
  for (int k = 0; k < nb; ++k) {
    if (!Cholesky6(s.diag_A[k], s.diag_inv[k])) return false;
    const int begin = s.col_start[k], end = s.col_start[k + 1];
    for (int e = begin; e < end; ++e) SolveRightTransposed(s.diag_A[k], s.diag_inv[k], s.off_A[e]);
    // Schur complement: A_ij -= L_ik L_jk^T for every pair of rows i >= j of column k
    for (int e = begin; e < end; ++e) {
      const int i = s.col_row[e];
      const Mat6& Lik = s.off_A[e];
      SubtractOuterLower(s.diag_A[i], Lik);
      for (int f = begin; f < e; ++f) {
        const int j = s.col_row[f];
        s.off_A[s.block[static_cast<std::size_t>(i) * nb + j]].noalias() -=
            Lik * s.off_A[f].transpose();
      }
    }
  }
  return true;
}

// y <- (L L^T)^-1 y with the factor, by position; false unless the result is finite
bool Substitute(const GroupSolverScratch& s, int nb, std::vector<Vec6>& y) {
  for (int k = 0; k < nb; ++k) {  // L z = y
    ForwardSubstitute(s.diag_A[k], s.diag_inv[k], y[k]);
    for (int e = s.col_start[k]; e < s.col_start[k + 1]; ++e) {
      y[s.col_row[e]].noalias() -= s.off_A[e] * y[k];
    }
  }
  for (int k = nb - 1; k >= 0; --k) {  // L^T y = z
    for (int e = s.col_start[k]; e < s.col_start[k + 1]; ++e) {
      y[k].noalias() -= s.off_A[e].transpose() * y[s.col_row[e]];
    }
    BackSubstitute(s.diag_A[k], s.diag_inv[k], y[k]);
  }
  for (int k = 0; k < nb; ++k) {
    if (!y[k].allFinite()) return false;
  }
  return true;
}

// the active contacts' patches (consecutive contacts that SamePatch joins) into s.patch_range,
// [begin, end) each; dropped contacts may lie between two patches
void PartitionPatches(GroupSolverScratch& s, std::span<const ImplicitContact> contacts) {
  const int nc = static_cast<int>(contacts.size());
  s.npatch = 0;
  for (int begin = 0; begin < nc;) {
    int end = begin + 1;
    if (!contacts[begin].active) {
      begin = end;
      continue;
    }
    while (end < nc && contacts[end].active && SamePatch(contacts[begin], contacts[end])) ++end;
    s.patch_range[2 * s.npatch] = begin;
    s.patch_range[2 * s.npatch + 1] = end;
    ++s.npatch;
    begin = end;
  }
}

// assembles M + h sum c J^T J and M v + h F + h sum phi J^T over the active contacts, a patch
// at a time
void Assemble(const Model& model, const Data& data, std::span<const int> bodies,
              std::span<const int> slot, std::span<const ImplicitContact> contacts,
              std::span<const Vec3> force_W, std::span<const Vec3> torque_W,
              GroupSolverScratch& s) {
  const double h = model.timestep_s;
  const int nb = static_cast<int>(bodies.size());
  for (int k = 0; k < nb; ++k) {
    const int i = bodies[k];
    const BodyModel& bm = model.bodies[i];
    const BodyState& st = data.bodies[i];
    const int p = s.pos[k];
    const Mat3 I = WorldInertia(bm, st);
    Mat6& D = s.diag_A[p];
    D.setZero();
    D.topLeftCorner<3, 3>().diagonal().setConstant(bm.mass_kg);
    D.bottomRightCorner<3, 3>() = I;
    s.b[p] << bm.mass_kg * st.v_W + h * force_W[i], I * st.w_W + h * torque_W[i];
  }
  for (int e = 0; e < s.col_start[nb]; ++e) s.off_A[e].setZero();
  PartitionPatches(s, contacts);
  for (int q = 0; q < s.npatch; ++q) {
    AssemblePatch(s, data, slot, contacts, s.patch_range[2 * q], s.patch_range[2 * q + 1], h, nb);
  }
}

// the forces of patch [begin, end) at the velocities s.x. With r = p - x_a and d = x_a - x_b, a
// point's relative velocity is (v_a - v_b - w_b x d) + (w_a - w_b) x r: one cross product per
// point. Returns true if a normal force would pull. `may_drop`: such a contact is taken out
// (active = false, no force), so the system is solved again without it. kAccumulate: the patch's
// impulse over the step, h sum J^T f, is added to s.b (the residual of the momentum balance).
template <bool kAccumulate>
bool PatchForces(GroupSolverScratch& s, const Data& data, std::span<const int> slot,
                 std::span<ImplicitContact> contacts, int begin, int end, bool may_drop, double h) {
  const ImplicitContact& first = contacts[begin];
  const bool has_a = first.body_a >= 0, has_b = first.body_b >= 0;
  const int pa = has_a ? s.pos[slot[first.body_a]] : -1;
  const int pb = has_b ? s.pos[slot[first.body_b]] : -1;
  const Vec3& origin = data.bodies[has_a ? first.body_a : first.body_b].x_W;
  Vec3 d = Vec3::Zero();  // x_a - x_b
  Vec3 v0 = Vec3::Zero(), w = Vec3::Zero();
  if (has_a) {
    const Vec6& x = s.x[pa];
    v0 += x.head<3>();
    w += x.tail<3>();
  }
  if (has_b) {
    const Vec6& x = s.x[pb];
    v0 -= x.head<3>();
    w -= x.tail<3>();
    if (has_a) {
      d = origin - data.bodies[first.body_b].x_W;
      v0 -= x.tail<3>().cross(d);
    }
  }
  // in scalars: Eigen's 3-vector cross products and temporaries cost about twice as much here
  const double vx = v0.x(), vy = v0.y(), vz = v0.z(), wx = w.x(), wy = w.y(), wz = w.z();
  const double ox = origin.x(), oy = origin.y(), oz = origin.z();
  bool pulled = false;
  double Fx = 0.0, Fy = 0.0, Fz = 0.0;  // total force on a
  double Tx = 0.0, Ty = 0.0, Tz = 0.0;  // and its moment about origin
  for (int k = begin; k < end; ++k) {
    ImplicitContact& c = contacts[k];
    const double rx = c.p_W.x() - ox, ry = c.p_W.y() - oy, rz = c.p_W.z() - oz;
    const double ux = vx + (wy * rz - wz * ry);
    const double uy = vy + (wz * rx - wx * rz);
    const double uz = vz + (wx * ry - wy * rx);
    const double nx = c.n_W.x(), ny = c.n_W.y(), nz = c.n_W.z();
    const double un = ux * nx + uy * ny + uz * nz;
    const double fn = c.phi_n_N - c.c_n_Ns_per_m * un;
    if (fn < 0.0) {
      pulled = true;
      if (may_drop) {
        // a contact that stops pushing has no friction either
        c.active = false;
        continue;
      }
    }
    c.normal_force_N = fn;
    double fx = fn * nx, fy = fn * ny, fz = fn * nz;
    if (c.stick) {
      const double ct = c.c_t_Ns_per_m;
      const double tx = c.phi_t_W.x() - ct * (ux - un * nx);
      const double ty = c.phi_t_W.y() - ct * (uy - un * ny);
      const double tz = c.phi_t_W.z() - ct * (uz - un * nz);
      c.friction_force_W = Vec3(tx, ty, tz);
      fx += tx;
      fy += ty;
      fz += tz;
    }
    if constexpr (kAccumulate) {
      Fx += fx;
      Fy += fy;
      Fz += fz;
      Tx += ry * fz - rz * fy;
      Ty += rz * fx - rx * fz;
      Tz += rx * fy - ry * fx;
    }
  }
  if constexpr (kAccumulate) {
    const Vec3 F(h * Fx, h * Fy, h * Fz), T(h * Tx, h * Ty, h * Tz);
    if (has_a) {
      s.b[pa].head<3>() += F;
      s.b[pa].tail<3>() += T;
    }
    if (has_b) {
      s.b[pb].head<3>() -= F;
      s.b[pb].tail<3>() -= T + d.cross(F);
    }
  }
  return pulled;
}

// --- the lagged factorisation ---

// the patches' keys (GroupSolverScratch::PatchKey), sorted: the bodies, count and stick state
// exactly, the coefficients by their bits
void PatchKeys(GroupSolverScratch& s, std::span<const ImplicitContact> contacts) {
  for (int q = 0; q < s.npatch; ++q) {
    const int begin = s.patch_range[2 * q], end = s.patch_range[2 * q + 1];
    const ImplicitContact& c = contacts[begin];
    // body indices + 1 (static: 0) in 24 bits each, the count in 15, the stick state in 1
    const auto lo = static_cast<std::uint64_t>(std::min(c.body_a, c.body_b) + 1);
    const auto hi = static_cast<std::uint64_t>(std::max(c.body_a, c.body_b) + 1);
    const auto count = static_cast<std::uint64_t>(end - begin);
    const std::uint64_t shape = lo << 40 | hi << 16 | count << 1 | (c.stick ? 1 : 0);
    const auto c_n = std::bit_cast<std::uint64_t>(c.c_n_Ns_per_m);
    const auto c_t = std::bit_cast<std::uint64_t>(c.stick ? c.c_t_Ns_per_m : 0.0);
    s.patch_keys[q] = {shape, c_n ^ (c_t << 1 | c_t >> 63)};
  }
  std::sort(s.patch_keys.begin(), s.patch_keys.begin() + s.npatch);
}

// true if the factor kept in the scratch was made for a system of this shape: the same bodies in
// the same positions and the same patch keys. Its values differ (the contacts moved), which the
// refinement accounts for; keys that are equal by chance for different systems only cost a
// refinement that fails. Partitions the contacts into patches when the bodies match.
bool FactorFits(GroupSolverScratch& s, std::span<const int> bodies,
                std::span<const ImplicitContact> contacts) {
  const int nb = static_cast<int>(bodies.size());
  if (!s.factor_valid || nb != s.factor_nb ||
      !std::equal(bodies.begin(), bodies.end(), s.factor_bodies.begin())) {
    return false;
  }
  PartitionPatches(s, contacts);
  if (s.npatch != s.factor_npatch) return false;
  PatchKeys(s, contacts);
  return std::equal(s.patch_keys.begin(), s.patch_keys.begin() + s.npatch, s.factor_keys.begin());
}

// records what the factor now in the scratch was made for (FactorFits), from the patches
// assembled with every contact active
void KeepFactor(GroupSolverScratch& s, std::span<const int> bodies,
                std::span<const ImplicitContact> contacts) {
  PatchKeys(s, contacts);
  s.factor_nb = static_cast<int>(bodies.size());
  std::copy(bodies.begin(), bodies.end(), s.factor_bodies.begin());
  s.factor_npatch = s.npatch;
  std::copy(s.patch_keys.begin(), s.patch_keys.begin() + s.npatch, s.factor_keys.begin());
  s.factor_valid = true;
}

// f^T m^-1 f + t^T I^-1 t for a body of rotation R (the M^-1 norm of an impulse, squared)
double InverseMassNorm2(const BodyModel& b, const Mat3& R, const Vec3& f, const Vec3& t) {
  const Vec3 t_B = R.transpose() * t;
  return f.squaredNorm() / b.mass_kg + t_B.dot(t_B.cwiseQuotient(b.inertia_kgm2));
}

// the residual of the momentum balance at the velocities s.x, into s.b:
//   r = M (v - x) + h F + h sum J^T f(x),
// zero exactly at the solution of the implicit system; the contacts' forces at x are left in
// them. Returns r^T M^-1 r. Since A = M + h sum J^T C J >= M, the error of x in the kinetic-energy
// norm is bounded by the residual: (x - x*)^T M (x - x*) <= r^T A^-1 r <= r^T M^-1 r.
double Residual(const Model& model, const Data& data, std::span<const int> bodies,
                std::span<const int> slot, std::span<ImplicitContact> contacts,
                std::span<const Vec3> force_W, std::span<const Vec3> torque_W,
                GroupSolverScratch& s, bool* pulls) {
  const double h = model.timestep_s;
  const int nb = static_cast<int>(bodies.size());
  for (int k = 0; k < nb; ++k) {
    const int i = bodies[k], p = s.pos[k];
    const BodyState& st = data.bodies[i];
    s.b[p].head<3>() = model.bodies[i].mass_kg * (st.v_W - s.x[p].head<3>()) + h * force_W[i];
    s.b[p].tail<3>() =
        WorldInertiaTimes(model.bodies[i], s.rotation[p], st.w_W - s.x[p].tail<3>()) +
        h * torque_W[i];
  }
  bool pulled = false;
  for (int q = 0; q < s.npatch; ++q) {
    pulled |= PatchForces<true>(s, data, slot, contacts, s.patch_range[2 * q],
                                s.patch_range[2 * q + 1], false, h);
  }
  *pulls = pulled;
  double r2 = 0.0;
  for (int k = 0; k < nb; ++k) {
    const int p = s.pos[k];
    const Vec3 rl = s.b[p].head<3>(), ra = s.b[p].tail<3>();
    r2 += InverseMassNorm2(model.bodies[bodies[k]], s.rotation[p], rl, ra);
  }
  return r2;
}

// solves the group with the factor of an earlier step's system of the same shape, by iterative
// refinement against this step's system: x <- x + F^-1 r(x) from the current velocities, until
// the residual bounds the velocity error in the kinetic-energy norm by kRefineTolerance of the
// step's momentum scale. False (nothing final written, the caller factors afresh) if that takes
// more than kMaxRefinements corrections or the accepted velocities would make a contact pull.
bool SolveLagged(const Model& model, const Data& data, std::span<const int> bodies,
                 std::span<const int> slot, std::span<ImplicitContact> contacts,
                 std::span<const Vec3> force_W, std::span<const Vec3> torque_W,
                 GroupSolverScratch& s) {
  const double h = model.timestep_s;
  const int nb = static_cast<int>(bodies.size());
  // the momentum scale: |M v| + |h F| + |r(v)|, each in the M^-1 norm
  double mv2 = 0.0, hf2 = 0.0;
  for (int k = 0; k < nb; ++k) {
    const int i = bodies[k], p = s.pos[k];
    const BodyModel& bm = model.bodies[i];
    const BodyState& st = data.bodies[i];
    const Mat3 R = st.q_WB.toRotationMatrix();
    s.rotation[p] = R;
    s.x[p] << st.v_W, st.w_W;
    const Vec3 w_B = R.transpose() * st.w_W;
    mv2 += bm.mass_kg * st.v_W.squaredNorm() + w_B.dot(w_B.cwiseProduct(bm.inertia_kgm2));
    hf2 += h * h * InverseMassNorm2(bm, R, force_W[i], torque_W[i]);
  }
  bool pulls = false;
  double r2 = Residual(model, data, bodies, slot, contacts, force_W, torque_W, s, &pulls);
  const double scale = std::sqrt(mv2) + std::sqrt(hf2) + std::sqrt(r2);
  const double tol2 = kRefineTolerance * kRefineTolerance * scale * scale;
  int steps = 0;
  double last2 = r2;
  while (!(r2 <= tol2)) {
    if (steps == kMaxRefinements) return false;
    if (steps > 0) {
      // each correction shrinks the residual by about the last one's ratio: stop early if the
      // corrections left cannot bring it under the tolerance
      double predicted2 = r2;
      for (int k = steps; k < kMaxRefinements; ++k) predicted2 *= r2 / last2;
      if (!(predicted2 <= tol2)) return false;
    }
    if (!Substitute(s, nb, s.b)) return false;
    for (int p = 0; p < nb; ++p) s.x[p] += s.b[p];
    last2 = r2;
    r2 = Residual(model, data, bodies, slot, contacts, force_W, torque_W, s, &pulls);
    ++steps;
  }
  if (pulls) return false;
  s.refinement_steps += steps;
  return true;
}

}  // namespace

void GroupSolverScratch::Reserve(int max_group_bodies, int max_group_contacts) {
  max_bodies = max_group_bodies;
  max_contacts = max_group_contacts;
  // every pair of bodies could couple after fill-in, but a contact group is sparse: bound the
  // factor's off-diagonal blocks by 32 per body
  const long full = static_cast<long>(max_bodies) * (max_bodies - 1) / 2;
  max_blocks = static_cast<int>(std::min<long>(full, 32L * max_bodies));
  const auto n2 = static_cast<std::size_t>(max_bodies) * max_bodies;
  diag_A.assign(max_bodies, Mat6::Zero());
  diag_inv.assign(max_bodies, Vec6::Zero());
  b.assign(max_bodies, Vec6::Zero());
  x.assign(max_bodies, Vec6::Zero());
  pos.assign(max_bodies, 0);
  col_start.assign(max_bodies + 1, 0);
  col_row.assign(max_blocks, 0);
  off_A.assign(max_blocks, Mat6::Zero());
  block.assign(n2, -1);
  adj.assign(n2, 0);
  degree.assign(max_bodies, 0);
  eliminated.assign(max_bodies, 0);
  pairs.assign(max_contacts, 0);
  analysed_pairs.assign(max_contacts, 0);
  npairs = 0;
  analysed_npairs = analysed_nb = -1;
  patch_range.assign(2 * static_cast<std::size_t>(max_contacts), 0);
  npatch = 0;
  factor_valid = false;
  factor_nb = factor_npatch = 0;
  factor_bodies.assign(max_bodies, -1);
  patch_keys.assign(max_contacts, PatchKey{});
  factor_keys.assign(max_contacts, PatchKey{});
  rotation.assign(max_bodies, Mat3::Identity());
  factorisations = lagged_solves = refinement_steps = lagged_failures = 0;
  lag_backoff = lag_skip = 0;
}

bool SolveGroupVelocities(const Model& model, Data& data, std::span<const int> bodies,
                          std::span<const int> slot, std::span<ImplicitContact> contacts,
                          std::span<const Vec3> force_W, std::span<const Vec3> torque_W,
                          GroupSolverScratch& s) {
  const int nb = static_cast<int>(bodies.size());
  const int nc = static_cast<int>(contacts.size());
  if (nb > s.max_bodies || nc > s.max_contacts) return false;
  StructureOf(s, slot, contacts);
  const auto pairs_end = s.pairs.begin() + s.npairs;
  if (nb != s.analysed_nb || s.npairs != s.analysed_npairs ||
      !std::equal(s.pairs.begin(), pairs_end, s.analysed_pairs.begin())) {
    s.analysed_nb = -1;  // stays invalid if the analysis fails
    if (!Analyse(s, nb)) return false;
    std::copy(s.pairs.begin(), pairs_end, s.analysed_pairs.begin());
    s.analysed_npairs = s.npairs;
    s.analysed_nb = nb;
  }

  // a contact may come in inactive (dropped by the caller): then the system is not the one
  // kept factors are made for
  const bool reuse =
      s.reuse_factor && std::all_of(contacts.begin(), contacts.end(),
                                    [](const ImplicitContact& c) { return c.active; });
  bool lagged = false;
  if (reuse && FactorFits(s, bodies, contacts)) {
    if (s.lag_skip > 0) {
      --s.lag_skip;
    } else if (SolveLagged(model, data, bodies, slot, contacts, force_W, torque_W, s)) {
      lagged = true;
      ++s.lagged_solves;
      s.lag_backoff = 0;
    } else {
      // while the group moves too much for the kept factor, try it ever more rarely
      ++s.lagged_failures;
      s.lag_backoff = std::min(2 * s.lag_backoff + 1, kMaxBackoff);
      s.lag_skip = s.lag_backoff;
    }
  }
  if (!lagged) {
    s.factor_valid = false;
    for (int pass = 0; pass < kMaxPasses; ++pass) {
      // the factorisation overwrites the system: each pass assembles it over the contacts left
      Assemble(model, data, bodies, slot, contacts, force_W, torque_W, s);
      if (!Factor(s, nb)) return false;
      ++s.factorisations;
      std::copy(s.b.begin(), s.b.begin() + nb, s.x.begin());
      if (!Substitute(s, nb, s.x)) return false;
      for (ImplicitContact& c : contacts) {
        c.normal_force_N = 0.0;
        c.friction_force_W.setZero();
      }
      bool pulled = false;
      for (int q = 0; q < s.npatch; ++q) {
        pulled |=
            PatchForces<false>(s, data, slot, contacts, s.patch_range[2 * q],
                               s.patch_range[2 * q + 1], pass + 1 < kMaxPasses, model.timestep_s);
      }
      if (!pulled) {
        // a factor of the system with every contact is kept for the next steps
        if (pass == 0 && reuse) KeepFactor(s, bodies, contacts);
        break;
      }
    }
  }
  for (int k = 0; k < nb; ++k) {
    BodyState& st = data.bodies[bodies[k]];
    const Vec6& v = s.x[s.pos[k]];
    st.v_W = v.head<3>();
    st.w_W = v.tail<3>();
  }
  return true;
}

}  // namespace rigidtouch::dynamics
