// Coulomb friction through a tangential stick anchor (tick stages 3 and 4): each contact keeps an
// anchor on both bodies; while it sticks, a spring-damper between the anchors holds the contact,
// and once the spring's force would leave the friction cone the anchor slides so that the force
// stays on the cone's edge.
#pragma once

#include <span>

#include "contact/penalty.h"
#include "dynamics/kinematics.h"
#include "rigidtouch/data.h"

namespace rigidtouch::contact {

/// Tangential stretch of the stick anchor: a's anchor relative to b's, in the tangent plane  [m].
/// (Inline: it is evaluated for every scene contact every tick.)
[[gnu::always_inline]] inline Vec3 AnchorDisplacement(const Data& data, const Contact& c) {
  const Vec3 d = dynamics::WorldPoint(data, c.body_a, c.anchor_A) -
                 dynamics::WorldPoint(data, c.body_b, c.anchor_B);
  return d - d.dot(c.n_W) * c.n_W;
}

/// Moves b's anchor so that the anchor spring alone, of stiffness kt, would exert `f_t` on a (the
/// slip limit); `s` is the anchor's stretch before the move.
void SlideAnchor(const Data& data, Contact& c, const Vec3& s, const Vec3& f_t, double kt);

/// Decides stick or slip for the geom pair whose points are data.contacts[begin, end), from the
/// anchor springs alone: the points of one face are one contact patch with one friction cone
/// (sum |kt s| <= mu_s sum k d), and a decision on state, not on velocities, cannot chatter with
/// velocity noise. Only implicit (scene) contacts; writes their anchor stretch into
/// `anchor_displacement`. A tool contact decides alone (penalty stage).
void DecidePatchFriction(Data& data, std::span<const PenaltyLaw> laws,
                         std::span<Vec3> anchor_displacement, int begin, int end);

}  // namespace rigidtouch::contact
