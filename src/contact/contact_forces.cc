#include "contact/contact_forces.h"

#include <algorithm>

#include "contact/friction.h"
#include "contact/groups.h"
#include "contact/relative_motion.h"

namespace rigidtouch::contact {
namespace {

// the friction patch of contact ci: its geom pair's points, consecutive in data.contacts; the
// index of the first
int PatchStart(const Data& data, int ci) {
  const Contact& c = data.contacts[ci];
  int patch = ci;
  while (patch > 0 && data.contacts[patch - 1].geom_a == c.geom_a &&
         data.contacts[patch - 1].geom_b == c.geom_b) {
    --patch;
  }
  return patch;
}

}  // namespace

void ExplicitContact(Data& data, const PenaltyLaw& law, int ci, dynamics::VelocityScratch& forces) {
  Contact& c = data.contacts[ci];
  Vec3 r_a, r_b;
  Offsets(data, c, &r_a, &r_b);
  const Vec3 u = RelativeVelocity(data, c, r_a, r_b);
  const double un = u.dot(c.n_W);
  const double fn = NormalForce(law, c.depth_m, un);
  Vec3 ft = Vec3::Zero();
  if (fn > 0.0) {
    const Vec3 s = AnchorDisplacement(data, c);
    const Vec3 ut = u - un * c.n_W;
    ft = -law.kt_N_per_m * s - law.bt_Ns_per_m * ut;
    c.sticking = ft.norm() <= law.mu_static * fn;
    if (c.sticking) {
      PlaceAnchors(data, c, s);
    } else {
      ft *= law.mu_kinetic * fn / ft.norm();
      SlideAnchor(data, c, s, ft, law.kt_N_per_m);
    }
  } else {
    c.anchor_A = c.p_A;  // no load: the anchor follows the contact point
    c.anchor_B = c.p_B;
    c.sticking = false;
  }
  c.normal_force_N = fn;
  c.friction_force_N_W = ft;
  forces.AddContactForce(c, fn * c.n_W + ft, r_a, r_b);
}

bool LinearizeContact(const Model& model, Data& data, const ContactScratch& scratch, int ci,
                      dynamics::ImplicitContact& ic) {
  return LinearizeContact(model, data, scratch, ci, PatchStart(data, ci), ic);
}

bool LinearizeContact(const Model& model, Data& data, const ContactScratch& scratch, int ci,
                      int patch, dynamics::ImplicitContact& ic) {
  Contact& c = data.contacts[ci];
  const PenaltyLaw& law = scratch.laws[ci];
  const double h = model.timestep_s;
  c.normal_force_N = 0.0;
  c.friction_force_N_W.setZero();
  if (!(c.depth_m > 0.0)) {
    c.anchor_A = c.p_A;
    c.anchor_B = c.p_B;
    c.sticking = false;
    return false;
  }
  // backward Euler: depth after the step is d - h u_n+, so the force is k d - (h k + b) u_n+;
  // every penetrating point enters the solve, and SolveGroupVelocities drops the contacts that
  // would pull at the new velocities (a trial on the old velocities would react to velocity noise).
  // Every field is written, so no default object is built first.
  ic.body_a = c.body_a;
  ic.body_b = c.body_b;
  ic.n_W = c.n_W;
  ic.p_W = c.p_W;
  ic.phi_n_N = law.k_N_per_m * c.depth_m;
  ic.c_n_Ns_per_m = h * law.k_N_per_m + law.b_Ns_per_m;
  ic.contact = ci;
  ic.mu_static = law.mu_static;
  ic.mu_kinetic = law.mu_kinetic;
  ic.patch = patch;
  ic.active = true;
  ic.normal_force_N = 0.0;
  ic.friction_force_N_W.setZero();
  // stick or slip was decided for the whole geom pair in stage 3 (DecidePatchFriction) from the
  // anchor springs; a sticking patch whose forces at the new velocities leave the friction cone
  // slips too (SolveGroupVelocities, EnforceFrictionCones), so sliding starts Coulomb-bounded
  const Vec3 s = scratch.anchor_displacement[ci];
  ic.c_t_stick_Ns_per_m = h * law.kt_N_per_m + law.bt_Ns_per_m;
  ic.reversal_limit_mps = law.kt_N_per_m > 0.0
                              ? law.mu_kinetic * std::max(0.0, ic.phi_n_N) / (law.kt_N_per_m * h)
                              : 0.0;
  ic.slip_power_W = 0.0;
  if (c.sticking) {
    // the anchor spring (s lies in the tangent plane) with implicit tangential damping
    ic.stick = true;
    ic.phi_t_W = -law.kt_N_per_m * s;
    ic.c_t_Ns_per_m = ic.c_t_stick_Ns_per_m;
    PlaceAnchors(data, c, s);
  } else {
    // kinetic friction opposes the stretch of the anchor, which trails the sliding contact; it
    // enters the solve as the contact's tangential force, so it goes with the contact if that
    // would pull, and the solve keeps it within mu_k times the normal force
    const double stretch = s.norm();
    const Vec3 ft =
        stretch > 0.0 ? Vec3(-s * (law.mu_kinetic * ic.phi_n_N / stretch)) : Vec3::Zero();
    SlideAnchor(data, c, s, ft, law.kt_N_per_m);
    ic.stick = false;
    ic.phi_t_W = ft;
    ic.c_t_Ns_per_m = 0.0;
  }
  return true;
}

namespace {

// group g's contacts: the explicit ones' forces on its bodies, in contact order, and the implicit
// ones linearised into forces.implicit from the group's first contact's place on (every contact
// of a group touches only the group's bodies, so groups are independent)
void GroupContactForces(const Model& model, Data& data, const ContactScratch& scratch,
                        dynamics::VelocityScratch& forces, int g) {
  const Groups& G = scratch.groups;
  const bool too_large = G.body_start[g + 1] - G.body_start[g] > model.max_group_bodies;
  int n = G.contact_start[g];
  forces.implicit_start[g] = n;
  // a geom pair's points are consecutive in data.contacts and in the same group, so its patch
  // (first point) is known from the previous point instead of searched for again
  int patch = -1;
  const ContactPhase phase = scratch.group_phase[g];
  for (int k = G.contact_start[g]; k < G.contact_start[g + 1]; ++k) {
    const int ci = G.contacts[k];
    data.contacts[ci].group = g;  // for reports and viewers, as stage 3 decided
    data.contacts[ci].phase = phase;
    if (!scratch.laws[ci].implicit || too_large) {
      ExplicitContact(data, scratch.laws[ci], ci, forces);
      continue;
    }
    const Contact& c = data.contacts[ci];
    const bool same_pair = patch >= 0 && G.contacts[k - 1] == ci - 1 &&
                           data.contacts[ci - 1].geom_a == c.geom_a &&
                           data.contacts[ci - 1].geom_b == c.geom_b;
    if (!same_pair) patch = PatchStart(data, ci);
    if (LinearizeContact(model, data, scratch, ci, patch, forces.implicit[n])) ++n;
  }
  forces.implicit_end[g] = n;
}

// fewer contacts than this are not worth the hand-off to the worker; the range carries the
// groups' solves too (stage 5, which shared its groups from 64 implicit contacts on its own)
constexpr int kMinForceContactsForTwoThreads = 64;

}  // namespace

bool ClassifyAndForces(const Model& model, Data& data, ContactScratch& scratch,
                       dynamics::VelocityScratch& forces, parallel::Worker* worker,
                       parallel::Task alongside, parallel::ItemTask after_group) {
  const int n = data.ncontact;
  const bool two = worker != nullptr && n >= kMinForceContactsForTwoThreads;
  // by groups when there is no worker, or when last tick had groups enough to share (the choice
  // changes only the speed: one group is better classified by blocks of contacts on two threads)
  const bool by_groups = !two || data.ngroup >= 2;
  if (!by_groups) {
    ClassifyByPairs(model, data, scratch, worker, alongside);
  } else if (two && alongside.run != nullptr) {
    // the caller's work on the worker while this thread builds the groups
    worker->Post(alongside.run, alongside.context);
    BuildGroups(data, scratch.groups);
    worker->Finish();
  } else {
    BuildGroups(data, scratch.groups);
    alongside();
  }
  const Groups& G = scratch.groups;
  for (int g = 0; g < G.ngroup; ++g) {
    if (G.body_start[g + 1] - G.body_start[g] > model.max_group_bodies) {
      data.Warn(Warning::kGroupTooLarge);
    }
  }
  const bool shared = two && G.ngroup >= 2;
  parallel::ShareRangeSides(
      shared ? worker : nullptr, G.ngroup,
      [&model, &data, &scratch, &forces, by_groups, after_group](int g, int side) {
        if (by_groups) {
          ClassifyGroup(model, data, scratch, g);
        } else {
          UpdateGroupWindow(model, data, scratch, g);
        }
        GroupContactForces(model, data, scratch, forces, g);
        after_group(g, side);
      },
      [] {});
  return shared;
}

void GroupsAndVelocities(const Model& model, Data& data, ContactScratch& scratch,
                         dynamics::VelocityScratch& velocity, const Wrench& user, bool onsets,
                         parallel::Worker* worker) {
  if (!onsets) {
    for (int ci = 0; ci < data.ncontact; ++ci) data.contacts[ci].is_new = false;
  }
  dynamics::FreeMotionForces free{model, data, user, velocity};
  const Groups& groups = scratch.groups;
  dynamics::GroupSolves solves{
      model, data, {groups.body_start, groups.bodies, groups.slot}, velocity};
  dynamics::BeginVelocities(velocity);
  const bool shared =
      ClassifyAndForces(model, data, scratch, velocity, worker, free.AsTask(), solves.AsTask());
  // the groups with trees, on this thread once the free-body groups are done (tree_groups.h)
  if (!model.trees.empty()) SolveTreeGroups(model, data, scratch, velocity);
  dynamics::EndVelocities(model, data, velocity, shared);
}

}  // namespace rigidtouch::contact
