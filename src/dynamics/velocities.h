// Free-motion forces and the velocity update (tick stages 4-5), and the position update (stage
// 7): Eq. 1 over one step h for every dynamic body.
#pragma once

#include <array>
#include <span>
#include <vector>

#include "dynamics/group_dynamics.h"
#include "parallel/worker.h"
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
  // threads 2: the solver scratch of the groups the worker's side of the range takes (SolveGroup)
  GroupSolverScratch worker_solver;
  KeptFactors kept;                    // every group's kept factor, whichever thread solves it
  std::array<int, 2> failed_solves{};  // this step's failed group solves, by side
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
  parallel::Task AsTask();
};

/// Stage 5's start, before stage 3 (ClassifyAndForces) solves the groups: the worker's solver
/// takes the tick's settings, and no solve has failed yet.
void BeginVelocities(VelocityScratch& scratch);

/// The contact groups as the group solve reads them: group g's bodies are
/// bodies[body_start[g] .. body_start[g + 1]), and slot[i] is body i's place in its group. Spans
/// over the lists stage 3 builds (contact::Groups, sized once), so dynamics needs nothing of
/// contact's.
struct GroupBodies {
  std::span<const int> body_start;  // (ngroup + 1)
  std::span<const int> bodies;      // (nbody)
  std::span<const int> slot;        // (nbody)
};

/// Stage 5 for group g, run by stage 3-4's shared range right after the group's forces (as
/// GroupSolves::AsTask), while its implicit contacts are in the cache of the thread that wrote
/// them: a group with implicit contacts is solved by SolveGroupVelocities with side 0's solver
/// scratch (the tick's thread's) or side 1's (the worker's); if that fails (counted, a
/// Warning::kSolverFailed in EndVelocities) and for a group without implicit contacts, its bodies
/// move freely under their explicit forces. Writes each implicit contact's forces at the new
/// velocities back into data.contacts. Groups share no body or contact, and each group's kept
/// factor is stored with its bodies, whichever side solved it, so every result is the same bit
/// for bit on one thread or two.
void SolveGroup(const Model& model, Data& data, const GroupBodies& groups, VelocityScratch& scratch,
                int g, int side);

/// SolveGroup's arguments, for running it as the stage 3-4 range's task after each group.
struct GroupSolves {
  const Model& model;
  Data& data;
  GroupBodies groups;
  VelocityScratch& scratch;
  /// A task that calls SolveGroup with these arguments (this object must outlive it).
  parallel::ItemTask AsTask();
};

/// Stage 5's end: every body in no group moves freely under its explicit force, and the failed
/// group solves are counted as warnings. `shared`: the groups were split between the threads
/// (counted in shared_steps).
void EndVelocities(const Model& model, Data& data, VelocityScratch& scratch, bool shared);

/// Body i moves freely over the step under its explicit force sums (Eq. 1 without contact
/// coupling): what EndVelocities does for a body in no group; the groups with a tree (contact::
/// SolveTreeGroups) start their bodies' solve from it.
void MoveFreely(const Model& model, Data& data, const VelocityScratch& scratch, int i);

/// Stage 7: semi-implicit Euler position update of every body with its new velocity.
void IntegratePositions(const Model& model, Data& data);

}  // namespace rigidtouch::dynamics
