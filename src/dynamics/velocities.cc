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
    const int begin = scratch.implicit_start[g], end = scratch.implicit_start[g + 1];
    bool solved = false;
    if (end > begin) {
      const std::span<ImplicitContact> implicit(scratch.implicit.data() + begin, end - begin);
      solved = SolveGroupVelocities(model, data, bodies, groups.slot, implicit, scratch.force_W,
                                    scratch.torque_W, solver);
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

// whether SolveGroupVelocities takes group g on (and so sets its scratch's kept factor)
bool Solved(const contact::Groups& groups, const VelocityScratch& scratch, int g) {
  const int nc = scratch.implicit_start[g + 1] - scratch.implicit_start[g];
  const int nb = groups.body_start[g + 1] - groups.body_start[g];
  return nc > 0 && nb <= scratch.group_solver.max_bodies && nc <= scratch.group_solver.max_contacts;
}

// The worker's part: groups taken from the back. The first solved group it takes, the highest
// solved group of the step, is solved last, so that the worker's scratch ends the step with that
// group's factor state, as one thread's would.
void RunGroupJob(void* context) {
  auto* job = static_cast<VelocityScratch::GroupJob*>(context);
  VelocityScratch& s = *job->scratch;
  int last = -1;
  for (int g = s.shared_groups.TakeBack(); g >= 0; g = s.shared_groups.TakeBack()) {
    if (last < 0 && Solved(*job->groups, s, g)) {
      last = g;
      continue;
    }
    job->failed += SolveGroups(*job->model, *job->data, *job->groups, s, s.worker_solver, g, g + 1);
  }
  if (last >= 0) {
    job->failed +=
        SolveGroups(*job->model, *job->data, *job->groups, s, s.worker_solver, last, last + 1);
  }
  job->last_solved = last;
}

// fewer implicit contacts than this are not worth the hand-off to the worker
constexpr int kMinContactsForTwoThreads = 64;

// the first solved group when the groups are worth sharing with the worker (two or more solved
// groups, enough implicit contacts); -1 otherwise
int FirstSharedSolve(const contact::Groups& groups, const VelocityScratch& scratch) {
  int first = -1, solved = 0, total = 0;
  for (int g = 0; g < groups.ngroup; ++g) {
    if (!Solved(groups, scratch, g)) continue;
    if (first < 0) first = g;
    ++solved;
    total += scratch.implicit_start[g + 1] - scratch.implicit_start[g];
  }
  return solved >= 2 && total >= kMinContactsForTwoThreads ? first : -1;
}

// After a step shared with the worker, one thread's scratch would hold the factor state of the
// last group solved, which is then the worker's, and the back-off of the step's first solve (only
// a step's first solved group can meet a kept factor made for its bodies: every later one follows
// a group of other bodies). The factors, assemblies and keys change places; the back-off and the
// counters stay with their scratch.
void HandOnKeptFactor(VelocityScratch& s) {
  GroupSolverScratch& a = s.group_solver;
  GroupSolverScratch& b = s.worker_solver;
  std::swap(a, b);
  std::swap(a.lagged.lag_backoff, b.lagged.lag_backoff);
  std::swap(a.lagged.lag_skip, b.lagged.lag_skip);
  std::swap(a.lagged.lagged_solves, b.lagged.lagged_solves);
  std::swap(a.lagged.refinement_steps, b.lagged.refinement_steps);
  std::swap(a.lagged.lagged_failures, b.lagged.lagged_failures);
  std::swap(a.factorisations, b.factorisations);
}

}  // namespace

void VelocityScratch::Reserve(int nbody, int max_contacts, int max_group_bodies, int threads) {
  force_W.resize(nbody);
  torque_W.resize(nbody);
  implicit.resize(max_contacts);
  implicit_start.assign(nbody + 1, 0);
  group_solver.Reserve(max_group_bodies, max_contacts);
  if (threads == 2) worker_solver.Reserve(max_group_bodies, max_contacts);
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

void UpdateVelocities(const Model& model, Data& data, const contact::Groups& groups,
                      VelocityScratch& scratch, geometry::Worker* worker) {
  const int nbody = static_cast<int>(model.bodies.size());
  for (int i = 0; i < nbody; ++i) {
    if (data.body_group[i] < 0) FreeMotion(model, data, scratch, i);
  }
  const int first = worker != nullptr ? FirstSharedSolve(groups, scratch) : -1;
  if (first < 0) {
    const int failed =
        SolveGroups(model, data, groups, scratch, scratch.group_solver, 0, groups.ngroup);
    for (int k = 0; k < failed; ++k) data.Warn(Warning::kSolverFailed);
    return;
  }
  // The groups up to the first solved one stay on this thread: that one may meet the factor kept
  // from the last step, which is in this thread's scratch. Every later group follows a group of
  // other bodies, as it would with one thread, and cannot; the worker's scratch starts the step
  // without a factor.
  GroupSolverScratch& w = scratch.worker_solver;
  w.lagged.reuse_factor = scratch.group_solver.lagged.reuse_factor;
  w.lagged.factor_valid = false;
  scratch.shared_groups.Reset(first + 1, groups.ngroup);
  scratch.job = {&model, &data, &groups, &scratch, 0, -1};
  worker->Post(&RunGroupJob, &scratch.job);
  int failed = SolveGroups(model, data, groups, scratch, scratch.group_solver, 0, first + 1);
  for (int g = scratch.shared_groups.TakeFront(); g >= 0; g = scratch.shared_groups.TakeFront()) {
    failed += SolveGroups(model, data, groups, scratch, scratch.group_solver, g, g + 1);
  }
  worker->Finish();
  failed += scratch.job.failed;
  // the worker's groups all come after this thread's: if it solved one, one thread would end the
  // step with the worker's factor state
  if (scratch.job.last_solved >= 0) HandOnKeptFactor(scratch);
  ++scratch.shared_steps;
  for (int k = 0; k < failed; ++k) data.Warn(Warning::kSolverFailed);
}

void IntegratePositions(const Model& model, Data& data) {
  for (BodyState& s : data.bodies) IntegratePosition(s, model.timestep_s);
}

}  // namespace rigidtouch::dynamics
