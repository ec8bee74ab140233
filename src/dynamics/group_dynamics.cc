#include "dynamics/group_dynamics.h"

#include <cmath>

#include "dynamics/rigid_body.h"

namespace rigidtouch::dynamics {
namespace {

using Vec6 = Eigen::Matrix<double, 6, 1>;

Vec6 RowJacobian(const Vec3& d, const Vec3& r) {
  Vec6 j;
  j << d, r.cross(d);  // velocity of the point along d: d.v + (r x d).w
  return j;
}

constexpr int kMaxPasses = 4;

// in-place Cholesky H = L L^T (lower triangle) and solve L L^T x = b, over preallocated storage.
// Eigen's LLT switches to a blocked product above a few dozen rows whose blocking buffers come
// from the heap; this loop never allocates. Returns false if H is not positive definite.
bool CholeskySolve(Eigen::Ref<Eigen::MatrixXd> H, Eigen::Ref<Eigen::VectorXd> x) {
  const int n = static_cast<int>(H.rows());
  for (int j = 0; j < n; ++j) {
    double d = H(j, j);
    for (int k = 0; k < j; ++k) d -= H(j, k) * H(j, k);
    if (!(d > 0.0)) return false;
    d = std::sqrt(d);
    H(j, j) = d;
    for (int i = j + 1; i < n; ++i) {
      double s = H(i, j);
      for (int k = 0; k < j; ++k) s -= H(i, k) * H(j, k);
      H(i, j) = s / d;
    }
  }
  for (int i = 0; i < n; ++i) {  // L y = b
    double s = x(i);
    for (int k = 0; k < i; ++k) s -= H(i, k) * x(k);
    x(i) = s / H(i, i);
  }
  for (int i = n - 1; i >= 0; --i) {  // L^T x = y
    double s = x(i);
    for (int k = i + 1; k < n; ++k) s -= H(k, i) * x(k);
    x(i) = s / H(i, i);
  }
  return true;
}

}  // namespace

void GroupSolverScratch::Reserve(int max_group_bodies) {
  H.setZero(6 * max_group_bodies, 6 * max_group_bodies);
  x.setZero(6 * max_group_bodies);
  v0.assign(max_group_bodies, Vec3::Zero());
  w0.assign(max_group_bodies, Vec3::Zero());
}

double RowVelocity(const Data& data, const ImplicitRow& row) {
  double u = 0.0;
  if (row.body_a >= 0) u += row.d_W.dot(PointVelocity(data.bodies[row.body_a], row.r_a_W));
  if (row.body_b >= 0) u -= row.d_W.dot(PointVelocity(data.bodies[row.body_b], row.r_b_W));
  return u;
}

bool SolveGroupVelocities(const Model& model, Data& data, std::span<const int> bodies,
                          std::span<const int> slot, std::span<ImplicitRow> rows,
                          std::span<const Vec3> force_W, std::span<const Vec3> torque_W,
                          GroupSolverScratch& scratch) {
  const double h = model.timestep_s;
  const int n = 6 * static_cast<int>(bodies.size());
  for (std::size_t k = 0; k < bodies.size(); ++k) {
    scratch.v0[k] = data.bodies[bodies[k]].v_W;
    scratch.w0[k] = data.bodies[bodies[k]].w_W;
  }
  for (int pass = 0; pass < kMaxPasses; ++pass) {
    auto H = scratch.H.topLeftCorner(n, n);
    auto x = scratch.x.head(n);
    H.setZero();
    for (std::size_t k = 0; k < bodies.size(); ++k) {
      const int i = bodies[k];
      const BodyModel& bm = model.bodies[i];
      const BodyState& s = data.bodies[i];
      const int o = 6 * static_cast<int>(k);
      const Mat3 I = WorldInertia(bm, s);
      H.block<3, 3>(o, o).diagonal().setConstant(bm.mass_kg);
      H.block<3, 3>(o + 3, o + 3) = I;
      x.segment<3>(o) = bm.mass_kg * scratch.v0[k] + h * force_W[i];
      x.segment<3>(o + 3) = I * scratch.w0[k] + h * torque_W[i];
    }
    for (const ImplicitRow& r : rows) {
      if (!r.active) continue;
      const int sa = r.body_a >= 0 ? 6 * slot[r.body_a] : -1;
      const int sb = r.body_b >= 0 ? 6 * slot[r.body_b] : -1;
      const Vec6 ja = RowJacobian(r.d_W, r.r_a_W);
      const Vec6 jb = -RowJacobian(r.d_W, r.r_b_W);
      const double hc = h * r.c_Ns_per_m;
      if (sa >= 0) {
        H.block<6, 6>(sa, sa).noalias() += hc * ja * ja.transpose();
        x.segment<6>(sa) += h * r.phi_N * ja;
      }
      if (sb >= 0) {
        H.block<6, 6>(sb, sb).noalias() += hc * jb * jb.transpose();
        x.segment<6>(sb) += h * r.phi_N * jb;
      }
      if (sa >= 0 && sb >= 0) {
        H.block<6, 6>(sa, sb).noalias() += hc * ja * jb.transpose();
        H.block<6, 6>(sb, sa).noalias() += hc * jb * ja.transpose();
      }
    }
    if (!CholeskySolve(H, x) || !x.allFinite()) return false;
    // write the candidate velocities, then check that no normal row pulls
    for (std::size_t k = 0; k < bodies.size(); ++k) {
      BodyState& s = data.bodies[bodies[k]];
      s.v_W = x.segment<3>(6 * k);
      s.w_W = x.segment<3>(6 * k + 3);
    }
    bool pulled = false;
    for (ImplicitRow& r : rows) {
      if (!r.active || r.normal_row >= 0) continue;
      if (r.phi_N - r.c_Ns_per_m * RowVelocity(data, r) < 0.0) {
        r.active = false;
        pulled = true;
      }
    }
    if (!pulled) return true;
    // a contact that stops pushing has no friction either; solve again without them
    for (ImplicitRow& r : rows) {
      if (r.normal_row >= 0 && !rows[r.normal_row].active) r.active = false;
    }
  }
  return true;  // the last pass's velocities stand; rows still pulling are reported as zero
}

}  // namespace rigidtouch::dynamics
