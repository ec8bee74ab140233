#include "dynamics/group_assembly.h"

#include <algorithm>

#include "dynamics/rigid_body.h"

namespace rigidtouch::dynamics {
namespace {

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
void AssemblePatch(GroupAssembly& g, BlockCholesky& factor, const Data& data,
                   std::span<const int> slot, std::span<const ImplicitContact> contacts, int begin,
                   int end, double h) {
  const ImplicitContact& first = contacts[begin];
  const int pa = first.body_a >= 0 ? factor.pos[slot[first.body_a]] : -1;
  const int pb = first.body_b >= 0 ? factor.pos[slot[first.body_b]] : -1;
  const Vec3& origin = data.bodies[pa >= 0 ? first.body_a : first.body_b].x_W;
  Vec3 F = Vec3::Zero(), T = Vec3::Zero(), P = Vec3::Zero();
  double sxx = 0.0, syy = 0.0, szz = 0.0, sxy = 0.0, sxz = 0.0, syz = 0.0;  // S, symmetric
  for (int k = begin; k < end; ++k) {
    const ImplicitContact& c = contacts[k];
    // the anchor spring of a sticking contact, the kinetic friction of a slipping one
    const Vec3 f = c.phi_n_N * c.n_W + c.phi_t_W;
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
    g.b[p].head<3>() += sign * F;
    g.b[p].tail<3>() += sign * T;
    AddPatchBlock<true>(factor.diag[p], count, ct, dc, n, P, P, S);
    return;
  }
  const Vec3 d = origin - data.bodies[first.body_b].x_W;
  const Vec3 Pb = P + count * d;
  const Mat3 Sab = S + P * d.transpose();
  const Mat3 Sbb = Sab + d * Pb.transpose();
  g.b[pa].head<3>() += F;
  g.b[pa].tail<3>() += T;
  g.b[pb].head<3>() -= F;
  g.b[pb].tail<3>() -= T + d.cross(F);
  AddPatchBlock<true>(factor.diag[pa], count, ct, dc, n, P, P, S);
  AddPatchBlock<true>(factor.diag[pb], count, ct, dc, n, Pb, Pb, Sbb);
  // the coupling H_ab = -h sum J_a^T C J_b; only the lower block (larger position first) is
  // stored. Both points on one body: J = J_a - J_b adds both couplings to the diagonal.
  if (pa == pb) {
    AddPatchBlock<true>(factor.diag[pa], count, -ct, -dc, n, P, Pb, Sab);
    AddPatchBlock<true>(factor.diag[pa], count, -ct, -dc, n, Pb, P, Sab.transpose());
  } else if (pa > pb) {
    AddPatchBlock<false>(factor.Lower(pa, pb), count, -ct, -dc, n, P, Pb, Sab);
  } else {
    AddPatchBlock<false>(factor.Lower(pb, pa), count, -ct, -dc, n, Pb, P, Sab.transpose());
  }
}

// adds contacts [begin, end) (one patch, all active) to the right-hand side only:
// h sum phi J^T d, as AssemblePatch does (same sums in the same order)
void AddPatchLoad(GroupAssembly& g, const BlockCholesky& factor, const Data& data,
                  std::span<const int> slot, std::span<const ImplicitContact> contacts, int begin,
                  int end, double h) {
  const ImplicitContact& first = contacts[begin];
  const int pa = first.body_a >= 0 ? factor.pos[slot[first.body_a]] : -1;
  const int pb = first.body_b >= 0 ? factor.pos[slot[first.body_b]] : -1;
  const Vec3& origin = data.bodies[pa >= 0 ? first.body_a : first.body_b].x_W;
  Vec3 F = Vec3::Zero(), T = Vec3::Zero();
  for (int k = begin; k < end; ++k) {
    const ImplicitContact& c = contacts[k];
    const Vec3 f = c.phi_n_N * c.n_W + c.phi_t_W;
    F += f;
    T += (c.p_W - origin).cross(f);
  }
  F *= h;
  T *= h;
  if (pa < 0 || pb < 0) {
    const int p = pa >= 0 ? pa : pb;
    const double sign = pa >= 0 ? 1.0 : -1.0;
    g.b[p].head<3>() += sign * F;
    g.b[p].tail<3>() += sign * T;
    return;
  }
  const Vec3 d = origin - data.bodies[first.body_b].x_W;
  g.b[pa].head<3>() += F;
  g.b[pa].tail<3>() += T;
  g.b[pb].head<3>() -= F;
  g.b[pb].tail<3>() -= T + d.cross(F);
}

// M v + h F of body slot k into the right-hand side at its elimination position
void AddMomentum(const Model& model, const Data& data, std::span<const int> bodies,
                 std::span<const Vec3> force_W, std::span<const Vec3> torque_W, GroupAssembly& g,
                 const BlockCholesky& factor, int k) {
  const double h = model.timestep_s;
  const int i = bodies[k];
  const BodyModel& bm = model.bodies[i];
  const BodyState& st = data.bodies[i];
  g.b[factor.pos[k]] << bm.mass_kg * st.v_W + h * force_W[i],
      WorldInertia(bm, st) * st.w_W + h * torque_W[i];
}

}  // namespace

void AssembleRightHandSide(const Model& model, const Data& data, std::span<const int> bodies,
                           std::span<const int> slot, std::span<const ImplicitContact> contacts,
                           std::span<const Vec3> force_W, std::span<const Vec3> torque_W,
                           GroupAssembly& g, const BlockCholesky& factor) {
  const int nb = static_cast<int>(bodies.size());
  for (int k = 0; k < nb; ++k) AddMomentum(model, data, bodies, force_W, torque_W, g, factor, k);
  for (int q = 0; q < g.npatch; ++q) {
    AddPatchLoad(g, factor, data, slot, contacts, g.patch_range[2 * q], g.patch_range[2 * q + 1],
                 model.timestep_s);
  }
}

void GroupAssembly::Reserve(int max_bodies, int max_contacts) {
  pairs.assign(max_contacts, 0);
  npairs = 0;
  patch_range.assign(2 * static_cast<std::size_t>(max_contacts), 0);
  npatch = 0;
  b.assign(max_bodies, Vec6::Zero());
  x.assign(max_bodies, Vec6::Zero());
}

void StructureOf(GroupAssembly& g, std::span<const int> slot,
                 std::span<const ImplicitContact> contacts) {
  g.npairs = 0;
  int last_a = -1, last_b = -1;  // the bodies of the previous two-body contact
  for (const ImplicitContact& c : contacts) {
    if (c.body_a < 0 || c.body_b < 0) continue;
    if (c.body_a == last_a && c.body_b == last_b) continue;  // the manifold's next point
    last_a = c.body_a;
    last_b = c.body_b;
    const int i = std::min(slot[c.body_a], slot[c.body_b]);
    const int j = std::max(slot[c.body_a], slot[c.body_b]);
    if (i != j) g.pairs[g.npairs++] = PackEdge(i, j);
  }
  const auto begin = g.pairs.begin(), end = begin + g.npairs;
  std::sort(begin, end);
  g.npairs = static_cast<int>(std::unique(begin, end) - begin);
}

void PartitionPatches(GroupAssembly& g, std::span<const ImplicitContact> contacts) {
  const int nc = static_cast<int>(contacts.size());
  g.npatch = 0;
  for (int begin = 0; begin < nc;) {
    int end = begin + 1;
    if (!contacts[begin].active) {
      begin = end;
      continue;
    }
    while (end < nc && contacts[end].active && SamePatch(contacts[begin], contacts[end])) ++end;
    g.patch_range[2 * g.npatch] = begin;
    g.patch_range[2 * g.npatch + 1] = end;
    ++g.npatch;
    begin = end;
  }
}

void Assemble(const Model& model, const Data& data, std::span<const int> bodies,
              std::span<const int> slot, std::span<const ImplicitContact> contacts,
              std::span<const Vec3> force_W, std::span<const Vec3> torque_W, GroupAssembly& g,
              BlockCholesky& factor) {
  const double h = model.timestep_s;
  const int nb = static_cast<int>(bodies.size());
  for (int k = 0; k < nb; ++k) {
    const int i = bodies[k];
    const BodyModel& bm = model.bodies[i];
    const BodyState& st = data.bodies[i];
    const int p = factor.pos[k];
    const Mat3 I = WorldInertia(bm, st);
    Mat6& D = factor.diag[p];
    D.setZero();
    D.topLeftCorner<3, 3>().diagonal().setConstant(bm.mass_kg);
    D.bottomRightCorner<3, 3>() = I;
    g.b[p] << bm.mass_kg * st.v_W + h * force_W[i], I * st.w_W + h * torque_W[i];
  }
  factor.ZeroOffDiagonal(nb);
  PartitionPatches(g, contacts);
  for (int q = 0; q < g.npatch; ++q) {
    AssemblePatch(g, factor, data, slot, contacts, g.patch_range[2 * q], g.patch_range[2 * q + 1],
                  h);
  }
}

// With r = p - x_a and d = x_a - x_b, a point's relative velocity is
// (v_a - v_b - w_b x d) + (w_a - w_b) x r: one cross product per point.
template <bool kAccumulate>
bool PatchForces(GroupAssembly& g, const BlockCholesky& factor, const Data& data,
                 std::span<const int> slot, std::span<ImplicitContact> contacts, int begin, int end,
                 bool may_drop, double h) {
  const ImplicitContact& first = contacts[begin];
  const bool has_a = first.body_a >= 0, has_b = first.body_b >= 0;
  const int pa = has_a ? factor.pos[slot[first.body_a]] : -1;
  const int pb = has_b ? factor.pos[slot[first.body_b]] : -1;
  const Vec3& origin = data.bodies[has_a ? first.body_a : first.body_b].x_W;
  Vec3 d = Vec3::Zero();  // x_a - x_b
  Vec3 v0 = Vec3::Zero(), w = Vec3::Zero();
  if (has_a) {
    const Vec6& x = g.x[pa];
    v0 += x.head<3>();
    w += x.tail<3>();
  }
  if (has_b) {
    const Vec6& x = g.x[pb];
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
      c.friction_force_N_W = Vec3(tx, ty, tz);
      fx += tx;
      fy += ty;
      fz += tz;
    } else {
      // slipping: the kinetic friction, independent of the new velocity
      c.friction_force_N_W = c.phi_t_W;
      c.slip_power_W = c.phi_t_W.x() * ux + c.phi_t_W.y() * uy + c.phi_t_W.z() * uz;
      fx += c.phi_t_W.x();
      fy += c.phi_t_W.y();
      fz += c.phi_t_W.z();
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
      g.b[pa].head<3>() += F;
      g.b[pa].tail<3>() += T;
    }
    if (has_b) {
      g.b[pb].head<3>() -= F;
      g.b[pb].tail<3>() -= T + d.cross(F);
    }
  }
  return pulled;
}

