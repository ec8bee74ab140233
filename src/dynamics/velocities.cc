#include "dynamics/velocities.h"

#include <algorithm>
#include <utility>

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

// solves groups [begin, end) with `solver` (a group whose solve fails moves freely) and returns
// how many failed; counts no warning, so that the worker can run it
int SolveGroups(const Model& model, Data& data, const contact::Groups& groups,
                VelocityScratch& scratch, GroupSolverScratch& solver, int first, int last) {
  int failed = 0;
  for (int g = first; g < last; ++g) {
    const int nb = groups.body_start[g + 1] - groups.body_start[g];
    const std::span<const int> bodies(groups.bodies.data() + groups.body_start[g], nb);
    const int begin = scratch.implicit_start[g], end = scratch.implicit_end[g];
    bool solved = false;
    if (end > begin) {
      const std::span<ImplicitContact> implicit(scratch.implicit.data() + begin, end - begin);
      solved = SolveGroupVelocities(model, data, bodies, groups.slot, implicit, scratch.force_W,
                                    scratch.torque_W, solver, scratch.kept);
      if (solved) {
        // report the implicit forces at the new velocities
        for (const ImplicitContact& ic : implicit) {
          Contact& c = data.contacts[ic.contact];
          c.normal_force_N = std::max(0.0, ic.normal_force_N);
          c.friction_force_W += ic.friction_force_W;
        }
      } else {
        ++failed;
      }
    }
    if (!solved) {
      for (int i : bodies) FreeMotion(model, data, scratch, i);
    }
  }
  return failed;
}

// The worker's part: groups taken from the back.
void RunGroupJob(void* context) {
  auto* job = static_cast<VelocityScratch::GroupJob*>(context);
  VelocityScratch& s = *job->scratch;
  for (int g = s.shared_groups.TakeBack(); g >= 0; g = s.shared_groups.TakeBack()) {
    job->failed += SolveGroups(*job->model, *job->data, *job->groups, s, s.worker_solver, g, g + 1);
  }
}

// fewer implicit contacts than this are not worth the hand-off to the worker
constexpr int kMinContactsForTwoThreads = 64;

// whether the groups are worth sharing with the worker: two or more with implicit contacts, and
// enough implicit contacts
bool WorthSharing(const contact::Groups& groups, const VelocityScratch& scratch) {
  int solved = 0, implicit = 0;
  for (int g = 0; g < groups.ngroup; ++g) {
    const int n = scratch.implicit_end[g] - scratch.implicit_start[g];
    solved += n > 0 ? 1 : 0;
    implicit += n;
  }
  return solved >= 2 && implicit >= kMinContactsForTwoThreads;
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

geometry::Task FreeMotionForces::AsTask() {
  return {[](void* context) {
            const auto& f = *static_cast<const FreeMotionForces*>(context);
            AddFreeMotionForces(f.model, f.data, f.user, f.scratch);
          },
          this};
}

void UpdateVelocities(const Model& model, Data& data, const contact::Groups& groups,
                      VelocityScratch& scratch, geometry::Worker* worker) {
  const int nbody = static_cast<int>(model.bodies.size());
  for (int i = 0; i < nbody; ++i) {
    if (data.body_group[i] < 0) FreeMotion(model, data, scratch, i);
  }
  if (worker == nullptr || !WorthSharing(groups, scratch)) {
    const int failed =
        SolveGroups(model, data, groups, scratch, scratch.group_solver, 0, groups.ngroup);
    for (int k = 0; k < failed; ++k) data.Warn(Warning::kSolverFailed);
    return;
  }
  // no state crosses groups (each keeps its factor with its bodies), so either thread may solve
  // any group
  scratch.worker_solver.lagged.reuse_factor = scratch.group_solver.lagged.reuse_factor;
  scratch.shared_groups.Reset(0, groups.ngroup);
  scratch.job = {&model, &data, &groups, &scratch, 0};
  worker->Post(&RunGroupJob, &scratch.job);
  int failed = 0;
  for (int g = scratch.shared_groups.TakeFront(); g >= 0; g = scratch.shared_groups.TakeFront()) {
    failed += SolveGroups(model, data, groups, scratch, scratch.group_solver, g, g + 1);
  }
  worker->Finish();
  failed += scratch.job.failed;
  ++scratch.shared_steps;
  for (int k = 0; k < failed; ++k) data.Warn(Warning::kSolverFailed);
}

void IntegratePositions(const Model& model, Data& data) {
  for (BodyState& s : data.bodies) IntegratePosition(s, model.timestep_s);
}

}  // namespace rigidtouch::dynamics
