// Collision impulses for one contact group (Eq. 2-5, Eq. 8), on compact solver rows.
//
// A group is packed into SolverBody (dynamic bodies only) and SolverRow (one frictionless contact
// each, Eq. 3). Static geometry is a body index of -1 and has infinite mass.
#pragma once

#include <Eigen/Core>
#include <span>

#include "rigidtouch/types.h"

namespace rigidtouch::contact {

/// A dynamic body of a contact group, packed for the impulse solver; world frame (W), at the
/// centre of mass.
struct SolverBody {
  double inv_mass = 0.0;              // 1 / m  [1/kg]
  Mat3 inv_inertia_W = Mat3::Zero();  // I^-1 in world frame  [1/(kg m^2)]
  Vec3 v_W = Vec3::Zero();            // linear velocity of the centre of mass  [m/s]
  Vec3 w_W = Vec3::Zero();            // angular velocity  [rad/s]
};

/// One frictionless contact row (Eq. 3). A normal impulse p >= 0 acts as +p n on body a and -p n
/// on body b, at the contact point. Body indices refer to the group's SolverBody array; -1 means
/// static geometry. The relative normal velocity Jc v is n . (v_a + w_a x r_a - v_b - w_b x r_b);
/// negative means approaching.
struct SolverRow {
  int body_a = -1;
  int body_b = -1;
  Vec3 n_W = Vec3::UnitZ();   // unit normal, pointing from b towards a
  Vec3 r_a_W = Vec3::Zero();  // contact point from a's centre of mass  [m]
  Vec3 r_b_W = Vec3::Zero();  // contact point from b's centre of mass  [m]
};

/// A read-only view of one group's impulse problem.
struct ImpulseProblem {
  std::span<const SolverBody> bodies;
  std::span<const SolverRow> rows;
};

}  // namespace rigidtouch::contact
