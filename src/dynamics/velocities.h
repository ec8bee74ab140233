// Free-motion forces and the velocity update (tick stages 4-5), and the position update (stage
// 7): Eq. 1 over one step h for every dynamic body.
#pragma once

#include <span>
#include <vector>

#include "contact/groups.h"
#include "dynamics/group_dynamics.h"
#include "geometry/worker.h"
#include "rigidtouch/data.h"
#include "rigidtouch/model.h"

namespace rigidtouch::dynamics {

/// The group solvers' counters (GroupSolverScratch, LaggedFactor), both threads' together.
struct GroupSolveCounts {
  long factorisations = 0, lagged_solves = 0, refinement_steps = 0, lagged_failures = 0, unkept = 0;
  GroupSolveCounts operator-(const GroupSolveCounts& o) const {
    return {factorisations - o.factorisations, lagged_solves - o.lagged_solves,
            refinement_steps - o.refinement_steps, lagged_failures - o.lagged_failures,
            unkept - o.unkept};
  }
};

/// Explicit forces of this tick and the implicit contacts of each group, sized once by Reserve.
struct VelocityScratch {
  std::vector<Vec3> force_W, torque_W;    // (nbody) explicit force [N] and torque [N m]
  std::vector<ImplicitContact> implicit;  // (max_contacts) implicit contacts, group by group
  std::vector<int> implicit_start;        // (nbody) group g's: [start[g], end[g])
  std::vector<int> implicit_end;          // (nbody)
  GroupSolverScratch group_solver;
  // threads 2: the worker's solver scratch, and the job it is given (UpdateVelocities)
  GroupSolverScratch worker_solver;
  KeptFactors kept;  // every group's kept factor, whichever thread solves it
  struct GroupJob {
    const Model* model = nullptr;
    Data* data = nullptr;
    const contact::Groups* groups = nullptr;
    VelocityScratch* scratch = nullptr;
    int failed = 0;  // the worker's solves that failed (counted as warnings afterwards)
  };
  GroupJob job;
  geometry::TwoEndedRange shared_groups;  // the groups of a shared step
  long shared_steps = 0;  // steps whose groups were split between the threads (since Reserve)

  /// Sizes every buffer (the worker's solver scratch too with threads 2); the only allocating
  /// call.
  void Reserve(int nbody, int max_contacts, int max_group_bodies, int threads = 1);
  /// The counters since Reserve, both solver scratches' together.
  GroupSolveCounts Counts() const;
  /// Drops the kept factors and their back-off (KeptFactors::Forget).
  void ForgetFactors() { kept.Forget(); }
  /// Adds a contact force f_on_a acting +on a and -on b at offsets r_a, r_b.
  void AddContactForce(const Contact& c, const Vec3& f_on_a, const Vec3& r_a, const Vec3& r_b) {
    if (c.body_a >= 0) {
      force_W[c.body_a] += f_on_a;
      torque_W[c.body_a] += r_a.cross(f_on_a);
    }
    if (c.body_b >= 0) {
      force_W[c.body_b] -= f_on_a;
      torque_W[c.body_b] -= r_b.cross(f_on_a);
    }
  }
};

/// Starts stage 4's force sums: gravity and the gyroscopic torque of Eq. 1 on every body (the
/// implicit-midpoint step's equivalent torque, ImplicitGyroscopicTorque, so that free flight keeps
/// its kinetic energy and |L|), and the user wrench on the tool. A tool held through a device is
/// gravity-compensated like the device.
void AddFreeMotionForces(const Model& model, const Data& data, const Wrench& user,
                         VelocityScratch& scratch);

/// AddFreeMotionForces's arguments, for running it as a task alongside another stage's shared
/// work (it reads only the model, the bodies' rotations and angular velocities, and the user
/// wrench, and writes only the scratch's force sums).
struct FreeMotionForces {
  const Model& model;
  const Data& data;
  const Wrench& user;
  VelocityScratch& scratch;
  /// A task that calls AddFreeMotionForces with these arguments (this object must outlive it).
  geometry::Task AsTask();
};

/// Stage 5: the new velocities. A group with implicit contacts is solved by SolveGroupVelocities
/// (Warning::kSolverFailed, then free motion, if that fails); every other body moves freely under
/// its explicit force. Writes each implicit contact's forces at the new velocities back into
/// data.contacts.
///
/// With a worker (threads 2) and at least two groups to solve, this thread takes groups from the
/// front and the worker from the back (its own solver scratch) until they meet. The groups share
/// no body or contact, and each group's kept factor is stored with its bodies, whichever thread
/// solved it, so every result is the same bit for bit.
void UpdateVelocities(const Model& model, Data& data, const contact::Groups& groups,
                      VelocityScratch& scratch, geometry::Worker* worker = nullptr);

/// Stage 7: semi-implicit Euler position update of every body with its new velocity.
void IntegratePositions(const Model& model, Data& data);

}  // namespace rigidtouch::dynamics
