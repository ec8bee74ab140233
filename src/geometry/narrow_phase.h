// Hand-written narrow phase for plane, sphere and box pairs (tick stage 2). Replaces MuJoCo's
// mj_collision for these pairs because it allocates every tick, misses the step-time goal on the
// 100-box pile, and its box-box depths jump by a factor of two between ticks on a resting stack.
// Every routine is deterministic (the same poses give bitwise the same points in the same order),
// never allocates or throws, and gives depths that vary continuously with the pose while the
// contact keeps its type.
#pragma once

#include "rigidtouch/model.h"
#include "rigidtouch/types.h"

namespace rigidtouch::geometry {

/// Pose of a geom in the world frame.
struct GeomPose {
  Vec3 p_W;
  Mat3 R_WG;
};

/// One contact point between geom 1 and geom 2: n_W is the unit normal pointing from geom 2
/// towards geom 1 (the force on geom 1 acts along +n), depth_m > 0 is the penetration, p_W the
/// midpoint between the two surfaces (MuJoCo's convention).
struct ContactPoint {
  Vec3 p_W;
  Vec3 n_W;
  double depth_m;
};

/// Maximum points one pair can produce.
inline constexpr int kMaxPairContacts = 8;

/// True if this pair of types is handled here (plane, sphere, box in any order except
/// plane-plane).
bool HasNarrowPhase(GeomType a, GeomType b);

/// Contact points of geoms 1 and 2 with penetration > 0 only (no margin), at most `capacity`
/// (<= kMaxPairContacts). Sizes use MuJoCo's convention: sphere size.x() = radius, box size =
/// half-extents, plane: the geom's local z axis is the normal through p_W, infinite. Returns the
/// number written. Never allocates or throws; non-finite input gives 0.
///
/// Pairs: sphere-plane, sphere-sphere and sphere-box give one point (a sphere centre inside a box
/// is pushed out through the nearest face). Box-plane gives every penetrating vertex, the
/// deepest four if more penetrate. Box-box runs the separating axis test over the 15 axes,
/// preferring face axes (and geom 1's faces over geom 2's) unless another axis penetrates at
/// least 5% less; a face axis clips the incident face against the reference face's side planes
/// and keeps at most 4 points below the reference face (the deepest, then those spanning the
/// largest area), an edge-edge axis gives one point between the two edges. Non-positive sizes,
/// unsupported pairs, a null `out` or `capacity` <= 0 give 0. Rotations must be orthonormal.
int Collide(GeomType t1, const Vec3& size1, const GeomPose& pose1, GeomType t2, const Vec3& size2,
            const GeomPose& pose2, ContactPoint* out, int capacity);

/// Whether every number of a pose is finite (Collide gives no contact otherwise).
inline bool PoseFinite(const GeomPose& pose) {
  // x * 0 is 0 for a finite x and NaN otherwise, and a sum with a NaN term is NaN
  return (pose.p_W.array() * 0.0).sum() + (pose.R_WG.array() * 0.0).sum() == 0.0;
}

/// Whether the size components that a type handled here uses are positive and finite (Collide
/// gives no contact otherwise). False for the types not handled here.
bool SizeValid(GeomType type, const Vec3& size);

/// Collide without its argument checks, for a caller that checks each geom once rather than each
/// pair: HasNarrowPhase(t1, t2), PoseFinite and SizeValid for both geoms, `out` not null and
/// 0 < capacity <= kMaxPairContacts must hold. Gives then the same points as Collide.
int CollideAccepted(GeomType t1, const Vec3& size1, const GeomPose& pose1, GeomType t2,
                    const Vec3& size2, const GeomPose& pose2, ContactPoint* out, int capacity);

}  // namespace rigidtouch::geometry
