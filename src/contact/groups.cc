#include "contact/groups.h"

#include <utility>

namespace rigidtouch::contact {
namespace {

int Find(int* parent, int i) {
  while (parent[i] != i) {
    parent[i] = parent[parent[i]];  // path halving
    i = parent[i];
  }
  return i;
}

void Unite(int* parent, int a, int b) {
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
  const int ncontact = data.ncontact;
  const Contact* contacts = data.contacts.data();
  int* parent = g.parent.data();
  int* count = g.count.data();
  int* body_group = data.body_group.data();
  for (int i = 0; i < nbody; ++i) {
    parent[i] = i;
    count[i] = 0;  // marks the bodies in contact
  }
  // the points of one geom pair are contiguous and share their bodies: one union per run. Each
  // root is the lowest index of its component whatever the order of the unions.
  int last_a = -2, last_b = -2;
  for (int c = 0; c < ncontact; ++c) {
    const int a = contacts[c].body_a, b = contacts[c].body_b;
    if (a == last_a && b == last_b) continue;
    last_a = a;
    last_b = b;
    if (a >= 0) count[a] = 1;
    if (b >= 0) count[b] = 1;
    if (a >= 0 && b >= 0) Unite(parent, a, b);
  }
  // number the groups by their root (the lowest body index), in body order: a body's root comes
  // no later than the body, so its group is known by then. A body's slot is the number of bodies
  // of its group before it, counted in body_start[k + 1] (zeroed as group k is made: the arrays'
  // capacity is nbody + 1, their used part ngroup + 1)
  int* body_start = g.body_start.data();
  int* contact_start = g.contact_start.data();
  int* slot = g.slot.data();
  int ngroup = 0;
  for (int i = 0; i < nbody; ++i) {
    if (count[i] == 0) {
      body_group[i] = -1;
      slot[i] = -1;
      continue;
    }
    const int root = Find(parent, i);
    int k;
    if (root == i) {
      k = ngroup++;
      body_start[k + 1] = 0;
      contact_start[k + 1] = 0;
    } else {
      k = body_group[root];
    }
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
  const auto group_of = [contacts, body_group](int c) {
    return body_group[contacts[c].body_a >= 0 ? contacts[c].body_a : contacts[c].body_b];
  };
  for (int c = 0; c < ncontact; ++c) ++contact_start[group_of(c) + 1];
  for (int k = 0; k < ngroup; ++k) {
    contact_start[k + 1] += contact_start[k];
    count[k] = contact_start[k];
  }
  for (int c = 0; c < ncontact; ++c) g.contacts[count[group_of(c)]++] = c;
}

}  // namespace rigidtouch::contact
