// Penalty stage (tick stage 4, run with stage 3 group by group: ClassifyAndForces): the forces of
// every contact's law at this tick's state. Tool
// contacts (and scene contacts of a group too large for the implicit solve) are explicit: their
// penalty and friction forces enter the bodies' force sums. Scene contacts are linearised for the
// backward-Euler solve of stage 5, with their friction cones.
#pragma once

#include "contact/phases.h"
#include "dynamics/velocities.h"
#include "rigidtouch/data.h"
#include "rigidtouch/model.h"

namespace rigidtouch::contact {

/// Explicit penalty and friction of contact ci; updates its friction anchor and adds its force to
/// the bodies' sums.
void ExplicitContact(Data& data, const PenaltyLaw& law, int ci, dynamics::VelocityScratch& forces);

/// Contact ci as a row of the implicit solve (false: not penetrating, nothing to solve): its
/// normal row, and the tangential rows of a sticking contact or the kinetic friction of a
/// slipping one (mu_k k d against the anchor's stretch), with its patch's friction cone.
bool LinearizeContact(const Model& model, Data& data, const ContactScratch& scratch, int ci,
                      dynamics::ImplicitContact& ic);
/// The same, with the index of the first point of ci's geom pair in data.contacts (its friction
/// patch) already known.
bool LinearizeContact(const Model& model, Data& data, const ContactScratch& scratch, int ci,
                      int patch, dynamics::ImplicitContact& ic);

/// Stages 3 and 4 over data.contacts, group by group: the groups, each contact's law, approach
/// speed and stick or slip, each group's window and phase (stage 3, phases.h); then the explicit
/// contacts' forces, and each group's implicit contacts in forces.implicit (group g's at
/// [implicit_start[g], implicit_end[g]), implicit_start[g] its first contact's place in the
/// groups' contact list), each contact's group and phase written with its forces. A group with
/// more than Model::max_group_bodies bodies counts Warning::kGroupTooLarge: its contacts are
/// explicit. `alongside` runs while the groups are built: work of the caller's that reads and
/// writes nothing these stages do (on the worker, when it takes it). One thread does each group
/// whole, classification and forces, so its contacts are read once, in one place. With a worker
/// (threads 2), two or more groups and enough contacts, the two threads share the groups (no
/// contact touches two); with one group, the classification is shared by blocks of contacts
/// instead (ClassifyByPairs). The same results, bit for bit. `after_group(g, side)` runs on the
/// thread that did group g, right after its forces (side 0 the tick's thread's end of the range,
/// 1 the worker's): the tick solves the group there (stage 5, dynamics::SolveGroup) while its
/// contacts are in that thread's cache. Returns whether the groups were shared by the threads.
bool ClassifyAndForces(const Model& model, Data& data, ContactScratch& scratch,
                       dynamics::VelocityScratch& forces, parallel::Worker* worker = nullptr,
                       parallel::Task alongside = {}, parallel::ItemTask after_group = {});

/// Stage 4, groups and velocities, in one call (docs/architecture.md): stage 3's contacts lose
/// their onsets when `onsets` is false (render::CouplingResult::new_motion); then, with the
/// free-motion forces (dynamics::AddFreeMotionForces) alongside the building of the groups,
/// ClassifyAndForces gives each group its laws, window, phase and forces and solves it right
/// after on the same thread (dynamics::SolveGroup); the bodies in no group move freely
/// (dynamics::EndVelocities). With trees, the groups that hold one are solved in joint space on
/// the tick's thread after the others (SolveTreeGroups: each tree's step prepared, its free motion
/// and its contact and limit forces). The threads' interleaving stays inside this call.
void GroupsAndVelocities(const Model& model, Data& data, ContactScratch& scratch,
                         dynamics::VelocityScratch& velocity, const Wrench& user, bool onsets,
                         parallel::Worker* worker);

}  // namespace rigidtouch::contact
