// Contact groups (tick stage 3): connected components of dynamic bodies through contacts. Static
// geometry does not join groups, so boxes on one floor are separate groups unless they touch.
#pragma once

#include <span>
#include <vector>

#include "rigidtouch/data.h"

namespace rigidtouch::contact {

/// Groups in compressed rows: group g has bodies bodies[body_start[g] .. body_start[g+1]) and
/// contacts contacts[contact_start[g] .. contact_start[g+1]). Preallocated by Reserve.
struct Groups {
  std::vector<int> parent;         // (nbody) union-find forest
  std::vector<int> body_start;     // (nbody + 1)
  std::vector<int> bodies;         // (nbody)
  std::vector<int> contact_start;  // (nbody + 1)
  std::vector<int> contacts;       // (max_contacts)
  std::vector<int> slot;           // (nbody) position of a body inside its group
  std::vector<int> count;          // (nbody) scratch
  int ngroup = 0;

  /// Sizes every buffer; the only allocating call.
  void Reserve(int nbody, int max_contacts);
};

/// Builds the groups of data.contacts[0 .. ncontact) and writes data.body_group; reads the
/// contacts' bodies only (ClassifyContacts writes each contact's group), from the list's runs
/// (data.runs, which collision detection writes with the list) when they cover it exactly, and
/// from the contacts themselves otherwise (a list written by hand). Bodies in no contact get group
/// -1. Groups are numbered in the order of their first contacts in the list; a group's bodies and
/// contacts are in index order.
void BuildGroups(Data& data, Groups& groups);

}  // namespace rigidtouch::contact
