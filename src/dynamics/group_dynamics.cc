#include "dynamics/group_dynamics.h"

#include <algorithm>

namespace rigidtouch::dynamics {
namespace {

// solves per step: a friction patch's slip at most twice (it slips, then its kinetic friction
// meets its normal force), contacts that pull at most a few times
constexpr int kMaxPasses = 6;

}  // namespace

void GroupSolverScratch::Reserve(int max_group_bodies, int max_group_contacts) {
  max_bodies = max_group_bodies;
  max_contacts = max_group_contacts;
  // every pair of bodies could couple after fill-in, but a contact group is sparse: bound the
  // factor's off-diagonal blocks by 32 per body
  const long full = static_cast<long>(max_bodies) * (max_bodies - 1) / 2;
  const int max_blocks = static_cast<int>(std::min<long>(full, 32L * max_bodies));
  factor.Reserve(max_bodies, max_contacts, max_blocks);
  assembly.Reserve(max_bodies, max_contacts);
  lagged.Reserve(max_bodies, max_contacts);
  factorisations = 0;
}

bool SolveGroupVelocities(const Model& model, Data& data, std::span<const int> bodies,
                          std::span<const int> slot, std::span<ImplicitContact> contacts,
                          std::span<const Vec3> force_W, std::span<const Vec3> torque_W,
                          GroupSolverScratch& s, KeptFactors& kept) {
  const int nb = static_cast<int>(bodies.size());
  const int nc = static_cast<int>(contacts.size());
  if (nb > s.max_bodies || nc > s.max_contacts) return false;
  GroupAssembly& g = s.assembly;
  StructureOf(g, slot, contacts);
  if (!s.factor.Analyse(nb, g.structure())) return false;

  // a contact may come in inactive (dropped by the caller): then the system is not the one
  // kept factors are made for
  const bool reuse =
      s.lagged.reuse_factor && std::all_of(contacts.begin(), contacts.end(),
                                           [](const ImplicitContact& c) { return c.active; });
  // a kept factor's answer stands only if every friction patch keeps within its cone
  bool lagged = reuse && SolveWithKeptFactor(model, data, bodies, slot, contacts, force_W, torque_W,
                                             s.lagged, kept, g, s.factor);
  if (lagged &&
      (EnforceFrictionCones(contacts, false) != kFrictionKept || StickReversedSlips(contacts))) {
    lagged = false;
  }
  if (!lagged) {
    if (reuse) DropKeptFactor(kept, bodies[0]);
    bool dropped = false;
    bool same_matrix = false;  // only slipping friction changed since the last factorisation
    for (int pass = 0; pass < kMaxPasses; ++pass) {
      if (same_matrix) {
        AssembleRightHandSide(model, data, bodies, slot, contacts, force_W, torque_W, g, s.factor);
      } else {
        // the factorisation overwrites the system: each pass assembles it over the contacts left
        Assemble(model, data, bodies, slot, contacts, force_W, torque_W, g, s.factor);
        if (!s.factor.Factor(nb)) return false;
        ++s.factorisations;
      }
      same_matrix = false;
      std::copy(g.b.begin(), g.b.begin() + nb, g.x.begin());
      if (!s.factor.Solve(nb, g.x)) return false;
      for (ImplicitContact& c : contacts) {
        c.normal_force_N = 0.0;
        c.friction_force_N_W.setZero();
      }
      bool pulled = false;
      for (int q = 0; q < g.npatch; ++q) {
        pulled |= PatchForces<false>(g, s.factor, data, slot, contacts, g.patch_range[2 * q],
                                     g.patch_range[2 * q + 1], false, model.timestep_s);
      }
      if (pass + 1 == kMaxPasses) break;
      // Coulomb first: a sticking patch beyond its cone (a trial whose tangential damping would
      // stop a sliding body in one step) slips, and the contacts that trial made pull are kept
      // for the solve with the kinetic friction
      const int cone = EnforceFrictionCones(contacts, pass + 2 == kMaxPasses);
      if (cone & kFrictionSlipped) continue;
      // a slip that one step of kinetic friction reversed sticks (not in the last two passes, so
      // that the cone is checked once more after it)
      if (pass + 3 < kMaxPasses && StickReversedSlips(contacts)) continue;
      if (!pulled) {
        if (cone != kFrictionKept) {
          // a slipping patch's friction, a force independent of the new velocities, changed
          same_matrix = true;
          continue;
        }
        // a factor of the system with every contact is kept for the next steps
        if (!dropped && reuse) KeepFactor(kept, s.lagged, g, bodies, contacts, s.factor);
        break;
      }
      // a contact that stops pushing has no friction either: solve again without it
      for (ImplicitContact& c : contacts) {
        if (c.active && c.normal_force_N < 0.0) {
          c.active = false;
          c.normal_force_N = 0.0;
          c.friction_force_N_W.setZero();
          dropped = true;
        }
      }
    }
  }
  for (int k = 0; k < nb; ++k) {
    BodyState& st = data.bodies[bodies[k]];
    const Vec6& v = g.x[s.factor.pos[k]];
    st.v_W = v.head<3>();
    st.w_W = v.tail<3>();
  }
  return true;
}

}  // namespace rigidtouch::dynamics
