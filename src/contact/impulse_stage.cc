#include "contact/impulse_stage.h"

#include <algorithm>
#include <cmath>

#include "contact/impulse_math.h"
#include "contact/relative_motion.h"
#include "contact/schedule.h"
#include "dynamics/rigid_body.h"

namespace rigidtouch::contact {
namespace {

// fewer rows than this in the groups with an impulse due are not worth the hand-off to the worker
constexpr int kMinRowsForTwoThreads = 64;

// packs group g's bodies and rows into lane L; returns whether the tool takes part
bool Pack(const Model& model, const Data& data, const Groups& G, int g, ImpulseLane& L) {
  const int nb = G.body_start[g + 1] - G.body_start[g];
  const int nc = G.contact_start[g + 1] - G.contact_start[g];
  for (int k = 0; k < nb; ++k) {
    const int i = G.bodies[G.body_start[g] + k];
    const BodyState& state = data.bodies[i];
    SolverBody& sb = L.bodies[k];
    sb.inv_mass = 1.0 / model.bodies[i].mass_kg;
    sb.inv_inertia_W = dynamics::WorldInverseInertia(model.bodies[i], data.R_WB[i]);
    sb.v_W = state.v_W;
    sb.w_W = state.w_W;
  }
  bool tool = false;
  for (int k = 0; k < nc; ++k) {
    const Contact& c = data.contacts[G.contacts[G.contact_start[g] + k]];
    SolverRow& row = L.rows[k];
    row.body_a = c.body_a >= 0 ? G.slot[c.body_a] : -1;
    row.body_b = c.body_b >= 0 ? G.slot[c.body_b] : -1;
    row.n_W = c.n_W;
    Offsets(data, c, &row.r_a_W, &row.r_b_W);
    tool = tool || c.body_a == model.tool || c.body_b == model.tool;
  }
  return tool;
}

// the impulse of Eq. 5 (N = 1) or Eq. 8 (e = 0) into p; false if the solver failed. `interior`:
// on entry whether the group's last solve used the interior-point method (the solver's hint), on
// return whether this one did
bool SolveImpulse(const Model& model, const ImpulseProblem& problem, int remaining, ImpulseLane& L,
                  ReferenceSolver* reference, std::span<double> p, bool& interior) {
  const double e = model.render.renderer == RendererKind::kImpulse ? model.render.restitution : 0.0;
  if (model.render.reference_solver) {
    // exact Eq. 5 / Eq. 8 with the pseudo-inverse (may pull), for comparison runs
    interior = false;
    return reference != nullptr && reference->Solve(problem, e, remaining, p);
  }
  // Eq. 8's share 1 / (N - i + 1), or a material train's envelope share
  const double scale =
      (1.0 + e) * TrainShare(model.schedule, model.render, model.timestep_s, remaining);
  const ImpulseSolverStats stats =
      L.solver->Solve(problem, scale, p, {}, ImpulseSolveHint{.interior = interior});
  const bool solved = stats.error == ImpulseSolverError::kNone;
  interior = solved && stats.interior_point;
  return solved;
}

// applies p to group g's bodies and contacts and describes it in ev (recorded later, in order)
void Apply(const Model& model, Data& data, const Groups& G, int g, int index, bool tool,
           const ImpulseProblem& problem, std::span<const double> p, ImpulseLane& L,
           ImpulseEvent& ev) {
  const int nb = static_cast<int>(problem.bodies.size());
  const int nc = static_cast<int>(problem.rows.size());
  const std::span<SolverBody> bodies(L.bodies.data(), nb);
  const double ke_before = KineticEnergy(bodies);
  ApplyImpulses(bodies, problem.rows, p);
  const double ke_after = KineticEnergy(bodies);
  ev = ImpulseEvent{};
  ev.step = data.step;
  ev.time_s = data.time_s;
  ev.group = g;
  ev.contacts = nc;
  ev.index = index;
  ev.total = model.schedule.impulses;
  ev.tool = tool;
  ev.kinetic_energy_before_J = ke_before;
  ev.kinetic_energy_after_J = ke_after;
  double norm2 = 0.0;
  for (int k = 0; k < nc; ++k) {
    Contact& c = data.contacts[G.contacts[G.contact_start[g] + k]];
    c.impulse_Ns = p[k];
    norm2 += p[k] * p[k];
    if (c.body_a == model.tool) ev.tool_impulse_Ns_W += p[k] * c.n_W;
    if (c.body_b == model.tool) ev.tool_impulse_Ns_W -= p[k] * c.n_W;
  }
  ev.impulse_norm_Ns = std::sqrt(norm2);
  for (int k = 0; k < nb; ++k) {
    BodyState& state = data.bodies[G.bodies[G.body_start[g] + k]];
    state.v_W = bodies[k].v_W;
    state.w_W = bodies[k].w_W;
  }
}

// group d.group's due impulse with lane L: solved, applied to its bodies and contacts, and
// described in d.event; d.solved false if the solver failed. Touches only the group's own bodies
// and contacts, so the two threads may solve different groups at once.
void SolveDue(const Model& model, Data& data, const Groups& G, ImpulseScratch::Due& d,
              ImpulseLane& L, ReferenceSolver* reference) {
  const int g = d.group;
  const int nb = G.body_start[g + 1] - G.body_start[g];
  const int nc = G.contact_start[g + 1] - G.contact_start[g];
  const bool tool = Pack(model, data, G, g, L);
  const ImpulseProblem problem{std::span<const SolverBody>(L.bodies.data(), nb),
                               std::span<const SolverRow>(L.rows.data(), nc)};
  const std::span<double> p(L.impulses.data(), nc);
  d.interior = data.window[G.bodies[G.body_start[g]]].interior;
  d.solved = SolveImpulse(model, problem, d.remaining, L, reference, p, d.interior);
  if (d.solved) Apply(model, data, G, g, d.index, tool, problem, p, L, d.event);
}

// The worker's part of the shared groups: places in the due list taken from the back.
void RunImpulseJob(void* context) {
  const auto* job = static_cast<const ImpulseScratch::Job*>(context);
  ImpulseScratch& s = *job->scratch;
  const Groups& G = *job->groups;
  const int capacity = static_cast<int>(s.worker_lane.rows.size());
  for (int k = s.shared.TakeBack(); k >= 0; k = s.shared.TakeBack()) {
    ImpulseScratch::Due& d = s.due[k];
    if (G.contact_start[d.group + 1] - G.contact_start[d.group] > capacity) {
      d.left = true;
      ++s.left_by_worker;
      continue;
    }
    SolveDue(*job->model, *job->data, G, d, s.worker_lane, nullptr);
    ++s.solved_on_worker;
  }
}

// lists the groups with an impulse due this tick (Eq. 6-7) in group order; returns their rows
int ListDue(const Model& model, const Data& data, const Groups& G, ImpulseScratch& s) {
  s.ndue = 0;
  int rows = 0;
  for (int g = 0; g < G.ngroup; ++g) {
    const int nc = G.contact_start[g + 1] - G.contact_start[g];
    ImpulseScratch::Due& d = s.due[s.ndue];
    if (nc > 0 && ImpulseDue(model.schedule, data.window[G.bodies[G.body_start[g]]], data.step,
                             &d.index, &d.remaining)) {
      d.group = g;
      d.solved = false;
      d.left = false;
      ++s.ndue;
      rows += nc;
    }
  }
  return rows;
}

void SizeLane(const Model& model, int rows, ImpulseLane& L) {
  const int nbody = static_cast<int>(model.bodies.size());
  L.bodies.resize(nbody);
  L.rows.resize(rows);
  L.impulses.resize(rows);
  L.solver = std::make_unique<ImpulseSolver>(rows, nbody);
}

}  // namespace

void ImpulseScratch::Reserve(const Model& model, int worker_rows) {
  const int nbody = static_cast<int>(model.bodies.size());
  SizeLane(model, model.max_contacts, lane);
  worker_lane = ImpulseLane{};
  if (model.threads == 2) {
    SizeLane(model, std::clamp(worker_rows, 0, model.max_contacts), worker_lane);
  }
  due.assign(nbody, Due{});
  ndue = 0;
  shared_steps = 0;
  solved_on_worker = 0;
  left_by_worker = 0;
  reference.reset();
  if (model.render.reference_solver) {
    // its dense system is rows x rows: sized for every contact the scene can produce (12653 for
    // the 100-box pile) it would take 1.3 GB. A comparison run's impulse problems are the groups
    // in a window, far smaller; one beyond the cap fails its solve, counted as solver_failed
    constexpr int kMaxReferenceRows = 2048;  // a 32 MB system
    reference =
        std::make_unique<ReferenceSolver>(std::min(model.max_contacts, kMaxReferenceRows), nbody);
  }
}

void CollisionImpulses(const Model& model, Data& data, const Groups& G, ImpulseScratch& scratch,
                       parallel::Worker* worker, TreeGroupScratch* trees) {
  if (trees != nullptr && G.ntree_group > 0) TreeGroupImpulses(model, data, G, *trees);
  // penalty and event-based transients apply no impulses (the event renderer's window only
  // marks the onset its transient starts from)
  if (model.render.renderer == RendererKind::kPenalty ||
      model.render.renderer == RendererKind::kEvent) {
    return;
  }
  ImpulseScratch& s = scratch;
  const int rows = ListDue(model, data, G, s);
  // the reference solver is the tick's thread's alone
  if (worker != nullptr && !model.render.reference_solver && s.ndue >= 2 &&
      rows >= kMinRowsForTwoThreads) {
    s.shared.Reset(0, s.ndue);
    s.job = {&model, &data, &G, &s};
    worker->Post(&RunImpulseJob, &s.job);
    for (int k = s.shared.TakeFront(); k >= 0; k = s.shared.TakeFront()) {
      SolveDue(model, data, G, s.due[k], s.lane, nullptr);
    }
    worker->Finish();
    for (int k = 0; k < s.ndue; ++k) {
      if (s.due[k].left) SolveDue(model, data, G, s.due[k], s.lane, nullptr);
    }
    ++s.shared_steps;
  } else {
    for (int k = 0; k < s.ndue; ++k) SolveDue(model, data, G, s.due[k], s.lane, s.reference.get());
  }
  // recorded in group order, as one thread solving the groups in turn would
  for (int k = 0; k < s.ndue; ++k) {
    const ImpulseScratch::Due& d = s.due[k];
    data.window[G.bodies[G.body_start[d.group]]].interior = d.interior;
    if (!d.solved) {
      data.Warn(Warning::kSolverFailed);
      continue;
    }
    data.impulses[data.nimpulse++] = d.event;
    data.tool_impulse_Ns_W += d.event.tool_impulse_Ns_W;
    data.window[G.bodies[G.body_start[d.group]]].impulses_done = d.index;
  }
  // a group's window is its first body's; every body of the group takes it on
  for (int g = 0; g < G.ngroup; ++g) {
    const WindowState w = data.window[G.bodies[G.body_start[g]]];
    for (int k = G.body_start[g] + 1; k < G.body_start[g + 1]; ++k) data.window[G.bodies[k]] = w;
  }
}

}  // namespace rigidtouch::contact
