// Solver scratch owned by Data: sized once by MakeData, reused every tick.
#pragma once

#include <memory>
#include <vector>

#include "contact/groups.h"
#include "contact/impulse.h"
#include "contact/impulse_solver.h"
#include "contact/penalty.h"
#include "dynamics/group_dynamics.h"
#include "geometry/collision.h"

namespace rigidtouch {

struct Workspace {
  geometry::CollisionScratch collision;  // broad and narrow phase scratch
  contact::Groups groups;
  std::vector<contact::PenaltyLaw> laws;            // (max_contacts)
  std::vector<Vec3> anchor_displacement;            // (max_contacts) stick-anchor stretch
  std::vector<double> normal_velocity;              // (max_contacts) approach speed of new contacts
  std::vector<Vec3> force_W, torque_W;              // (nbody) explicit force and torque this tick
  std::vector<dynamics::ImplicitContact> implicit;  // (max_contacts) implicit contacts of a group
  dynamics::GroupSolverScratch group_solver;
  std::vector<contact::SolverBody> solver_bodies;  // (max_group_bodies)
  std::vector<contact::SolverRow> solver_rows;     // (max_contacts)
  std::vector<double> impulses;                    // (max_contacts)
  std::unique_ptr<contact::ImpulseSolver> impulse_solver;
};

}  // namespace rigidtouch
