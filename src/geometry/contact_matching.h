// Contact identity across ticks (part of tick stage 3, collision detection): last tick's contacts
// indexed by geom pair, each new point matched to the nearest one of the same pair to keep its id,
// friction anchors and phase, and the ids of the new points given in contact order.
//
// The state lives in the collision stage's scratch (CollisionScratch::matching), not in Data: it is
// the stage's bookkeeping, not what a user reads. Data::contacts holds this tick's list and
// Data::runs its index by geom pair.
#pragma once

#include <vector>

#include "rigidtouch/data.h"

namespace rigidtouch::geometry {

/// Distance within which a contact point (in the first body's frame) is the same contact as one
/// of last tick on the same geom pair.
inline constexpr double kMatchDistance_m = 0.005;

/// What matching keeps from one tick to the next. Sized by Reserve; nothing grows afterwards.
struct ContactMatching {
  std::vector<Contact> previous;  // (max contacts) last tick's contacts; first nprevious valid
  int nprevious = 0;
  // (max contacts) the runs of `previous`, sorted by geom pair; the runs whose first geom is g at
  // previous_runs[run_start[g] .. run_start[g + 1])
  std::vector<PairRun> previous_runs;
  int nprevious_runs = 0;
  std::vector<int> run_start;  // (ngeom + 1)
  std::vector<int> run_fill;   // (ngeom) counting-sort scratch
  int next_contact_id = 0;     // the id the next new contact gets

  /// Sizes the buffers for `max_contacts` contacts among `ngeom` geoms and forgets every contact.
  void Reserve(int max_contacts, int ngeom);
  /// Forgets last tick's contacts and numbers new contacts from 0 again.
  void Reset();
};

/// Whether data.runs indexes data.contacts: consecutive runs of at least one point each that
/// cover contacts[0 .. ncontact) exactly, as DetectContacts writes them (a list written by hand
/// has none). Only the runs are read.
bool RunsIndexList(const Data& data);

/// Makes data.contacts last tick's contacts (the buffers trade places with m.previous, no copy),
/// indexes their geom pairs for MatchPair, and empties data.contacts and data.runs.
void RememberPrevious(Data& data, ContactMatching& m);

/// Matches the points of one geom pair, data.contacts[begin .. end), against last tick's: a
/// matched point takes the old one's id, stick state, anchors and phase; a new point gets id -1
/// (AssignNewIds numbers it). Returns whether the pair has a new point. Reads only last tick's
/// contacts and the pair's own, so the two collision threads may match different pairs at once.
bool MatchPair(Data& data, const ContactMatching& m, int begin, int end);

/// Numbers the new points of data.contacts[begin .. end) that MatchPair left without an id.
void AssignNewIds(Data& data, ContactMatching& m, int begin, int end);

/// MatchPair and AssignNewIds on one thread, and the pair's run appended to data.runs (a buffer
/// smaller than the contact list's, in a Data not made by MakeData, leaves the index short:
/// RunsIndexList then says so, and the list is read instead).
void MatchAndNumber(Data& data, ContactMatching& m, int begin, int end);

}  // namespace rigidtouch::geometry
