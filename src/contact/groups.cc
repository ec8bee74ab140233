#include "contact/groups.h"

#include <utility>

#include "geometry/collision.h"

namespace rigidtouch::contact {
namespace {

int FindRoot(int* parent, int i) {
  while (parent[i] != i) {
    parent[i] = parent[parent[i]];  // path halving
    i = parent[i];
  }
  return i;
}

void Unite(int* parent, int a, int b) {
  a = FindRoot(parent, a);
  b = FindRoot(parent, b);
  if (a == b) return;
  if (a < b) std::swap(a, b);
  parent[a] = b;  // the lowest index is the root, whatever the order of the unions
}

// calls f(body_a, body_b, begin, count) for each run of contacts of one pair of bodies, in list
// order: from data.runs when it indexes the list (as collision detection writes it), else from
// the contacts themselves (a list written by hand), consecutive contacts of the same bodies
template <typename F>
void ForEachRun(const Data& data, bool indexed, F&& f) {
  if (indexed) {
    for (int r = 0; r < data.nruns; ++r) {
      const PairRun& run = data.runs[r];
      f(run.body_a, run.body_b, run.begin, run.count);
    }
    return;
  }
  const Contact* contacts = data.contacts.data();
  for (int begin = 0; begin < data.ncontact;) {
    const int a = contacts[begin].body_a, b = contacts[begin].body_b;
    int end = begin + 1;
    while (end < data.ncontact && contacts[end].body_a == a && contacts[end].body_b == b) ++end;
    f(a, b, begin, end - begin);
    begin = end;
  }
}

// calls f(node_a, node_b, begin, count) for each run of contacts, a side's node its body, the
// tree of its link geom (nbody + tree) or -1 (static)
template <typename F>
void ForEachNodeRun(const Data& data, const Groups& g, bool indexed, F&& f) {
  const int nbody = static_cast<int>(data.bodies.size());
  const auto node = [&g, nbody](int body, int geom) {
    if (body >= 0) return body;
    const int t = geom >= 0 ? g.geom_tree[geom] : -1;
    return t >= 0 ? nbody + t : -1;
  };
  if (indexed) {
    for (int r = 0; r < data.nruns; ++r) {
      const PairRun& run = data.runs[r];
      f(node(run.body_a, run.geom_a), node(run.body_b, run.geom_b), run.begin, run.count);
    }
    return;
  }
  const Contact* contacts = data.contacts.data();
  for (int begin = 0; begin < data.ncontact;) {
    const Contact& c = contacts[begin];
    int end = begin + 1;
    while (end < data.ncontact && contacts[end].geom_a == c.geom_a &&
           contacts[end].geom_b == c.geom_b) {
      ++end;
    }
    f(node(c.body_a, c.geom_a), node(c.body_b, c.geom_b), begin, end - begin);
    begin = end;
  }
}

// BuildGroups for a model with trees: union-find over bodies and trees
void BuildGroupsWithTrees(Data& data, Groups& g) {
  const int nbody = static_cast<int>(data.bodies.size());
  const int nnode = nbody + g.ntree;
  const bool indexed = geometry::RunsIndexList(data);
  int* parent = g.parent.data();
  int* count = g.count.data();
  int* group = g.node_group.data();
  char* has_tree = g.node_has_tree.data();
  for (int i = 0; i < nnode; ++i) {
    parent[i] = i;
    count[i] = i >= nbody ? 1 : 0;  // every tree is in a group
    group[i] = -1;
    has_tree[i] = 0;
  }
  ForEachNodeRun(data, g, indexed, [parent, count](int a, int b, int, int) {
    if (a >= 0) count[a] = 1;
    if (b >= 0) count[b] = 1;
    if (a >= 0 && b >= 0) Unite(parent, a, b);
  });
  for (int t = 0; t < g.ntree; ++t) has_tree[FindRoot(parent, nbody + t)] = 1;
  int ngroup = 0;
  ForEachNodeRun(data, g, indexed, [&](int a, int b, int, int) {
    if (a < 0 && b < 0) return;  // two static sides (a list written by hand): no group
    const int root = FindRoot(parent, a >= 0 ? a : b);
    if (!has_tree[root] && group[root] < 0) group[root] = ngroup++;
  });
  const int nplain = ngroup;
  for (int t = 0; t < g.ntree; ++t) {
    const int root = FindRoot(parent, nbody + t);
    if (group[root] < 0) group[root] = ngroup++;
  }
  int* body_start = g.body_start.data();
  int* contact_start = g.contact_start.data();
  for (int k = 0; k <= ngroup; ++k) body_start[k] = contact_start[k] = 0;
  for (int k = 0; k <= ngroup - nplain; ++k) g.tree_start[k] = 0;
  for (int i = 0; i < nbody; ++i) {
    data.body_group[i] = count[i] != 0 ? group[FindRoot(parent, i)] : -1;
    g.slot[i] = count[i] != 0 ? body_start[data.body_group[i] + 1]++ : -1;
  }
  for (int t = 0; t < g.ntree; ++t) {
    const int k = group[FindRoot(parent, nbody + t)];
    g.tree_group[t] = k;
    g.tree_slot[t] = g.tree_start[k - nplain + 1]++;
  }
  for (int k = 0; k < ngroup; ++k) body_start[k + 1] += body_start[k];
  for (int k = 0; k < ngroup - nplain; ++k) g.tree_start[k + 1] += g.tree_start[k];
  for (int i = 0; i < nbody; ++i) {
    if (data.body_group[i] >= 0) g.bodies[body_start[data.body_group[i]] + g.slot[i]] = i;
  }
  for (int t = 0; t < g.ntree; ++t) {
    g.trees[g.tree_start[g.tree_group[t] - nplain] + g.tree_slot[t]] = t;
  }
  // contacts per group in list order (counting sort)
  const auto group_of = [&data, &g, nbody](int a, int b) {
    const int n = a >= 0 ? a : b;
    return n < 0 ? -1 : n < nbody ? data.body_group[n] : g.tree_group[n - nbody];
  };
  ForEachNodeRun(data, g, indexed, [contact_start, &group_of](int a, int b, int, int n) {
    if (group_of(a, b) >= 0) contact_start[group_of(a, b) + 1] += n;
  });
  for (int k = 0; k < ngroup; ++k) {
    contact_start[k + 1] += contact_start[k];
    count[k] = contact_start[k];
  }
  int* out = g.contacts.data();
  ForEachNodeRun(data, g, indexed, [out, count, &group_of](int a, int b, int begin, int n) {
    if (group_of(a, b) < 0) return;
    int& next = count[group_of(a, b)];
    for (int i = 0; i < n; ++i) out[next + i] = begin + i;
    next += n;
  });
  g.ngroup = nplain;
  g.ntree_group = ngroup - nplain;
  data.ngroup = nplain;
}

}  // namespace

void Groups::ReserveTrees(const Model& model) {
  ntree = static_cast<int>(model.trees.size());
  ntree_group = 0;
  geom_tree.assign(model.geoms.size(), -1);
  for (std::size_t i = 0; i < model.geoms.size(); ++i) geom_tree[i] = model.geoms[i].tree;
  if (ntree == 0) return;
  const int nbody = static_cast<int>(model.bodies.size());
  const int nnode = nbody + ntree;
  parent.assign(nnode, 0);
  count.assign(nnode, 0);
  body_start.assign(nnode + 1, 0);
  contact_start.assign(nnode + 1, 0);
  tree_start.assign(ntree + 1, 0);
  trees.assign(ntree, 0);
  tree_group.assign(ntree, -1);
  tree_slot.assign(ntree, 0);
  node_group.assign(nnode, -1);
  node_has_tree.assign(nnode, 0);
}

void Groups::Reserve(int nbody, int max_contacts) {
  ntree = 0;
  ntree_group = 0;
  parent.assign(nbody, 0);
  body_start.assign(nbody + 1, 0);
  bodies.assign(nbody, 0);
  contact_start.assign(nbody + 1, 0);
  contacts.assign(max_contacts, 0);
  slot.assign(nbody, -1);
  count.assign(nbody, 0);
  ngroup = 0;
}

void BuildGroups(Data& data, Groups& g) {
  if (g.ntree > 0) {
    BuildGroupsWithTrees(data, g);
    return;
  }
  const int nbody = static_cast<int>(data.bodies.size());
  const int ncontact = data.ncontact;
  const bool indexed = geometry::RunsIndexList(data);
  int* parent = g.parent.data();
  int* count = g.count.data();
  int* body_group = data.body_group.data();
  for (int i = 0; i < nbody; ++i) {
    parent[i] = i;
    count[i] = 0;  // marks the bodies in contact
  }
  // the points of one geom pair are contiguous and share their bodies: one union per run. Each
  // root is the lowest index of its component whatever the order of the unions.
  ForEachRun(data, indexed, [parent, count](int a, int b, int, int) {
    if (a >= 0) count[a] = 1;
    if (b >= 0) count[b] = 1;
    if (a >= 0 && b >= 0) Unite(parent, a, b);
  });
  // number the groups in the order of their first contacts in the list (its root's entry of
  // body_group holds a group's number until every body has its own). Two threads take the list's
  // pairs and the groups from the same ends, so that the contacts a thread writes in stage 2 are
  // mostly those it reads in stages 3 to 5 (docs/decisions.md, "Groups in the order of the contact
  // list"). A body's slot is the number of bodies of its group before it, counted in
  // body_start[k + 1] (zeroed as group k is made: the arrays' capacity is nbody + 1, their used
  // part ngroup + 1)
  int* body_start = g.body_start.data();
  int* contact_start = g.contact_start.data();
  int* slot = g.slot.data();
  int ngroup = 0;
  for (int i = 0; i < nbody; ++i) body_group[i] = -1;
  ForEachRun(data, indexed, [&](int a, int b, int, int) {
    const int root = FindRoot(parent, a >= 0 ? a : b);  // a contact has a dynamic body
    if (body_group[root] >= 0) return;
    body_group[root] = ngroup;
    body_start[ngroup + 1] = 0;
    contact_start[ngroup + 1] = 0;
    ++ngroup;
  });
  for (int i = 0; i < nbody; ++i) {
    if (count[i] == 0) {
      slot[i] = -1;
      continue;
    }
    const int k = body_group[FindRoot(parent, i)];
    body_group[i] = k;
    slot[i] = body_start[k + 1]++;
  }
  body_start[0] = 0;
  contact_start[0] = 0;
  g.ngroup = ngroup;
  data.ngroup = ngroup;
  if (ngroup == 1) {
    // one group (the usual case of a small scene) holds every body in contact and every contact
    // (each has a dynamic body), in index order: no offsets to sum
    for (int i = 0; i < nbody; ++i) {
      if (slot[i] >= 0) g.bodies[slot[i]] = i;
    }
    for (int c = 0; c < ncontact; ++c) g.contacts[c] = c;
    contact_start[1] = ncontact;
    return;
  }
  // bodies per group, at their slots after the group's offset
  for (int k = 0; k < ngroup; ++k) body_start[k + 1] += body_start[k];
  for (int i = 0; i < nbody; ++i) {
    if (body_group[i] >= 0) g.bodies[body_start[body_group[i]] + slot[i]] = i;
  }
  // contacts per group (counting sort keeps contact order inside a group); each contact's group
  // is its dynamic body's (contacts are only read here: the tick's second thread may be working
  // on other fields of them, ClassifyContacts)
  const auto group_of = [body_group](int a, int b) { return body_group[a >= 0 ? a : b]; };
  ForEachRun(data, indexed, [contact_start, &group_of](int a, int b, int, int n) {
    contact_start[group_of(a, b) + 1] += n;
  });
  for (int k = 0; k < ngroup; ++k) {
    contact_start[k + 1] += contact_start[k];
    count[k] = contact_start[k];
  }
  int* out = g.contacts.data();
  ForEachRun(data, indexed, [out, count, &group_of](int a, int b, int begin, int n) {
    int& next = count[group_of(a, b)];
    for (int i = 0; i < n; ++i) out[next + i] = begin + i;
    next += n;
  });
}

}  // namespace rigidtouch::contact
