#include "contact/groups.h"

#include <algorithm>

namespace rigidtouch::contact {
namespace {

int Find(std::vector<int>& parent, int i) {
  while (parent[i] != i) {
    parent[i] = parent[parent[i]];  // path halving
    i = parent[i];
  }
  return i;
}

void Unite(std::vector<int>& parent, int a, int b) {
  a = Find(parent, a);
  b = Find(parent, b);
  if (a == b) return;
  if (a < b) std::swap(a, b);
  parent[a] = b;  // the lowest index is the root: deterministic group order
}

}  // namespace

void Groups::Reserve(int nbody, int max_contacts) {
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
  const int nbody = static_cast<int>(data.bodies.size());
  for (int i = 0; i < nbody; ++i) g.parent[i] = i;
  std::fill(g.count.begin(), g.count.end(), 0);  // contacts per body, marks bodies in contact
  for (int c = 0; c < data.ncontact; ++c) {
    const Contact& con = data.contacts[c];
    if (con.body_a >= 0) ++g.count[con.body_a];
    if (con.body_b >= 0) ++g.count[con.body_b];
    if (con.body_a >= 0 && con.body_b >= 0) Unite(g.parent, con.body_a, con.body_b);
  }
  // number the groups by their root (the lowest body index), in body order
  g.ngroup = 0;
  for (int i = 0; i < nbody; ++i) data.body_group[i] = -1;
  for (int i = 0; i < nbody; ++i) {
    if (g.count[i] == 0) continue;
    const int root = Find(g.parent, i);
    if (root == i) data.body_group[i] = g.ngroup++;
  }
  for (int i = 0; i < nbody; ++i) {
    if (g.count[i] != 0) data.body_group[i] = data.body_group[Find(g.parent, i)];
  }
  // bodies per group (counting sort keeps body order inside a group)
  std::fill(g.body_start.begin(), g.body_start.begin() + g.ngroup + 1, 0);
  for (int i = 0; i < nbody; ++i) {
    if (data.body_group[i] >= 0) ++g.body_start[data.body_group[i] + 1];
  }
  for (int k = 0; k < g.ngroup; ++k) g.body_start[k + 1] += g.body_start[k];
  for (int k = 0; k < g.ngroup; ++k) g.count[k] = g.body_start[k];
  for (int i = 0; i < nbody; ++i) {
    const int k = data.body_group[i];
    if (k < 0) {
      g.slot[i] = -1;
      continue;
    }
    g.slot[i] = g.count[k] - g.body_start[k];
    g.bodies[g.count[k]++] = i;
  }
  // contacts per group
  std::fill(g.contact_start.begin(), g.contact_start.begin() + g.ngroup + 1, 0);
  for (int c = 0; c < data.ncontact; ++c) {
    Contact& con = data.contacts[c];
    con.group = data.body_group[con.body_a >= 0 ? con.body_a : con.body_b];
    ++g.contact_start[con.group + 1];
  }
  for (int k = 0; k < g.ngroup; ++k) g.contact_start[k + 1] += g.contact_start[k];
  for (int k = 0; k < g.ngroup; ++k) g.count[k] = g.contact_start[k];
  for (int c = 0; c < data.ncontact; ++c) g.contacts[g.count[data.contacts[c].group]++] = c;
  data.ngroup = g.ngroup;
}

}  // namespace rigidtouch::contact
