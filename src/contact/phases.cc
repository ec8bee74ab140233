#include "contact/phases.h"

#include <algorithm>

#include "contact/friction.h"
#include "contact/relative_motion.h"

namespace rigidtouch::contact {

void ContactScratch::Reserve(int nbody, int max_contacts) {
  groups.Reserve(nbody, max_contacts);
  laws.resize(max_contacts);
  anchor_displacement.resize(max_contacts);
  normal_velocity.resize(max_contacts);
  group_phase.assign(nbody, ContactPhase::kResting);
}

namespace {

// how long after a group's last onset a new onset keeps the group's solver hint
// (WindowState::interior): the longest collision window the method allows (human reaction time;
// the train's default t_c), for every renderer
constexpr double kSolverHintLifetime_s = 0.1;

}  // namespace

WindowState GroupWindow(const Model& model, const Data& data, const ContactScratch& scratch,
                        int g) {
  const Groups& G = scratch.groups;
  WindowState w;
  for (int k = G.body_start[g]; k < G.body_start[g + 1]; ++k) {
    const WindowState& b = data.window[G.bodies[k]];
    if (b.onset_step > w.onset_step) w = b;
  }
  if (model.render.renderer == RendererKind::kPenalty) return w;
  for (int k = G.contact_start[g]; k < G.contact_start[g + 1]; ++k) {
    const int ci = G.contacts[k];
    if (data.contacts[ci].is_new && scratch.normal_velocity[ci] < -model.contact.onset_speed_mps) {
      // a group that collides again within kSolverHintLifetime_s of its last onset keeps its
      // solver hint
      const double since_s = static_cast<double>(data.step - w.onset_step) * model.timestep_s;
      if (w.onset_step < 0 || since_s >= kSolverHintLifetime_s) w.interior = false;
      w.onset_step = data.step;
      w.impulses_done = 0;
      break;
    }
  }
  return w;
}

bool InWindow(const Model& model, const WindowState& window, std::int64_t step) {
  if (window.onset_step < 0) return false;
  const std::int64_t k = step - window.onset_step;
  return model.render.renderer == RendererKind::kTrain ? k < model.schedule.window_steps : k == 0;
}

namespace {

// contacts per block the two threads take in ClassifyContacts
constexpr int kContactBlock = 64;
// fewer contacts than this are not worth the hand-off to the worker
constexpr int kMinClassifyContactsForTwoThreads = 128;

bool SamePair(const Contact& a, const Contact& b) {
  return a.geom_a == b.geom_a && a.geom_b == b.geom_b;
}

// the first contact at or after ci that starts a geom pair's points
int PairStartFrom(const Data& data, int ci) {
  while (ci > 0 && ci < data.ncontact && SamePair(data.contacts[ci - 1], data.contacts[ci])) ++ci;
  return std::min(ci, data.ncontact);
}

// the points [first, last) of one geom pair: each one's law (one per pair) and, when new, its
// approach speed; stick or slip for the pair. Writes only those contacts and entries.
void ClassifyPair(const Model& model, Data& data, ContactScratch& scratch, int first, int last) {
  const PenaltyLaw law = LawFor(model, data.contacts[first]);
  for (int ci = first; ci < last; ++ci) {
    const Contact& c = data.contacts[ci];
    // the approach speed only matters for a new contact (a collision onset, GroupWindow)
    scratch.normal_velocity[ci] = 0.0;
    if (c.is_new) {
      Vec3 r_a, r_b;
      Offsets(data, c, &r_a, &r_b);
      scratch.normal_velocity[ci] = RelativeVelocity(data, c, r_a, r_b).dot(c.n_W);
    }
    scratch.laws[ci] = law;
  }
  DecidePatchFriction(data, scratch.laws, scratch.anchor_displacement, first, last);
}

// the geom pairs whose points start in [begin, end) (ClassifyPair)
void ClassifyPairs(const Model& model, Data& data, ContactScratch& scratch, int begin, int end) {
  for (int first = PairStartFrom(data, begin); first < end;) {
    int last = first + 1;
    while (last < data.ncontact && SamePair(data.contacts[first], data.contacts[last])) ++last;
    ClassifyPair(model, data, scratch, first, last);
    first = last;
  }
}

}  // namespace

// The group's contacts get the phase in stage 4, which writes each of them anyway: here, where a
// group's contacts lie all over the list, between the other thread's groups' ones, writing them
// cost three times as much on two threads as on one
void UpdateGroupWindow(const Model& model, Data& data, ContactScratch& scratch, int g) {
  const Groups& G = scratch.groups;
  const WindowState w = GroupWindow(model, data, scratch, g);
  for (int k = G.body_start[g]; k < G.body_start[g + 1]; ++k) data.window[G.bodies[k]] = w;
  scratch.group_phase[g] =
      InWindow(model, w, data.step) ? ContactPhase::kColliding : ContactPhase::kResting;
}

void ClassifyGroup(const Model& model, Data& data, ContactScratch& scratch, int g) {
  const Groups& G = scratch.groups;
  // a geom pair's points are consecutive in data.contacts and all in one group, so in the group's
  // list too
  const int end = G.contact_start[g + 1];
  for (int k = G.contact_start[g]; k < end;) {
    const int first = G.contacts[k];
    int n = 1;
    while (k + n < end && G.contacts[k + n] == first + n &&
           SamePair(data.contacts[first], data.contacts[first + n])) {
      ++n;
    }
    ClassifyPair(model, data, scratch, first, first + n);
    k += n;
  }
  UpdateGroupWindow(model, data, scratch, g);
}

void ClassifyByPairs(const Model& model, Data& data, ContactScratch& scratch,
                     parallel::Worker* worker, parallel::Task alongside) {
  // the pairs are independent: blocks of contacts, each taking the pairs that start in it. The
  // groups, whose building only reads the contacts' bodies and which no pair's work reads, are
  // built first on this thread while the worker starts on the pairs
  const int n = data.ncontact;
  const int nblock = (n + kContactBlock - 1) / kContactBlock;
  parallel::ShareRange(
      n >= kMinClassifyContactsForTwoThreads ? worker : nullptr, nblock,
      [&model, &data, &scratch, n](int k) {
        ClassifyPairs(model, data, scratch, k * kContactBlock,
                      std::min(n, (k + 1) * kContactBlock));
      },
      [&data, &scratch, alongside] {
        BuildGroups(data, scratch.groups);
        alongside();
      });
}

}  // namespace rigidtouch::contact
