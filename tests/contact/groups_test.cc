// Contact groups against a plain reference: connected components of the bodies through contacts
// by repeated relaxation, numbered in the order of their first contacts, bodies and contacts in
// index order; from the list's runs (Data::runs, as collision detection writes them) and from the
// contacts alone.
#include "contact/groups.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <utility>
#include <vector>

namespace rigidtouch::contact {
namespace {

// random contact lists in runs of 1-4 points of one body pair, as DetectContacts writes a geom
// pair's points, and their runs in data.runs; body -1 is static
void RandomContacts(std::mt19937_64& rng, int nbody, Data& data) {
  std::uniform_int_distribution<int> body(-1, nbody - 1), points(1, 4);
  const int cap = static_cast<int>(data.contacts.size());
  data.ncontact = 0;
  data.nruns = 0;
  const int npair = std::uniform_int_distribution<int>(0, nbody)(rng);
  for (int p = 0; p < npair && data.ncontact < cap; ++p) {
    int a = body(rng), b = body(rng);
    if (a == b) continue;
    if (a < 0) std::swap(a, b);  // a is dynamic
    const int begin = data.ncontact;
    for (int k = points(rng); k > 0 && data.ncontact < cap; --k) {
      Contact& c = data.contacts[data.ncontact++];
      c.body_a = a;
      c.body_b = b;
      c.group = -7;
    }
    data.runs[data.nruns++] = PairRun{p, p + 1, a, b, begin, data.ncontact - begin};
  }
}

// every body in one chain, every third also on the floor: one group of all bodies (no runs: the
// contacts are read)
void ChainContacts(int nbody, Data& data) {
  data.ncontact = 0;
  data.nruns = 0;
  auto add = [&data](int a, int b) {
    Contact& c = data.contacts[data.ncontact++];
    c.body_a = a;
    c.body_b = b;
    c.group = -7;
  };
  for (int i = 0; i < nbody; ++i) {
    if (i % 3 == 0) add(i, -1);
    if (i + 1 < nbody) add(i, i + 1);
  }
}

TEST(GroupsTest, SameAsReferenceOnRandomContacts) {
  std::mt19937_64 rng(3);
  // one Groups for every trial, as a Workspace keeps it from tick to tick: nothing may depend on
  // what the last call left
  Groups g;
  g.Reserve(23, 64);
  for (int trial = 0; trial < 1000; ++trial) {
    const int nbody = 1 + trial % 23;
    Data data;
    data.bodies.resize(nbody);
    data.contacts.resize(64);
    data.runs.resize(64);
    data.body_group.assign(nbody, 5);
    if (trial % 5 == 4) {
      ChainContacts(nbody, data);
    } else {
      RandomContacts(rng, nbody, data);
      // every third list without its runs, and every third after that with runs that do not
      // cover it (a list written by hand): the contacts themselves are read
      if (trial % 3 == 1) data.nruns = 0;
      if (trial % 3 == 2 && data.nruns > 0) --data.nruns;
    }
    BuildGroups(data, g);

    // reference: label each body by the lowest body it connects to
    std::vector<int> label(nbody), touched(nbody, 0);
    for (int i = 0; i < nbody; ++i) label[i] = i;
    for (int c = 0; c < data.ncontact; ++c) {
      const Contact& con = data.contacts[c];
      if (con.body_a >= 0) touched[con.body_a] = 1;
      if (con.body_b >= 0) touched[con.body_b] = 1;
    }
    for (bool changed = true; changed;) {
      changed = false;
      for (int c = 0; c < data.ncontact; ++c) {
        const Contact& con = data.contacts[c];
        if (con.body_a < 0 || con.body_b < 0) continue;
        const int low = std::min(label[con.body_a], label[con.body_b]);
        for (const int b : {con.body_a, con.body_b}) {
          if (label[b] != low) {
            label[b] = low;
            changed = true;
          }
        }
      }
    }
    // numbered in the order of the first contact of each
    std::vector<int> group_of_label(nbody, -1), body_group(nbody, -1);
    int ngroup = 0;
    for (int c = 0; c < data.ncontact; ++c) {
      const int l = label[data.contacts[c].body_a];
      if (group_of_label[l] < 0) group_of_label[l] = ngroup++;
    }
    for (int i = 0; i < nbody; ++i) {
      if (touched[i]) body_group[i] = group_of_label[label[i]];
    }
    ASSERT_EQ(data.ngroup, ngroup);
    ASSERT_EQ(g.ngroup, ngroup);
    EXPECT_EQ(data.body_group, body_group);
    // bodies and contacts of each group in index order, and each body's slot in its group
    for (int k = 0; k < ngroup; ++k) {
      std::vector<int> bodies, contacts;
      for (int i = 0; i < nbody; ++i) {
        if (body_group[i] == k) bodies.push_back(i);
      }
      for (int c = 0; c < data.ncontact; ++c) {
        const Contact& con = data.contacts[c];
        if (body_group[con.body_a] == k) contacts.push_back(c);
      }
      EXPECT_EQ(std::vector<int>(g.bodies.begin() + g.body_start[k],
                                 g.bodies.begin() + g.body_start[k + 1]),
                bodies);
      EXPECT_EQ(std::vector<int>(g.contacts.begin() + g.contact_start[k],
                                 g.contacts.begin() + g.contact_start[k + 1]),
                contacts);
      for (std::size_t s = 0; s < bodies.size(); ++s) {
        EXPECT_EQ(g.slot[bodies[s]], static_cast<int>(s));
      }
    }
    for (int i = 0; i < nbody; ++i) {
      if (body_group[i] < 0) {
        EXPECT_EQ(g.slot[i], -1);
      }
    }
  }
}

}  // namespace
}  // namespace rigidtouch::contact
