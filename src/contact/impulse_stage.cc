#include "contact/impulse_stage.h"

#include <algorithm>
#include <cmath>

#include "contact/impulse_math.h"
#include "contact/relative_motion.h"
#include "contact/schedule.h"
#include "dynamics/rigid_body.h"

namespace rigidtouch::contact {
namespace {

// packs group g's bodies and rows; returns whether the tool takes part
bool Pack(const Model& model, const Data& data, const Groups& G, int g, ImpulseScratch& s) {
  const int nb = G.body_start[g + 1] - G.body_start[g];
  const int nc = G.contact_start[g + 1] - G.contact_start[g];
  for (int k = 0; k < nb; ++k) {
    const int i = G.bodies[G.body_start[g] + k];
    const BodyState& state = data.bodies[i];
    SolverBody& sb = s.bodies[k];
    sb.inv_mass = 1.0 / model.bodies[i].mass_kg;
    sb.inv_inertia_W = dynamics::WorldInverseInertia(model.bodies[i], data.R_WB[i]);
    sb.v_W = state.v_W;
    sb.w_W = state.w_W;
  }
  bool tool = false;
  for (int k = 0; k < nc; ++k) {
    const Contact& c = data.contacts[G.contacts[G.contact_start[g] + k]];
    SolverRow& row = s.rows[k];
    row.body_a = c.body_a >= 0 ? G.slot[c.body_a] : -1;
    row.body_b = c.body_b >= 0 ? G.slot[c.body_b] : -1;
    row.n_W = c.n_W;
    Offsets(data, c, &row.r_a_W, &row.r_b_W);
    tool = tool || c.body_a == model.tool || c.body_b == model.tool;
  }
  return tool;
}

// the impulse of Eq. 5 (N = 1) or Eq. 8 (e = 0) into p; false if the solver failed
bool SolveImpulse(const Model& model, const ImpulseProblem& problem, int remaining,
                  ImpulseScratch& s, std::span<double> p) {
  const double e = model.render.renderer == RendererKind::kImpulse ? model.render.restitution : 0.0;
  if (model.render.reference_solver) {
    // exact Eq. 5 / Eq. 8 with the pseudo-inverse (may pull), for comparison runs
    return s.reference != nullptr && s.reference->Solve(problem, e, remaining, p);
  }
  // Eq. 8's share 1 / (N - i + 1), or a material train's envelope share
  const double scale =
      (1.0 + e) * TrainShare(model.schedule, model.render, model.timestep_s, remaining);
  return s.solver->Solve(problem, scale, p).error == ImpulseSolverError::kNone;
}

// applies p to group g's bodies and records the event
void Apply(const Model& model, Data& data, const Groups& G, int g, int index, bool tool,
           const ImpulseProblem& problem, std::span<const double> p, ImpulseScratch& s) {
  const int nb = static_cast<int>(problem.bodies.size());
  const int nc = static_cast<int>(problem.rows.size());
  const std::span<SolverBody> bodies(s.bodies.data(), nb);
  const double ke_before = KineticEnergy(bodies);
  ApplyImpulses(bodies, problem.rows, p);
  const double ke_after = KineticEnergy(bodies);
  ImpulseEvent& ev = data.impulses[data.nimpulse++];
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
    if (c.body_a == model.tool) ev.tool_impulse_W += p[k] * c.n_W;
    if (c.body_b == model.tool) ev.tool_impulse_W -= p[k] * c.n_W;
  }
  ev.impulse_norm_Ns = std::sqrt(norm2);
  data.tool_impulse_W += ev.tool_impulse_W;
  for (int k = 0; k < nb; ++k) {
    BodyState& state = data.bodies[G.bodies[G.body_start[g] + k]];
    state.v_W = bodies[k].v_W;
    state.w_W = bodies[k].w_W;
  }
}

// group g's impulse, if one is due in its window (Eq. 6-7)
void GroupImpulse(const Model& model, Data& data, const Groups& G, int g, WindowState& window,
                  ImpulseScratch& s) {
  int index = 0, remaining = 0;
  if (!ImpulseDue(model.schedule, window, data.step, &index, &remaining)) return;
  const int nb = G.body_start[g + 1] - G.body_start[g];
  const int nc = G.contact_start[g + 1] - G.contact_start[g];
  if (nc == 0) return;
  const bool tool = Pack(model, data, G, g, s);
  const ImpulseProblem problem{std::span<const SolverBody>(s.bodies.data(), nb),
                               std::span<const SolverRow>(s.rows.data(), nc)};
  const std::span<double> p(s.impulses.data(), nc);
  if (!SolveImpulse(model, problem, remaining, s, p)) {
    data.Warn(Warning::kSolverFailed);
    return;
  }
  Apply(model, data, G, g, index, tool, problem, p, s);
  window.impulses_done = index;
}

}  // namespace

void ImpulseScratch::Reserve(const Model& model) {
  const int nbody = static_cast<int>(model.bodies.size());
  bodies.resize(nbody);
  rows.resize(model.max_contacts);
  impulses.resize(model.max_contacts);
  solver = std::make_unique<ImpulseSolver>(model.max_contacts, nbody);
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

void CollisionImpulses(const Model& model, Data& data, const Groups& G, ImpulseScratch& scratch) {
  // penalty and event-based transients apply no impulses (the event renderer's window only
  // marks the onset its transient starts from)
  if (model.render.renderer == RendererKind::kPenalty ||
      model.render.renderer == RendererKind::kEvent) {
    return;
  }
  for (int g = 0; g < G.ngroup; ++g) {
    WindowState w = data.window[G.bodies[G.body_start[g]]];
    GroupImpulse(model, data, G, g, w, scratch);
    for (int k = G.body_start[g]; k < G.body_start[g + 1]; ++k) data.window[G.bodies[k]] = w;
  }
}

}  // namespace rigidtouch::contact
