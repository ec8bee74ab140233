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
  int ngroup = 0;                  // groups without a tree: 0 .. ngroup

  // Articulated trees (Model::trees), only when the model has some (ReserveTrees): a tree is one
  // member of a group, united with every body that touches one of its links. The groups with a
  // tree are numbered after the others, ngroup .. ngroup + ntree_group, with their bodies and
  // contacts in the arrays above (which then hold nbody + ntree + 1 entries) and their trees in
  // trees[tree_start[g] .. tree_start[g + 1]) (tree_start indexed by g - ngroup). Every tree is in
  // a group, alone when nothing touches it.
  int ntree = 0;
  int ntree_group = 0;
  std::vector<int> geom_tree;       // (ngeom) the tree of a link geom, -1 for any other
  std::vector<int> tree_start;      // (ntree + 1)
  std::vector<int> trees;           // (ntree)
  std::vector<int> tree_group;      // (ntree) each tree's group
  std::vector<int> tree_slot;       // (ntree) its place among its group's trees
  std::vector<int> node_group;      // (nbody + ntree) scratch
  std::vector<char> node_has_tree;  // (nbody + ntree) scratch

  /// Sizes every buffer; the only allocating call.
  void Reserve(int nbody, int max_contacts);
  /// Sizes the trees' buffers for `model` (nothing when it has no tree); after Reserve.
  void ReserveTrees(const Model& model);
};

/// Builds the groups of data.contacts[0 .. ncontact) and writes data.body_group; reads the
/// contacts' bodies only (ClassifyContacts writes each contact's group), from the list's runs
/// (data.runs, which collision detection writes with the list) when they cover it exactly, and
/// from the contacts themselves otherwise (a list written by hand). Bodies in no contact get group
/// -1. Groups are numbered in the order of their first contacts in the list; a group's bodies and
/// contacts are in index order. With trees (Groups::ReserveTrees), the groups without a tree
/// come first, numbered as above, then the groups with a tree in the order of their lowest
/// tree; data.ngroup counts the first kind.
void BuildGroups(Data& data, Groups& groups);

}  // namespace rigidtouch::contact
