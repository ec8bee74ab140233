// Joint-space contact groups: implicit penalty with friction and the impulses of Eq. 5 and Eq. 8
// on the stacked velocities of bodies and trees (joint_group.h).
#include "contact/joint_group.h"

#include <algorithm>
#include <cmath>

#include "contact/impulse_math.h"
#include "rigidtouch/types.h"

namespace rigidtouch::contact {
namespace {

// relative regularisation of the non-negative solve's free-set factor (redundant rows)
constexpr double kJointRegularization = 1e-13;
// a row whose W_jj is at most this fraction of the group's largest is inert (no impulse)
constexpr double kJointInertRow = 1e-12;
// relative slack of the friction bounds (rounding of the forces)
constexpr double kJointConeSlack = 1e-12;

// two unit tangents completing n to a right-handed orthonormal basis
void JointTangents(const Vec3& n, Vec3& t1, Vec3& t2) {
  const Vec3 other = std::abs(n.x()) < 0.6 ? Vec3::UnitX() : Vec3::UnitY();
  t1 = n.cross(other).normalized();
  t2 = n.cross(t1);
}

// in-place Cholesky of the leading m x m block (lower triangle); false at a non-positive pivot
bool JointCholesky(Eigen::MatrixXd& k, int m) {
  for (int j = 0; j < m; ++j) {
    double d = k(j, j);
    for (int c = 0; c < j; ++c) d -= k(j, c) * k(j, c);
    if (!(d > 0.0)) return false;
    const double l = std::sqrt(d);
    k(j, j) = l;
    for (int i = j + 1; i < m; ++i) {
      double s = k(i, j);
      for (int c = 0; c < j; ++c) s -= k(i, c) * k(j, c);
      k(i, j) = s / l;
    }
  }
  return true;
}

// x <- (L L^T)^-1 x with the factor of JointCholesky
void JointCholeskySolve(const Eigen::MatrixXd& l, int m, Eigen::VectorXd& x) {
  for (int i = 0; i < m; ++i) {
    double s = x[i];
    for (int c = 0; c < i; ++c) s -= l(i, c) * x[c];
    x[i] = s / l(i, i);
  }
  for (int i = m - 1; i >= 0; --i) {
    double s = x[i];
    for (int c = i + 1; c < m; ++c) s -= l(c, i) * x[c];
    x[i] = s / l(i, i);
  }
}

bool JointRowFinite(const JointRow& r) {
  return r.n_W.allFinite() && r.p_W.allFinite() && std::isfinite(r.limit_sign) &&
         std::isfinite(r.phi_n_N) && std::isfinite(r.c_n_Ns_per_m) && r.phi_t_W.allFinite() &&
         std::isfinite(r.c_t_Ns_per_m) && std::isfinite(r.mu_static) && std::isfinite(r.mu_kinetic);
}

}  // namespace

JointGroupSolver::JointGroupSolver(int max_rows, int max_dofs)
    : max_rows_(max_rows), max_dofs_(max_dofs) {
  if (max_rows < 1 || max_dofs < 1) {
    throw Error("JointGroupSolver: max_rows and max_dofs must be at least 1");
  }
  const int r = 3 * max_rows;
  body_offset_.assign(max_dofs, 0);
  tree_offset_.assign(max_dofs, 0);
  tree_dofs_.assign(max_dofs, 0);
  jac_t_.setZero(max_dofs, r);
  y_.setZero(max_dofs, r);
  yt_.setZero(r, max_dofs);
  solve_.assign(r, 0);
  w_.setZero(r, r);
  point_trans_.setZero(3, max_dofs);
  point_rot_.setZero(3, max_dofs);
  u_.setZero(max_dofs);
  force_.setZero(max_dofs);
  b_.setZero(r);
  phi_.setZero(r);
  c_.setZero(r);
  lambda_.setZero(r);
  rhs_.setZero(r);
  active_.assign(r, 0);
  index_.assign(r, 0);
  k_.setZero(r, r);
  p_.setZero(r);
  z_.setZero(r);
  g_.setZero(r);
  in_set_.assign(r, 0);
  free_.assign(r, 0);
  scales_.assign(max_rows, 0.0);
}

JointGroupError JointGroupSolver::AddSide(const JointGroup& group, const RowSide& side, double sign,
                                          const JointRow& row, int first) {
  if (side.kind == RowSideKind::kStatic) return JointGroupError::kNone;
  if (side.kind == RowSideKind::kBody) {
    if (side.member < 0 || side.member >= static_cast<int>(group.bodies.size())) {
      return JointGroupError::kBadRow;
    }
    const int off = body_offset_[side.member];
    const Vec3 r_W = row.p_W - group.body_com_W[side.member];
    Vec3 dirs[3];
    dirs[0] = row.n_W;
    JointTangents(row.n_W, dirs[1], dirs[2]);
    for (int d = 0; d < 3; ++d) {
      jac_t_.col(first + d).segment<3>(off) += sign * dirs[d];
      jac_t_.col(first + d).segment<3>(off + 3) += sign * r_W.cross(dirs[d]);
    }
    return JointGroupError::kNone;
  }
  if (side.member < 0 || side.member >= static_cast<int>(group.trees.size())) {
    return JointGroupError::kBadRow;
  }
  const GroupTree& tree = group.trees[side.member];
  const int off = tree_offset_[side.member];
  const int nv = tree_dofs_[side.member];
  if (side.kind == RowSideKind::kJoint) {
    if (side.index < 0 || side.index >= nv) return JointGroupError::kBadRow;
    jac_t_(off + side.index, first) += sign * row.limit_sign;
    return JointGroupError::kNone;
  }
  if (side.index < 0 || side.index >= static_cast<int>(tree.model->bodies.size())) {
    return JointGroupError::kBadRow;
  }
  dynamics::TreePointJacobian(*tree.model, *tree.data, side.index, row.p_W,
                              point_trans_.leftCols(nv), point_rot_.leftCols(nv));
  Vec3 dirs[3];
  dirs[0] = row.n_W;
  JointTangents(row.n_W, dirs[1], dirs[2]);
  for (int d = 0; d < 3; ++d) {
    for (int c = 0; c < nv; ++c) {
      jac_t_(off + c, first + d) += sign * point_trans_.col(c).dot(dirs[d]);
    }
  }
  return JointGroupError::kNone;
}

void JointGroupSolver::ApplyBodyInverseMass(const JointGroup& group, int column) {
  auto y = y_.col(column);
  for (int i = 0; i < static_cast<int>(group.bodies.size()); ++i) {
    const int off = body_offset_[i];
    const SolverBody& body = group.bodies[i];
    y.segment<3>(off) *= body.inv_mass;
    const Vec3 torque = y.segment<3>(off + 3);
    y.segment<3>(off + 3) = body.inv_inertia_W * torque;
  }
}

// the trees' blocks of the columns marked in solve_: Y <- (M + h D)^-1 Y per tree, all columns in
// one pass over its factor (TreeSolveRows does per column what TreeSolve did, so Y is the same)
void JointGroupSolver::ApplyTreeInverseMass(const JointGroup& group) {
  for (int t = 0; t < static_cast<int>(group.trees.size()); ++t) {
    const int off = tree_offset_[t], nv = tree_dofs_[t];
    auto yt = yt_.topLeftCorner(rows_, nv);
    yt = y_.block(off, 0, nv, rows_).transpose();
    dynamics::TreeSolveRows(*group.trees[t].data, yt);
    for (int c = 0; c < rows_; ++c) {
      if (solve_[c]) y_.col(c).segment(off, nv) = yt.row(c).transpose();
    }
  }
}

void JointGroupSolver::Gather(const JointGroup& group) {
  for (int i = 0; i < static_cast<int>(group.bodies.size()); ++i) {
    u_.segment<3>(body_offset_[i]) = group.bodies[i].v_W;
    u_.segment<3>(body_offset_[i] + 3) = group.bodies[i].w_W;
  }
  for (int t = 0; t < static_cast<int>(group.trees.size()); ++t) {
    u_.segment(tree_offset_[t], tree_dofs_[t]) = group.trees[t].data->qvel;
  }
}

void JointGroupSolver::Scatter(const JointGroup& group) const {
  for (int i = 0; i < static_cast<int>(group.bodies.size()); ++i) {
    group.bodies[i].v_W = u_.segment<3>(body_offset_[i]);
    group.bodies[i].w_W = u_.segment<3>(body_offset_[i] + 3);
  }
  for (int t = 0; t < static_cast<int>(group.trees.size()); ++t) {
    group.trees[t].data->qvel = u_.segment(tree_offset_[t], tree_dofs_[t]);
  }
}

// offsets, the rows' Jacobians (normal and two tangents per row), Y = M^-1 J^T, W = J Y and the
// stacked velocity
JointGroupError JointGroupSolver::Assemble(const JointGroup& group) {
  const int nrows = static_cast<int>(group.rows.size());
  if (nrows > max_rows_) return JointGroupError::kTooManyRows;
  if (group.body_com_W.size() != group.bodies.size()) return JointGroupError::kBadRow;
  if (static_cast<int>(group.bodies.size() + group.trees.size()) > max_dofs_) {
    return JointGroupError::kTooManyDofs;
  }
  int n = 0;
  for (int i = 0; i < static_cast<int>(group.bodies.size()); ++i, n += 6) body_offset_[i] = n;
  for (int t = 0; t < static_cast<int>(group.trees.size()); ++t) {
    const GroupTree& tree = group.trees[t];
    if (tree.model == nullptr || tree.data == nullptr) return JointGroupError::kBadRow;
    if (!tree.data->factored) return JointGroupError::kNotFactored;
    tree_offset_[t] = n;
    tree_dofs_[t] = tree.model->nv;
    n += tree.model->nv;
  }
  if (n > max_dofs_) return JointGroupError::kTooManyDofs;
  dofs_ = n;
  rows_ = 3 * nrows;
  jac_t_.topLeftCorner(n, rows_).setZero();
  for (int j = 0; j < nrows; ++j) {
    const JointRow& row = group.rows[j];
    if (!JointRowFinite(row)) return JointGroupError::kNonFinite;
    if (row.b.kind == RowSideKind::kJoint ||
        (row.a.kind == RowSideKind::kJoint && row.b.kind != RowSideKind::kStatic)) {
      return JointGroupError::kBadRow;
    }
    JointGroupError e = AddSide(group, row.a, 1.0, row, 3 * j);
    if (e == JointGroupError::kNone) e = AddSide(group, row.b, -1.0, row, 3 * j);
    if (e != JointGroupError::kNone) return e;
  }
  for (int c = 0; c < rows_; ++c) {
    y_.col(c).head(n) = jac_t_.col(c).head(n);
    solve_[c] = y_.col(c).head(n).isZero(0.0) ? 0 : 1;
    if (solve_[c]) ApplyBodyInverseMass(group, c);
  }
  ApplyTreeInverseMass(group);
  for (int i = 0; i < rows_; ++i) {
    for (int k = i; k < rows_; ++k) {
      w_(i, k) = jac_t_.col(i).head(n).dot(y_.col(k).head(n));
      w_(k, i) = w_(i, k);
    }
  }
  Gather(group);
  if (!u_.head(n).allFinite() || !w_.topLeftCorner(rows_, rows_).allFinite()) {
    return JointGroupError::kNonFinite;
  }
  return JointGroupError::kNone;
}

// the implicit rows (active, c > 0): (W_II + diag(1 / (h c))) lambda = -(J u + h W phi)_I
bool JointGroupSolver::SolveImplicit(double h_s) {
  int m = 0;
  for (int i = 0; i < rows_; ++i) {
    if (active_[i] && c_[i] > 0.0) index_[m++] = i;
  }
  for (int a = 0; a < m; ++a) {
    const int i = index_[a];
    double s = b_[i];
    for (int k = 0; k < rows_; ++k) {
      if (phi_[k] != 0.0) s += h_s * w_(i, k) * phi_[k];
    }
    rhs_[a] = -s;
    for (int c = 0; c <= a; ++c) k_(a, c) = w_(i, index_[c]);
    k_(a, a) += 1.0 / (h_s * c_[i]);
  }
  lambda_.head(rows_).setZero();
  if (!JointCholesky(k_, m)) return false;
  z_.head(m) = rhs_.head(m);
  JointCholeskySolve(k_, m, z_);
  for (int a = 0; a < m; ++a) lambda_[index_[a]] = z_[a];
  return lambda_.head(rows_).allFinite();
}

// after a solve: drops pulling rows, slips sticking rows outside mu_s f_n, keeps slipping rows'
// friction within mu_k f_n; true when something changed (solve again)
bool JointGroupSolver::UpdateRowStates(const JointGroup& group, JointPenaltyStats& stats,
                                       bool normals_only) {
  bool changed = false;
  const int nrows = static_cast<int>(group.rows.size());
  for (int j = 0; j < nrows; ++j) {
    const int c0 = 3 * j;
    if (!active_[c0]) continue;
    if (phi_[c0] + lambda_[c0] * inv_h_ < 0.0) {
      for (int d = 0; d < 3; ++d) active_[c0 + d] = 0, phi_[c0 + d] = 0.0, c_[c0 + d] = 0.0;
      ++stats.dropped_rows;
      changed = true;
    }
  }
  if (changed || normals_only) return changed;
  for (int j = 0; j < nrows; ++j) {
    JointRow& row = group.rows[j];
    const int c0 = 3 * j;
    if (!active_[c0] || row.a.kind == RowSideKind::kJoint) continue;
    const double fn = phi_[c0] + lambda_[c0] * inv_h_;
    const double f1 = phi_[c0 + 1] + lambda_[c0 + 1] * inv_h_;
    const double f2 = phi_[c0 + 2] + lambda_[c0 + 2] * inv_h_;
    const double ft = std::hypot(f1, f2);
    if (active_[c0 + 1]) {
      if (ft <= row.mu_static * fn * (1.0 + kJointConeSlack)) continue;
      const double scale = row.mu_kinetic * fn / ft;
      active_[c0 + 1] = active_[c0 + 2] = 0;
      c_[c0 + 1] = c_[c0 + 2] = 0.0;
      phi_[c0 + 1] = scale * f1;
      phi_[c0 + 2] = scale * f2;
      row.slipped = true;
      ++stats.slipped_rows;
      changed = true;
    } else if (ft > row.mu_kinetic * fn * (1.0 + kJointConeSlack)) {
      const double scale = row.mu_kinetic * fn / ft;
      phi_[c0 + 1] = scale * f1;
      phi_[c0 + 2] = scale * f2;
      changed = true;
    }
  }
  return changed;
}

JointPenaltyStats JointGroupSolver::SolveJointPenalty(const JointGroup& group,
                                                      double h_s) noexcept {
  JointPenaltyStats stats;
  if (!(h_s > 0.0) || !std::isfinite(h_s)) {
    stats.error = JointGroupError::kNonFinite;
    return stats;
  }
  stats.error = Assemble(group);
  if (stats.error != JointGroupError::kNone) return stats;
  inv_h_ = 1.0 / h_s;
  const int n = dofs_;
  const int nrows = static_cast<int>(group.rows.size());
  for (int i = 0; i < rows_; ++i) b_[i] = jac_t_.col(i).head(n).dot(u_.head(n));
  for (int j = 0; j < nrows; ++j) {
    JointRow& row = group.rows[j];
    const int c0 = 3 * j;
    active_[c0] = 1;
    phi_[c0] = row.phi_n_N;
    c_[c0] = std::max(row.c_n_Ns_per_m, 0.0);
    const bool tangential = row.a.kind != RowSideKind::kJoint && row.stick;
    Vec3 t1, t2;
    JointTangents(row.n_W, t1, t2);
    active_[c0 + 1] = active_[c0 + 2] = tangential ? 1 : 0;
    phi_[c0 + 1] = tangential ? row.phi_t_W.dot(t1) : 0.0;
    phi_[c0 + 2] = tangential ? row.phi_t_W.dot(t2) : 0.0;
    c_[c0 + 1] = c_[c0 + 2] = tangential ? std::max(row.c_t_Ns_per_m, 0.0) : 0.0;
    row.slipped = false;
  }
  // each pass drops a row or changes a friction state; the bound keeps the tick's cost bounded
  const int max_passes = 2 * nrows + 8;
  bool settled = false;
  for (int pass = 0; pass < max_passes && !settled; ++pass) {
    ++stats.passes;
    if (!SolveImplicit(h_s)) {
      stats.error = JointGroupError::kNonFinite;
      return stats;
    }
    settled = !UpdateRowStates(group, stats, false);
  }
  if (!settled) {
    // the friction states did not settle: no friction at all keeps every row inside its cone
    stats.frictionless_fallback = true;
    for (int j = 0; j < nrows; ++j) {
      for (int d = 1; d < 3; ++d)
        active_[3 * j + d] = 0, phi_[3 * j + d] = 0.0, c_[3 * j + d] = 0.0;
    }
    for (int pass = 0; pass <= nrows; ++pass) {
      ++stats.passes;
      if (!SolveImplicit(h_s)) {
        stats.error = JointGroupError::kNonFinite;
        return stats;
      }
      if (!UpdateRowStates(group, stats, true)) break;
    }
  }
  // u+ = u + M^-1 J^T (h phi + lambda); J^T f with f = phi + lambda / h
  force_.head(n).setZero();
  for (int i = 0; i < rows_; ++i) {
    const double f = active_[i] || phi_[i] != 0.0 ? phi_[i] + lambda_[i] * inv_h_ : 0.0;
    if (f == 0.0) continue;
    u_.head(n) += (h_s * f) * y_.col(i).head(n);
    force_.head(n) += f * jac_t_.col(i).head(n);
  }
  if (!u_.head(n).allFinite()) {
    stats.error = JointGroupError::kNonFinite;
    return stats;
  }
  for (int j = 0; j < nrows; ++j) {
    JointRow& row = group.rows[j];
    const int c0 = 3 * j;
    Vec3 t1, t2;
    JointTangents(row.n_W, t1, t2);
    row.normal_force_N = active_[c0] ? phi_[c0] + lambda_[c0] * inv_h_ : 0.0;
    row.friction_force_N_W = (phi_[c0 + 1] + lambda_[c0 + 1] * inv_h_) * t1 +
                             (phi_[c0 + 2] + lambda_[c0 + 2] * inv_h_) * t2;
  }
  Scatter(group);
  return stats;
}

// the free set's system W_FF z_F = -b_F (regularised), z = 0 outside it; false if its factor fails
bool JointGroupSolver::SolveFreeSet(int m, int& f) {
  f = 0;
  for (int a = 0; a < m; ++a) {
    if (in_set_[a]) free_[f++] = a;
  }
  for (int a = 0; a < f; ++a) {
    const int i = index_[free_[a]];
    for (int c = 0; c <= a; ++c) k_(a, c) = w_(i, index_[free_[c]]);
    k_(a, a) *= 1.0 + kJointRegularization;
    rhs_[a] = -b_[i];
  }
  if (!JointCholesky(k_, f)) return false;
  JointCholeskySolve(k_, f, rhs_);
  return true;
}

// min 1/2 p^T W_SS p + b_S^T p, p >= 0, over the m rows index_[0..m) (Lawson and Hanson's
// active-set method written for the quadratic program); the answer in p_
bool JointGroupSolver::SolveNonNegative(int m, int& iterations) {
  p_.head(m).setZero();
  for (int a = 0; a < m; ++a) in_set_[a] = 0;
  double v_ref = 0.0;
  for (int a = 0; a < m; ++a) v_ref = std::max(v_ref, std::abs(b_[index_[a]]));
  if (v_ref == 0.0) return true;
  const double tol = 1e-12 * v_ref;
  for (int outer = 0; outer < 3 * m + 30; ++outer) {
    for (int a = 0; a < m; ++a) {
      double g = b_[index_[a]];
      for (int c = 0; c < m; ++c) g += w_(index_[a], index_[c]) * p_[c];
      g_[a] = g;
    }
    int best = -1;
    for (int a = 0; a < m; ++a) {
      if (!in_set_[a] && g_[a] < -tol && (best < 0 || g_[a] < g_[best])) best = a;
    }
    if (best < 0) return true;
    in_set_[best] = 1;
    ++iterations;
    for (int inner = 0;; ++inner) {
      int f = 0;
      if (inner > m || !SolveFreeSet(m, f)) return false;
      z_.head(m).setZero();
      bool positive = true;
      for (int a = 0; a < f; ++a) {
        z_[free_[a]] = rhs_[a];
        positive = positive && rhs_[a] > 0.0;
      }
      if (inner == 0 && !(z_[best] > 0.0)) {
        in_set_[best] = 0;  // degenerate at rounding: nothing left to gain
        return true;
      }
      if (positive) {
        p_.head(m) = z_.head(m);
        break;
      }
      // step towards z until the first free impulse reaches 0; that one leaves the free set
      double alpha = 1.0;
      int blocking = -1;
      for (int a = 0; a < f; ++a) {
        const int k = free_[a];
        if (z_[k] > 0.0) continue;
        const double step = p_[k] / (p_[k] - z_[k]);
        if (blocking < 0 || step < alpha) alpha = step, blocking = k;
      }
      for (int a = 0; a < f; ++a) {
        const int k = free_[a];
        p_[k] += alpha * (z_[k] - p_[k]);
        if (k == blocking || p_[k] <= 0.0) {
          p_[k] = 0.0;
          in_set_[k] = 0;
        }
      }
    }
  }
  return false;
}

JointImpulseStats JointGroupSolver::ApplyJointImpulses(const JointGroup& group) noexcept {
  JointImpulseStats stats;
  const int nrows = static_cast<int>(group.rows.size());
  if (nrows > max_rows_) {
    stats.error = JointGroupError::kTooManyRows;
    return stats;
  }
  int nscales = 0;
  for (JointRow& row : group.rows) {
    row.impulse_Ns = 0.0;
    const double s = row.impulse_scale;
    if (!(s >= 0.0 && s <= 2.0)) {
      stats.error = JointGroupError::kBadScale;
      return stats;
    }
    if (s > 0.0 &&
        std::find(scales_.begin(), scales_.begin() + nscales, s) == scales_.begin() + nscales) {
      scales_[nscales++] = s;
    }
  }
  if (nscales == 0) return stats;
  stats.error = Assemble(group);
  if (stats.error != JointGroupError::kNone) return stats;
  const int n = dofs_;
  // smallest share first: the rows with the largest (a plastic single impulse) end the tick as
  // their rule says, whatever the shares before them did
  std::sort(scales_.begin(), scales_.begin() + nscales);
  double w_max = 0.0;
  for (int j = 0; j < nrows; ++j) {
    b_[3 * j] = jac_t_.col(3 * j).head(n).dot(u_.head(n));
    w_max = std::max(w_max, w_(3 * j, 3 * j));
  }
  for (int q = 0; q < nscales; ++q) {
    const double scale = scales_[q];
    int m = 0;
    for (int j = 0; j < nrows; ++j) {
      const int i = 3 * j;
      if (group.rows[j].impulse_scale == scale && w_(i, i) > kJointInertRow * w_max)
        index_[m++] = i;
    }
    ++stats.solves;
    if (!SolveNonNegative(m, stats.iterations)) {
      stats.converged = false;
      continue;  // this scale's rows get no impulse: the safe answer
    }
    for (int a = 0; a < m; ++a) {
      if (scale >= 1.0) stats.max_approach_mps = std::max(stats.max_approach_mps, -g_[a]);
    }
    for (int a = 0; a < m; ++a) {
      const int i = index_[a];
      const double p_Ns = scale * p_[a];  // Eq. 5 (scale 1 + e) or Eq. 8 (1 / (N - i + 1))
      if (p_Ns <= 0.0) continue;
      group.rows[i / 3].impulse_Ns += p_Ns;
      u_.head(n) += p_Ns * y_.col(i).head(n);  // Eq. 2
      for (int j = 0; j < nrows; ++j) b_[3 * j] += p_Ns * w_(3 * j, i);
    }
  }
  if (!u_.head(n).allFinite()) {
    stats.error = JointGroupError::kNonFinite;
    for (JointRow& row : group.rows) row.impulse_Ns = 0.0;
    return stats;
  }
  Scatter(group);
  return stats;
}

Eigen::Ref<const Eigen::VectorXd> JointGroupSolver::TreeContactForce(int tree) const {
  return force_.segment(tree_offset_[tree], tree_dofs_[tree]);
}

double JointGroupKineticEnergy(const JointGroup& group) {
  double ke_J = KineticEnergy(group.bodies);
  for (const GroupTree& tree : group.trees) ke_J += dynamics::TreeKineticEnergy(*tree.data);
  return ke_J;
}

}  // namespace rigidtouch::contact
