// Groups and windows (tick stage 3): the contact groups, each contact's law and approach speed,
// stick or slip per contact patch, and each group's collision-rendering window, which sets the
// phase (colliding or resting) of its contacts.
#pragma once

#include <vector>

#include "contact/groups.h"
#include "contact/penalty.h"
#include "contact/tree_groups.h"
#include "parallel/worker.h"
#include "rigidtouch/data.h"
#include "rigidtouch/model.h"

namespace rigidtouch::contact {

/// Per-contact scratch of stages 3 and 4, sized once by Reserve.
struct ContactScratch {
  Groups groups;
  std::vector<PenaltyLaw> laws;           // (max_contacts) each contact's law this tick
  std::vector<Vec3> anchor_displacement;  // (max_contacts) stick-anchor stretch (implicit ones)
  std::vector<double> normal_velocity;    // (max_contacts) approach speed of new contacts  [m/s]
  // (nbody) each group's phase this tick, which stage 4 gives the group's contacts as it writes
  // their forces (so that the windows of stage 3 write no contact)
  std::vector<ContactPhase> group_phase;
  // the groups with trees (Groups::ntree_group): their rows, solver and the limits' state
  TreeGroupScratch trees;

  /// Sizes every buffer; the only allocating call.
  void Reserve(int nbody, int max_contacts);
};

/// Stage 3, in one of two ways that give the same results bit for bit (the driver is stage 4's
/// ClassifyAndForces, contact_forces.h): builds the groups, gives every contact its law (one per
/// geom pair) and, when new, its normal velocity, decides stick or slip per patch, and updates
/// each group's window (data.window) and its phase (scratch.group_phase; stage 4 writes it and
/// the group's index into the group's contacts).
///
/// By pairs: ClassifyByPairs builds the groups on this thread (and runs `alongside` there: work
/// of the caller's that reads and writes nothing this stage does) while the contacts' laws,
/// approach speeds and stick-or-slip decisions are made in blocks of the contact list, shared
/// with a worker (threads 2) when there are enough contacts (each geom pair's on one thread);
/// then UpdateGroupWindow for every group.
void ClassifyByPairs(const Model& model, Data& data, ContactScratch& scratch,
                     parallel::Worker* worker = nullptr, parallel::Task alongside = {});
/// Group g's window and phase, once its contacts are classified.
void UpdateGroupWindow(const Model& model, Data& data, ContactScratch& scratch, int g);
/// By groups, once BuildGroups has run: group g's geom pairs classified, then its window and
/// phase. Reads and writes only group g's contacts, bodies and entries.
void ClassifyGroup(const Model& model, Data& data, ContactScratch& scratch, int g);

/// The collision window of group g: restarted by a new contact that approaches faster than
/// ContactParams::onset_speed_mps (a collision onset), otherwise the most recent window among
/// its bodies. Penalty rendering keeps the bodies' window as it is.
WindowState GroupWindow(const Model& model, const Data& data, const ContactScratch& scratch, int g);

/// Whether `step` lies inside `window`: the N-impulse window of a train (Eq. 6), the onset step
/// alone for a single impulse.
bool InWindow(const Model& model, const WindowState& window, std::int64_t step);

}  // namespace rigidtouch::contact
