#include "dynamics/velocities.h"

#include <algorithm>

#include "dynamics/rigid_body.h"

namespace rigidtouch::dynamics {
namespace {

// Eq. 1 without contact coupling: v += h F / m, w += h I^-1 tau
void FreeMotion(const Model& model, Data& data, const VelocityScratch& scratch, int i) {
  const double h = model.timestep_s;
  BodyState& s = data.bodies[i];
  s.v_W += h / model.bodies[i].mass_kg * scratch.force_W[i];
  s.w_W += h * WorldInverseInertiaTimes(model.bodies[i], data.R_WB[i], scratch.torque_W[i]);
}

}  // namespace

void VelocityScratch::Reserve(int nbody, int max_contacts, int max_group_bodies, int threads) {
  force_W.resize(nbody);
  torque_W.resize(nbody);
  implicit.resize(max_contacts);
  implicit_start.assign(nbody, 0);
  implicit_end.assign(nbody, 0);
  group_solver.Reserve(max_group_bodies, max_contacts);
  if (threads == 2) worker_solver.Reserve(max_group_bodies, max_contacts);
  kept.Reserve(nbody);
}

GroupSolveCounts VelocityScratch::Counts() const {
  GroupSolveCounts c;
  for (const GroupSolverScratch* s : {&group_solver, &worker_solver}) {
    c.factorisations += s->factorisations;
    c.lagged_solves += s->lagged.lagged_solves;
    c.refinement_steps += s->lagged.refinement_steps;
    c.lagged_failures += s->lagged.lagged_failures;
    c.unkept += s->lagged.unkept;
  }
  return c;
}

void AddFreeMotionForces(const Model& model, const Data& data, const Wrench& user,
                         VelocityScratch& scratch) {
  const int nbody = static_cast<int>(model.bodies.size());
  for (int i = 0; i < nbody; ++i) {
    const BodyModel& b = model.bodies[i];
    const bool compensated = i == model.tool && model.device.coupling != Coupling::kNone;
    scratch.force_W[i] = compensated ? Vec3::Zero() : Vec3(b.mass_kg * model.gravity_W);
    scratch.torque_W[i] =
        ImplicitGyroscopicTorque(b, data.R_WB[i], data.bodies[i].w_W, model.timestep_s);
  }
  scratch.force_W[model.tool] += user.force_N;
  scratch.torque_W[model.tool] += user.torque_Nm;
}

parallel::Task FreeMotionForces::AsTask() {
  return {[](void* context) {
            const auto& f = *static_cast<const FreeMotionForces*>(context);
            AddFreeMotionForces(f.model, f.data, f.user, f.scratch);
          },
          this};
}

void BeginVelocities(VelocityScratch& scratch) {
  scratch.worker_solver.lagged.reuse_factor = scratch.group_solver.lagged.reuse_factor;
  scratch.failed_solves = {0, 0};
}

void SolveGroup(const Model& model, Data& data, const GroupBodies& groups, VelocityScratch& scratch,
                int g, int side) {
  const int nb = groups.body_start[g + 1] - groups.body_start[g];
  const std::span<const int> bodies(groups.bodies.data() + groups.body_start[g], nb);
  const int begin = scratch.implicit_start[g], end = scratch.implicit_end[g];
  bool solved = false;
  if (end > begin) {
    const std::span<ImplicitContact> implicit(scratch.implicit.data() + begin, end - begin);
    GroupSolverScratch& solver = side == 0 ? scratch.group_solver : scratch.worker_solver;
    solved = SolveGroupVelocities(model, data, bodies, groups.slot, implicit, scratch.force_W,
                                  scratch.torque_W, solver, scratch.kept);
    if (solved) {
      // report the implicit forces at the new velocities
      for (const ImplicitContact& ic : implicit) {
        Contact& c = data.contacts[ic.contact];
        c.normal_force_N = std::max(0.0, ic.normal_force_N);
        c.friction_force_N_W += ic.friction_force_N_W;
      }
    } else {
      ++scratch.failed_solves[side];
    }
  }
  if (!solved) {
    for (int i : bodies) FreeMotion(model, data, scratch, i);
  }
}

parallel::ItemTask GroupSolves::AsTask() {
  return {[](void* context, int g, int side) {
            const auto& s = *static_cast<const GroupSolves*>(context);
            SolveGroup(s.model, s.data, s.groups, s.scratch, g, side);
          },
          this};
}

void EndVelocities(const Model& model, Data& data, VelocityScratch& scratch, bool shared) {
  const int nbody = static_cast<int>(model.bodies.size());
  for (int i = 0; i < nbody; ++i) {
    if (data.body_group[i] < 0) FreeMotion(model, data, scratch, i);
  }
  if (shared) ++scratch.shared_steps;
  const int failed = scratch.failed_solves[0] + scratch.failed_solves[1];
  for (int k = 0; k < failed; ++k) data.Warn(Warning::kSolverFailed);
}

void MoveFreely(const Model& model, Data& data, const VelocityScratch& scratch, int i) {
  FreeMotion(model, data, scratch, i);
}

void IntegratePositions(const Model& model, Data& data) {
  for (BodyState& s : data.bodies) IntegratePosition(s, model.timestep_s);
}

}  // namespace rigidtouch::dynamics
