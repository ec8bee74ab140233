#include "dynamics/group_dynamics.h"

#include <algorithm>
#include <cmath>

#include "dynamics/rigid_body.h"

namespace rigidtouch::dynamics {
namespace {

constexpr int kMaxPasses = 4;

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

// the group's structure: the pairs of group slots that share a contact, in the contacts' order
// with consecutive repeats (the points of one manifold) left out. Equal lists give equal
// analyses, so a group whose bodies keep touching the same neighbours is analysed once.
void StructureOf(GroupSolverScratch& s, std::span<const int> slot,
                 std::span<const ImplicitContact> contacts) {
  s.npairs = 0;
  int last_a = -1, last_b = -1;  // the bodies of the previous two-body contact
  for (const ImplicitContact& c : contacts) {
    if (c.body_a < 0 || c.body_b < 0) continue;
    if (c.body_a == last_a && c.body_b == last_b) continue;  // the manifold's next point
    last_a = c.body_a;
    last_b = c.body_b;
    const int a = slot[c.body_a], b = slot[c.body_b];
    if (a == b) continue;
    const int n = s.npairs;
    if (n > 0 && s.pairs[2 * n - 2] == a && s.pairs[2 * n - 1] == b) continue;
    s.pairs[2 * n] = a;
    s.pairs[2 * n + 1] = b;
    ++s.npairs;
  }
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
    const int a = s.pairs[2 * e], b = s.pairs[2 * e + 1];
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
// structure) and solves for x
bool FactorAndSolve(GroupSolverScratch& s, int nb) {
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
  std::copy(s.b.begin(), s.b.begin() + nb, s.x.begin());
  for (int k = 0; k < nb; ++k) {  // L y = b
    ForwardSubstitute(s.diag_A[k], s.diag_inv[k], s.x[k]);
    for (int e = s.col_start[k]; e < s.col_start[k + 1]; ++e) {
      s.x[s.col_row[e]].noalias() -= s.off_A[e] * s.x[k];
    }
  }
  for (int k = nb - 1; k >= 0; --k) {  // L^T x = y
    for (int e = s.col_start[k]; e < s.col_start[k + 1]; ++e) {
      s.x[k].noalias() -= s.off_A[e].transpose() * s.x[s.col_row[e]];
    }
    BackSubstitute(s.diag_A[k], s.diag_inv[k], s.x[k]);
  }
  for (int k = 0; k < nb; ++k) {
    if (!s.x[k].allFinite()) return false;
  }
  return true;
}

// assembles M + h sum c J^T J and M v + h F + h sum phi J^T over the active contacts, a patch
// at a time
void Assemble(const Model& model, const Data& data, std::span<const int> bodies,
              std::span<const int> slot, std::span<const ImplicitContact> contacts,
              std::span<const Vec3> force_W, std::span<const Vec3> torque_W,
              GroupSolverScratch& s) {
  const double h = model.timestep_s;
  const int nb = static_cast<int>(bodies.size());
  const int nc = static_cast<int>(contacts.size());
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
  s.npatch = 0;
  for (int begin = 0; begin < nc;) {
    int end = begin + 1;
    if (!contacts[begin].active) {
      begin = end;
      continue;
    }
    while (end < nc && contacts[end].active && SamePatch(contacts[begin], contacts[end])) ++end;
    AssemblePatch(s, data, slot, contacts, begin, end, h, nb);
    // a patch's range: dropped contacts may lie between two patches
    s.patch_range[2 * s.npatch] = begin;
    s.patch_range[2 * s.npatch + 1] = end;
    ++s.npatch;
    begin = end;
  }
}

// the forces of patch [begin, end) at the solved velocities. With r = p - x_a and d = x_a - x_b,
// a point's relative velocity is (v_a - v_b - w_b x d) + (w_a - w_b) x r: one cross product per
// point. `may_drop`: a contact whose normal force would pull is taken out (active = false, no
// force) and true returned, so the system is solved again without it.
bool PatchForces(const GroupSolverScratch& s, const Data& data, std::span<const int> slot,
                 std::span<ImplicitContact> contacts, int begin, int end, bool may_drop) {
  const ImplicitContact& first = contacts[begin];
  const bool has_a = first.body_a >= 0, has_b = first.body_b >= 0;
  const Vec3& origin = data.bodies[has_a ? first.body_a : first.body_b].x_W;
  Vec3 v0 = Vec3::Zero(), w = Vec3::Zero();
  if (has_a) {
    const Vec6& x = s.x[s.pos[slot[first.body_a]]];
    v0 += x.head<3>();
    w += x.tail<3>();
  }
  if (has_b) {
    const Vec6& x = s.x[s.pos[slot[first.body_b]]];
    v0 -= x.head<3>();
    w -= x.tail<3>();
    if (has_a) v0 -= x.tail<3>().cross(origin - data.bodies[first.body_b].x_W);
  }
  bool pulled = false;
  for (int k = begin; k < end; ++k) {
    ImplicitContact& c = contacts[k];
    const Vec3 u = v0 + w.cross(c.p_W - origin);
    const double un = u.dot(c.n_W);
    const double fn = c.phi_n_N - c.c_n_Ns_per_m * un;
    if (may_drop && fn < 0.0) {
      // a contact that stops pushing has no friction either
      c.active = false;
      pulled = true;
      continue;
    }
    c.normal_force_N = fn;
    if (c.stick) c.friction_force_W = c.phi_t_W - c.c_t_Ns_per_m * (u - un * c.n_W);
  }
  return pulled;
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
  pairs.assign(2 * static_cast<std::size_t>(max_contacts), 0);
  analysed_pairs.assign(2 * static_cast<std::size_t>(max_contacts), 0);
  npairs = 0;
  analysed_npairs = analysed_nb = -1;
  patch_range.assign(2 * static_cast<std::size_t>(max_contacts), 0);
  npatch = 0;
}

bool SolveGroupVelocities(const Model& model, Data& data, std::span<const int> bodies,
                          std::span<const int> slot, std::span<ImplicitContact> contacts,
                          std::span<const Vec3> force_W, std::span<const Vec3> torque_W,
                          GroupSolverScratch& s) {
  const int nb = static_cast<int>(bodies.size());
  const int nc = static_cast<int>(contacts.size());
  if (nb > s.max_bodies || nc > s.max_contacts) return false;
  StructureOf(s, slot, contacts);
  const auto pairs_end = s.pairs.begin() + 2 * static_cast<std::ptrdiff_t>(s.npairs);
  if (nb != s.analysed_nb || s.npairs != s.analysed_npairs ||
      !std::equal(s.pairs.begin(), pairs_end, s.analysed_pairs.begin())) {
    s.analysed_nb = -1;  // stays invalid if the analysis fails
    if (!Analyse(s, nb)) return false;
    std::copy(s.pairs.begin(), pairs_end, s.analysed_pairs.begin());
    s.analysed_npairs = s.npairs;
    s.analysed_nb = nb;
  }

  for (int pass = 0; pass < kMaxPasses; ++pass) {
    // the factorisation overwrites the system: each pass assembles it over the contacts left
    Assemble(model, data, bodies, slot, contacts, force_W, torque_W, s);
    if (!FactorAndSolve(s, nb)) return false;
    for (ImplicitContact& c : contacts) {
      c.normal_force_N = 0.0;
      c.friction_force_W.setZero();
    }
    bool pulled = false;
    for (int q = 0; q < s.npatch; ++q) {
      pulled |= PatchForces(s, data, slot, contacts, s.patch_range[2 * q], s.patch_range[2 * q + 1],
                            pass + 1 < kMaxPasses);
    }
    if (!pulled) break;
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
