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

/// Places the anchors at the contact point with the tangential stretch `s`: a's at the contact
/// point, b's at `s` behind it. Called every tick a loaded contact's friction is computed, so the
/// anchors move with the bodies for one tick only and the stretch grows by the slip of the
/// material points at the contact (Cundall and Strack 1979). Anchors kept on the bodies for
/// longer would leave the contact on a body that rolls or spins: the spring, whose force acts at
/// the contact point, would then resist rolling and do work its energy does not account for.
/// (Inline: it is called for every loaded contact every tick.)
[[gnu::always_inline]] inline void PlaceAnchors(const Data& data, Contact& c, const Vec3& s) {
  c.anchor_A = c.p_A;  // the contact point in a's frame
  c.anchor_B = dynamics::LocalPoint(data, c.body_b, c.p_W - s);
}

/// Places the anchors (PlaceAnchors) so that the anchor spring alone, of stiffness kt, would
/// exert `f_t` on a (the slip limit); without a spring (kt <= 0) the stretch `s` is kept.
void SlideAnchor(const Data& data, Contact& c, const Vec3& s, const Vec3& f_t, double kt);

/// Decides stick or slip for the geom pair whose points are data.contacts[begin, end), from the
/// anchor springs alone: the points of one face are one contact patch with one friction cone
/// (sum |kt s| <= mu_s sum k d), and a decision on state, not on velocities, cannot chatter with
/// velocity noise. Only implicit (scene) contacts; writes their anchor stretch into
/// `anchor_displacement`. A tool contact decides alone (penalty stage).
void DecidePatchFriction(Data& data, std::span<const PenaltyLaw> laws,
                         std::span<Vec3> anchor_displacement, int begin, int end);

}  // namespace rigidtouch::contact