namespace {

// the end of the friction patch that starts at contacts[begin] (its consecutive contacts with the
// same ImplicitContact::patch; a contact of patch -1 is a patch of its own)
int PatchEnd(std::span<const ImplicitContact> contacts, int begin) {
  const int nc = static_cast<int>(contacts.size());
  const int patch = contacts[begin].patch;
  int end = begin + 1;
  while (patch >= 0 && end < nc && contacts[end].patch == patch) ++end;
  return end;
}

}  // namespace

int EnforceFrictionCones(std::span<ImplicitContact> contacts, bool last_chance) {
  // a slipping patch is scaled only when its friction exceeds the bound by more than rounding,
  // and then below the bound by as much as it was over (at most 1e-3 of it): its kinetic
  // friction moves its normal force too (through the tilt it gives the body), by a fraction of
  // the change, so that the next solve lands inside, at most that fraction below the bound
  constexpr double kSlack = 1e-10;
  constexpr double kMaxBelow = 1e-3;
  const int nc = static_cast<int>(contacts.size());
  int changed = kFrictionKept;
  for (int begin = 0; begin < nc;) {
    const ImplicitContact& first = contacts[begin];
    const int end = PatchEnd(contacts, begin);
    double fn = 0.0, ft = 0.0;  // the active contacts' normal force, tangential forces' norms
    double phi_n = 0.0;         // and their penalty forces, the patch's force scale
    for (int k = begin; k < end; ++k) {
      const ImplicitContact& c = contacts[k];
      if (!c.active) continue;
      fn += std::max(0.0, c.normal_force_N);
      ft += c.friction_force_N_W.norm();
      phi_n += std::max(0.0, c.phi_n_N);
    }
    // a sticking patch slips only if its friction exceeds the cone by more than rounding of its
    // force scale: a trial friction at rounding level (a patch that neither slides nor is loaded
    // sideways, at a normal force of zero) has no direction to give the kinetic friction
    if (first.stick && ft > first.mu_static * (fn + kSlack * phi_n)) {
      // slip: the kinetic friction of each point along its trial force (the resultant's
      // direction for a point without one); the resultant is summed only here, where it is used
      Vec3 resultant = Vec3::Zero();
      for (int k = begin; k < end; ++k) {
        if (contacts[k].active) resultant += contacts[k].friction_force_N_W;
      }
      const double rn = resultant.norm();
      const Vec3 fallback = rn > 0.0 ? Vec3(resultant / rn) : Vec3::Zero();
      for (int k = begin; k < end; ++k) {
        ImplicitContact& c = contacts[k];
        c.stick = false;
        c.c_t_Ns_per_m = 0.0;
        const double f = c.friction_force_N_W.norm();
        const Vec3 dir = f > 0.0 ? Vec3(c.friction_force_N_W / f) : fallback;
        c.phi_t_W = c.mu_kinetic * std::max(0.0, c.phi_n_N) * dir;
      }
      changed |= kFrictionSlipped;
    } else if (!first.stick && ft > first.mu_kinetic * fn * (1.0 + kSlack)) {
      const double bound = first.mu_kinetic * fn;
      const double below = std::min(kMaxBelow, ft / bound - 1.0);
      const double scale = last_chance ? 0.0 : (1.0 - below) * bound / ft;
      for (int k = begin; k < end; ++k) contacts[k].phi_t_W *= scale;
      changed |= kFrictionScaled;
    }
    begin = end;
  }
  return changed;
}

