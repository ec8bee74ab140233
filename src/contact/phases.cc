#include "contact/phases.h"

#include "contact/friction.h"
#include "contact/relative_motion.h"

namespace rigidtouch::contact {

void ContactScratch::Reserve(int nbody, int max_contacts) {
  groups.Reserve(nbody, max_contacts);
  laws.resize(max_contacts);
  anchor_displacement.resize(max_contacts);
  normal_velocity.resize(max_contacts);
}

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

void ClassifyContacts(const Model& model, Data& data, ContactScratch& scratch) {
  BuildGroups(data, scratch.groups);
  for (int ci = 0; ci < data.ncontact; ++ci) {
    const Contact& c = data.contacts[ci];
    // the approach speed only matters for a new contact (a collision onset, GroupWindow)
    scratch.normal_velocity[ci] = 0.0;
    if (c.is_new) {
      Vec3 r_a, r_b;
      Offsets(data, c, &r_a, &r_b);
      scratch.normal_velocity[ci] = RelativeVelocity(data, c, r_a, r_b).dot(c.n_W);
    }
    // one law per geom pair: its points are consecutive
    const bool same_pair = ci > 0 && data.contacts[ci - 1].geom_a == c.geom_a &&
                           data.contacts[ci - 1].geom_b == c.geom_b &&
                           data.contacts[ci - 1].pair_points == c.pair_points;
    scratch.laws[ci] = same_pair ? scratch.laws[ci - 1] : LawFor(model, c);
  }
  DecidePatchFriction(data, scratch.laws, scratch.anchor_displacement);
  const Groups& G = scratch.groups;
  for (int g = 0; g < G.ngroup; ++g) {
    const WindowState w = GroupWindow(model, data, scratch, g);
    for (int k = G.body_start[g]; k < G.body_start[g + 1]; ++k) data.window[G.bodies[k]] = w;
    const ContactPhase phase =
        InWindow(model, w, data.step) ? ContactPhase::kColliding : ContactPhase::kResting;
    for (int k = G.contact_start[g]; k < G.contact_start[g + 1]; ++k) {
      data.contacts[G.contacts[k]].phase = phase;
    }
  }
}

}  // namespace rigidtouch::contact
