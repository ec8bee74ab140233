// Kinematics (the tick's stage after coupling): each body's rotation matrix at this tick's poses,
// written once into Data::R_WB and read by collision, contact, dynamics and impulses until the
// positions are integrated.
#pragma once

#include "rigidtouch/data.h"

namespace rigidtouch::dynamics {

/// Writes data.R_WB[i] from data.bodies[i].q_WB for every body.
void ComputeKinematics(Data& data);

/// World position of a point given in a body's frame (the world's for body -1), at this tick's
/// rotations.
[[gnu::always_inline]] inline Vec3 WorldPoint(const Data& data, int body, const Vec3& p_B) {
  if (body < 0) return p_B;
  return data.bodies[body].x_W + data.R_WB[body] * p_B;
}

/// A world point in a body's frame (the world's for body -1), at this tick's rotations.
inline Vec3 LocalPoint(const Data& data, int body, const Vec3& p_W) {
  if (body < 0) return p_W;
  return data.R_WB[body].transpose() * (p_W - data.bodies[body].x_W);
}

}  // namespace rigidtouch::dynamics