bool StickReversedSlips(std::span<ImplicitContact> contacts) {
  const int nc = static_cast<int>(contacts.size());
  bool changed = false;
  for (int begin = 0; begin < nc;) {
    const ImplicitContact& first = contacts[begin];
    const int end = PatchEnd(contacts, begin);
    if (!first.stick) {
      // the kinetic friction's power on the reversed slip against the same force at the limit
      double power = 0.0, limit = 0.0;
      for (int k = begin; k < end; ++k) {
        const ImplicitContact& c = contacts[k];
        if (!c.active) continue;
        power += c.slip_power_W;
        limit += c.phi_t_W.norm() * c.reversal_limit_mps;
      }
      if (power > limit) {
        for (int k = begin; k < end; ++k) {
          ImplicitContact& c = contacts[k];
          c.stick = true;
          c.c_t_Ns_per_m = c.c_t_stick_Ns_per_m;
        }
        changed = true;
      }
    }
    begin = end;
  }
  return changed;
}

template bool PatchForces<false>(GroupAssembly&, const BlockCholesky&, const Data&,
                                 std::span<const int>, std::span<ImplicitContact>, int, int, bool,
                                 double);
template bool PatchForces<true>(GroupAssembly&, const BlockCholesky&, const Data&,
                                std::span<const int>, std::span<ImplicitContact>, int, int, bool,
                                double);

}  // namespace rigidtouch::dynamics
