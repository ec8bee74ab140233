// One scene contact of the implicit group solve (group_dynamics.h), used by the
// assembly (group_assembly.h) and the lagged factorisation (lagged_factor.h).
#pragma once

#include <limits>

#include "rigidtouch/types.h"

namespace rigidtouch::dynamics {

/// One scene contact of the implicit solve, at the point p (its offsets from the two bodies'
/// centres of mass are p - x_a and p - x_b), along the unit normal n (from b towards a). Its normal
/// force is phi_n - c_n u_n at the new relative velocity u_n; while it sticks, its tangential
/// force is phi_t - c_t u_t (phi_t and the tangential velocity u_t both in the tangent plane, so
/// this is the two tangential rows of any orthonormal tangent basis at once); while it slips, its
/// tangential force is phi_t alone, the kinetic friction (no tangential rows). The contacts of one
/// friction patch (same `patch`, consecutive) share one Coulomb cone: the solve makes a sticking
/// patch whose forces leave mu_static times its normal force slip, and keeps a slipping patch's
/// kinetic friction within mu_kinetic times its normal force at the new velocities. Forces act
/// +on a, -on b.
struct ImplicitContact {
  int body_a = -1, body_b = -1;  // Model::bodies indices, -1 static
  Vec3 n_W = Vec3::UnitZ();
  Vec3 p_W = Vec3::Zero();
  double phi_n_N = 0.0;       // normal force independent of the new velocity
  double c_n_Ns_per_m = 0.0;  // h k + b: normal force per unit of new approach velocity
  bool stick = false;         // tangential rows present
  // tangential force on a independent of the new velocity, in the tangent plane (n . phi_t = 0):
  // the anchor spring while sticking, the kinetic friction while slipping
  Vec3 phi_t_W = Vec3::Zero();
  double c_t_Ns_per_m = 0.0;
  // c_t of the anchor spring-damper (h kt + bt), kept for a slipping patch that comes to stick
  double c_t_stick_Ns_per_m = 0.0;
  // a slip that one step of kinetic friction reversed faster than this, mu_k phi_n / (kt h),
  // sticks: in one step such a reversal stretches the anchor beyond the slip limit mu_k phi_n / kt,
  // which the next step's decision on the anchor cannot catch (infinite: never)
  double reversal_limit_mps = std::numeric_limits<double>::infinity();
  // the friction patch's cone; infinite: no cone (the tangential rows are never limited)
  double mu_static = std::numeric_limits<double>::infinity();
  double mu_kinetic = std::numeric_limits<double>::infinity();
  int patch = -1;      // friction patch (index of its geom pair's first contact); -1: its own
  int contact = -1;    // index in data.contacts
  bool active = true;  // false once dropped for pulling
  // output at the solved velocities (zero for a dropped contact): the normal force (negative only
  // if it still pulls after the last pass) and the tangential force on a
  double normal_force_N = 0.0;
  Vec3 friction_force_N_W = Vec3::Zero();
  // a slipping contact's kinetic friction times its new relative velocity  [W]: negative while
  // the friction opposes the slip; positive when one step of it reversed the slip (0: sticking)
  double slip_power_W = 0.0;
};

}  // namespace rigidtouch::dynamics
