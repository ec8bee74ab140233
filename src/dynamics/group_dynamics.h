// Velocity update of one contact group (tick stage 5): Eq. 1 over the step with penalty contact.
//
// Tool contacts are explicit (a device can only render forces from its current state). Scene
// contacts are linearly implicit (backward Euler): a row with force phi - c (J v+) gives
//   (M + h sum c J^T J) v+ = M v + h F + h sum phi J^T,
// so a stack of 0.1 kg boxes can use a stiffness of 2e5 N/m at h = 1 ms without going unstable.
#pragma once

#include <Eigen/Core>
#include <span>
#include <vector>

#include "rigidtouch/data.h"
#include "rigidtouch/model.h"

namespace rigidtouch::dynamics {

/// A force row of the implicit solve: force phi - c (J v+) along `d_W`, acting +d on a, -d on b.
struct ImplicitRow {
  int body_a = -1, body_b = -1;  // Model::bodies indices, -1 static
  Vec3 d_W = Vec3::UnitZ();      // unit direction
  Vec3 r_a_W = Vec3::Zero();     // application point from a's / b's centre of mass
  Vec3 r_b_W = Vec3::Zero();
  double phi_N = 0.0;       // force independent of the new velocity
  double c_Ns_per_m = 0.0;  // h k + b: force per unit of new relative velocity along d
  int contact = -1;         // index in data.contacts
  int normal_row = -1;      // for a tangential row, index of its contact's normal row
  bool active = true;
};

/// Dense scratch for one group's solve, sized for the largest allowed group.
struct GroupSolverScratch {
  Eigen::MatrixXd H;         // (6 nb x 6 nb) system matrix
  Eigen::VectorXd x;         // (6 nb) right-hand side, then the new velocities
  std::vector<Vec3> v0, w0;  // (nb) start-of-step velocities, kept across passes
  std::vector<char> mask;    // (nb x nb) non-zero 6 x 6 blocks of H, with fill-in
  void Reserve(int max_group_bodies);
};

/// Relative velocity along d of a row's points, (v_a + w_a x r_a) - (v_b + w_b x r_b).
double RowVelocity(const Data& data, const ImplicitRow& row);

/// Solves the new velocities of the group's bodies, in place in data.bodies. `force_W` and
/// `torque_W` hold each body's explicit force (gravity, user, gyroscopic, explicit contacts).
/// Normal rows that would pull after the solve are dropped and the solve repeated (at most a few
/// times), so the penalty never pulls. Returns false if the factorisation failed (then nothing
/// is written).
bool SolveGroupVelocities(const Model& model, Data& data, std::span<const int> bodies,
                          std::span<const int> slot, std::span<ImplicitRow> rows,
                          std::span<const Vec3> force_W, std::span<const Vec3> torque_W,
                          GroupSolverScratch& scratch);

}  // namespace rigidtouch::dynamics
