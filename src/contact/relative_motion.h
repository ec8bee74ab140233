// Relative motion at a contact point: the offsets of the point from the two bodies' centres of
// mass and the velocity of a's material point relative to b's.
#pragma once

#include "dynamics/rigid_body.h"
#include "rigidtouch/data.h"

namespace rigidtouch::contact {

/// The contact point's offsets from the centres of mass of a and b (zero for static geometry).
inline void Offsets(const Data& data, const Contact& c, Vec3* r_a, Vec3* r_b) {
  *r_a = c.body_a >= 0 ? Vec3(c.p_W - data.bodies[c.body_a].x_W) : Vec3::Zero();
  *r_b = c.body_b >= 0 ? Vec3(c.p_W - data.bodies[c.body_b].x_W) : Vec3::Zero();
}

/// Velocity of a's point relative to b's at the offsets r_a, r_b  [m/s]; its component along n_W
/// is positive when the bodies separate.
inline Vec3 RelativeVelocity(const Data& data, const Contact& c, const Vec3& r_a, const Vec3& r_b) {
  Vec3 u = Vec3::Zero();
  if (c.body_a >= 0) u += dynamics::PointVelocity(data.bodies[c.body_a], r_a);
  if (c.body_b >= 0) u -= dynamics::PointVelocity(data.bodies[c.body_b], r_b);
  return u;
}

}  // namespace rigidtouch::contact
