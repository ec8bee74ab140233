// Velocity update of one contact group (tick stage 5): Eq. 1 over the step with penalty contact.
//
// Tool contacts are explicit (a device can only render forces from its current state). Scene
// contacts are linearly implicit (backward Euler): a row with force phi - c (J v+) gives
//   (M + h sum c J^T J) v+ = M v + h F + h sum phi J^T,
// so a stack of 0.1 kg boxes can use a stiffness of 2e5 N/m at h = 1 ms without going unstable.
//
// Each contact is a normal row and, while it sticks, two tangential rows; the contacts of one
// face-face manifold share their blocks' assembly (AssemblePatch). The system is solved by a
// sparse Cholesky factorisation over 6 x 6 body blocks: only bodies
// that share a contact couple, the bodies are eliminated in minimum-degree order (a column of
// boxes is a chain and factors without fill-in; a leaning pile is a 3-D lattice where the order
// keeps the fill small), and the kernels are fixed-size 6 x 6 loops that never allocate.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "rigidtouch/data.h"
#include "rigidtouch/model.h"

namespace rigidtouch::dynamics {

using Mat6 = Eigen::Matrix<double, 6, 6>;
using Vec6 = Eigen::Matrix<double, 6, 1>;

/// One scene contact of the implicit solve, at the point p (its offsets from the two bodies'
/// centres of mass are p - x_a and p - x_b), along the unit normal n (from b towards a). Its normal
/// force is phi_n - c_n u_n at the new relative velocity u_n; while it sticks, its tangential
/// force is phi_t - c_t u_t (phi_t and the tangential velocity u_t both in the tangent plane, so
/// this is the two tangential rows of any orthonormal tangent basis at once). Forces act +on a,
/// -on b.
struct ImplicitContact {
  int body_a = -1, body_b = -1;  // Model::bodies indices, -1 static
  Vec3 n_W = Vec3::UnitZ();
  Vec3 p_W = Vec3::Zero();
  double phi_n_N = 0.0;       // normal force independent of the new velocity
  double c_n_Ns_per_m = 0.0;  // h k + b: normal force per unit of new approach velocity
  bool stick = false;         // tangential rows present
  // tangential force on a independent of the new velocity, in the tangent plane (n . phi_t = 0)
  Vec3 phi_t_W = Vec3::Zero();
  double c_t_Ns_per_m = 0.0;
  int contact = -1;    // index in data.contacts
  bool active = true;  // false once dropped for pulling
  // output at the solved velocities (zero for a dropped contact): the normal force (negative only
  // if it still pulls after the last pass) and the tangential force on a
  double normal_force_N = 0.0;
  Vec3 friction_force_W = Vec3::Zero();
};

/// Scratch for one group's solve, sized once for the largest allowed group; reused every tick.
struct GroupSolverScratch {
  int max_bodies = 0, max_contacts = 0, max_blocks = 0;
  // per body, by elimination position: the assembled diagonal block (then its factor),
  // 1 / diag(L), the right-hand side and then the solution
  std::vector<Mat6> diag_A;
  std::vector<Vec6> diag_inv, b, x;
  std::vector<int> pos;  // group slot -> elimination position
  // the factor's below-diagonal blocks, column by column (CSR over positions): rows ascending
  std::vector<int> col_start, col_row;
  std::vector<Mat6> off_A;  // (max_blocks) assembled off-diagonal blocks, then the factor's
  std::vector<int> block;   // (max_bodies^2) block index of (i, j), i > j positions; -1
  std::vector<char> adj;    // (max_bodies^2) elimination graph over group slots
  std::vector<int> degree;
  std::vector<char> eliminated;
  // the group's structure (StructureOf: slot pairs that share a contact) and the structure the
  // analysis above (pos, col_start, col_row, block) was made for: reused while they are equal
  std::vector<std::uint64_t> pairs, analysed_pairs;
  std::vector<int> patch_range;  // (2 max_contacts) the assembled patches' [begin, end)
  int npatch = 0;
  int npairs = 0, analysed_npairs = -1, analysed_nb = -1;
  // the lagged factorisation: while a group keeps its bodies, patches, stick states and
  // coefficients, the factor of an earlier step's system solves this step's by iterative
  // refinement (the result is accepted only when its residual bounds the velocity error, see
  // SolveGroupVelocities). false: every solve factors afresh.
  bool reuse_factor = true;
  bool factor_valid = false;
  // a patch's key: its two bodies (unordered), point count, stick state and coefficients; a
  // system's keys sorted, so that neither the patches' order nor which body is a matters
  using PatchKey = std::array<std::uint64_t, 2>;
  std::vector<PatchKey> patch_keys, factor_keys;  // (max_contacts) this solve's, the factor's
  int factor_nb = 0, factor_npatch = 0;
  std::vector<int> factor_bodies;     // (max_bodies)
  std::vector<Mat3> rotation;         // (max_bodies) the bodies' rotation matrices, by position
  int lag_backoff = 0, lag_skip = 0;  // after failed refinements: solves left without a try
  // counters since Reserve: solves that factored (each pass counts), solves by a kept factor,
  // the refinement's corrections over those, and refinements given up (then factored)
  long factorisations = 0, lagged_solves = 0, refinement_steps = 0, lagged_failures = 0;
  void Reserve(int max_group_bodies, int max_contacts);
  /// Drops the kept factor and the back-off, so that the next solves are those of a new scratch
  /// (ResetData: a run from the start repeats bit for bit).
  void ForgetFactor() {
    factor_valid = false;
    lag_backoff = lag_skip = 0;
  }
};

/// Solves the new velocities of the group's bodies, in place in data.bodies. `force_W` and
/// `torque_W` hold each body's explicit force (gravity, user, gyroscopic, explicit contacts).
/// Contacts whose normal force would pull after the solve are dropped (friction included) and
/// the solve repeated (at most a few times), so the penalty never pulls. Each contact's forces at
/// the new velocities are left in it. Returns false if the group exceeds the scratch's capacity
/// or the factorisation failed (then nothing is written). The ordering and fill-in analysis is
/// kept in the scratch and reused while the group's bodies touch the same neighbours.
///
/// With scratch.reuse_factor, a group whose system keeps its shape from the last solve (same
/// bodies, patches, stick states and coefficients; only the contacts' geometry and forces moved)
/// is solved with that solve's factorisation by iterative refinement from the current velocities.
/// Its result x is accepted only if the residual r of the momentum balance bounds the error in
/// the kinetic-energy norm, sqrt((x - x*)^T M (x - x*)) <= |r|_M^-1 <= 1e-10 (|M v| + |h F| +
/// |r(v)|) (A >= M, so A^-1 <= M^-1), within two corrections and with no contact pulling;
/// otherwise the system is assembled and factored as without it, and the kept factor is not
/// tried again for the next 1, 3, 7, ... (at most 63) solves. This pays off where contact rests
/// (a stack, a pile, an object held still), where the step changes the system little; a group
/// in fast motion factors every step.
bool SolveGroupVelocities(const Model& model, Data& data, std::span<const int> bodies,
                          std::span<const int> slot, std::span<ImplicitContact> contacts,
                          std::span<const Vec3> force_W, std::span<const Vec3> torque_W,
                          GroupSolverScratch& scratch);

}  // namespace rigidtouch::dynamics
