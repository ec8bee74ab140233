#include "dynamics/group_dynamics.h"

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <algorithm>
#include <cmath>

#include "dynamics/rigid_body.h"

namespace rigidtouch::dynamics {
namespace {

// [r]x, the cross-product matrix: [r]x w = r x w
Mat3 Skew(const Vec3& r) {
  Mat3 m;
  m << 0.0, -r.z(), r.y(), r.z(), 0.0, -r.x(), -r.y(), r.x(), 0.0;
  return m;
}

constexpr int kMaxPasses = 4;

using Mat6 = Eigen::Matrix<double, 6, 6>;
using Vec6 = Eigen::Matrix<double, 6, 1>;

// solves H x = b in place by a Cholesky factorisation over 6 x 6 body blocks, skipping the blocks
// of bodies that share no contact (a column of boxes is block tridiagonal: the cost grows with
// the bodies, not their cube). `mask` (nb x nb, row-major) marks the non-zero blocks and gains the
// fill-in. Fixed-size kernels only: nothing allocates. False if H is not positive definite.
bool BlockCholeskySolve(Eigen::Ref<Eigen::MatrixXd> H, Eigen::Ref<Eigen::VectorXd> x, int nb,
                        std::vector<char>& mask) {
  auto M = [&](int i, int j) -> char& { return mask[static_cast<std::size_t>(i) * nb + j]; };
  for (int k = 0; k < nb; ++k) {
    Eigen::LLT<Mat6> llt(H.block<6, 6>(6 * k, 6 * k));
    if (llt.info() != Eigen::Success) return false;
    const Mat6 L = llt.matrixL();
    H.block<6, 6>(6 * k, 6 * k) = L;
    for (int i = k + 1; i < nb; ++i) {
      if (!M(i, k)) continue;
      // L_ik = H_ik L_kk^-T
      const Mat6 Lik = L.triangularView<Eigen::Lower>()
                           .solve(H.block<6, 6>(6 * i, 6 * k).transpose())
                           .transpose();
      H.block<6, 6>(6 * i, 6 * k) = Lik;
    }
    for (int i = k + 1; i < nb; ++i) {
      if (!M(i, k)) continue;
      for (int j = k + 1; j <= i; ++j) {
        if (!M(j, k)) continue;
        if (!M(i, j)) {  // fill-in: a block that was structurally zero
          H.block<6, 6>(6 * i, 6 * j).setZero();
          M(i, j) = M(j, i) = 1;
        }
        H.block<6, 6>(6 * i, 6 * j).noalias() -=
            H.block<6, 6>(6 * i, 6 * k) * H.block<6, 6>(6 * j, 6 * k).transpose();
      }
    }
  }
  for (int k = 0; k < nb; ++k) {  // L y = b
    Vec6 r = x.segment<6>(6 * k);
    for (int j = 0; j < k; ++j) {
      if (M(k, j)) r.noalias() -= H.block<6, 6>(6 * k, 6 * j) * x.segment<6>(6 * j);
    }
    x.segment<6>(6 * k) = H.block<6, 6>(6 * k, 6 * k).triangularView<Eigen::Lower>().solve(r);
  }
  for (int k = nb - 1; k >= 0; --k) {  // L^T x = y
    Vec6 r = x.segment<6>(6 * k);
    for (int i = k + 1; i < nb; ++i) {
      if (M(i, k)) r.noalias() -= H.block<6, 6>(6 * i, 6 * k).transpose() * x.segment<6>(6 * i);
    }
    x.segment<6>(6 * k) =
        H.block<6, 6>(6 * k, 6 * k).transpose().triangularView<Eigen::Upper>().solve(r);
  }
  return true;
}

}  // namespace

void GroupSolverScratch::Reserve(int max_group_bodies) {
  H.setZero(6 * max_group_bodies, 6 * max_group_bodies);
  x.setZero(6 * max_group_bodies);
  v0.assign(max_group_bodies, Vec3::Zero());
  mask.assign(static_cast<std::size_t>(max_group_bodies) * max_group_bodies, 0);
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
    // only the blocks of bodies that share a contact are non-zero (plus fill-in, zeroed when the
    // factorisation creates it)
    const int nb = static_cast<int>(bodies.size());
    std::fill(scratch.mask.begin(), scratch.mask.begin() + nb * nb, 0);
    for (int k = 0; k < nb; ++k) scratch.mask[k * nb + k] = 1;
    for (const ImplicitRow& r : rows) {
      if (r.active && r.body_a >= 0 && r.body_b >= 0) {
        scratch.mask[slot[r.body_a] * nb + slot[r.body_b]] = 1;
        scratch.mask[slot[r.body_b] * nb + slot[r.body_a]] = 1;
      }
    }
    for (int i = 0; i < nb; ++i) {
      for (int j = 0; j < nb; ++j) {
        if (scratch.mask[i * nb + j]) H.block<6, 6>(6 * i, 6 * j).setZero();
      }
    }
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
    // per contact: its normal row and the tangential rows after it share the points, so
    // sum_r c_r J_r^T J_r = J^T C J with C = sum_r c_r d_r d_r^T (3 x 3) and J = [I, -[r]x]:
    // J_a^T C J_b = [[C, -C R_b], [R_a C, -R_a C R_b]] with R = [r]x, a few 3 x 3 products
    // instead of one 6 x 6 outer product per row and body pair
    for (std::size_t i = 0; i < rows.size();) {
      std::size_t end = i + 1;
      while (end < rows.size() && rows[end].normal_row == static_cast<int>(i)) ++end;
      Mat3 C = Mat3::Zero();
      Vec3 f = Vec3::Zero();
      for (std::size_t k = i; k < end; ++k) {
        const ImplicitRow& r = rows[k];
        if (!r.active) continue;
        C.noalias() += (h * r.c_Ns_per_m) * r.d_W * r.d_W.transpose();
        f += (h * r.phi_N) * r.d_W;
      }
      const ImplicitRow& r = rows[i];
      i = end;
      if (f.isZero(0.0) && C.isZero(0.0)) continue;
      const int sa = r.body_a >= 0 ? 6 * slot[r.body_a] : -1;
      const int sb = r.body_b >= 0 ? 6 * slot[r.body_b] : -1;
      const Mat3 Ra = Skew(r.r_a_W), Rb = Skew(r.r_b_W);
      const Mat3 CRb = C * Rb, RaC = Ra * C;
      if (sa >= 0) {
        const Mat3 CRa = C * Ra;
        H.block<3, 3>(sa, sa) += C;
        H.block<3, 3>(sa, sa + 3) -= CRa;
        H.block<3, 3>(sa + 3, sa) += RaC;
        H.block<3, 3>(sa + 3, sa + 3).noalias() -= Ra * CRa;
        x.segment<3>(sa) += f;
        x.segment<3>(sa + 3) += Ra * f;  // r_a x f
      }
      if (sb >= 0) {
        const Mat3 RbC = Rb * C;
        H.block<3, 3>(sb, sb) += C;
        H.block<3, 3>(sb, sb + 3) -= CRb;
        H.block<3, 3>(sb + 3, sb) += RbC;
        H.block<3, 3>(sb + 3, sb + 3).noalias() -= Rb * CRb;
        x.segment<3>(sb) -= f;
        x.segment<3>(sb + 3) -= Rb * f;
      }
      if (sa >= 0 && sb >= 0) {
        // J_a^T C (-J_b) and its transpose
        H.block<3, 3>(sa, sb) -= C;
        H.block<3, 3>(sa, sb + 3) += CRb;
        H.block<3, 3>(sa + 3, sb) -= RaC;
        H.block<3, 3>(sa + 3, sb + 3).noalias() += Ra * CRb;
        H.block<6, 6>(sb, sa) = H.block<6, 6>(sa, sb).transpose();
      }
    }
    if (!BlockCholeskySolve(H, x, nb, scratch.mask) || !x.allFinite()) return false;
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
