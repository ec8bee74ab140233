// How many candidate pairs and contact points a scene can produce in one tick, bounded from the
// scene at load time (issue 16), so that the broad phase and the contact list are sized once and
// never drop a pair or a point of a scene that behaves: the tick never allocates.
//
// Two bounds, the smaller is taken:
// - exact: every geom pair the collision filter lets collide (not both static, not on one body),
//   times the most points one pair of their types gives (MaxPairPoints);
// - packing, for large scenes of solid geoms that do not overlap: the geoms that can overlap geom
//   i's bounding box, or touch i, lie in a region around i whose volume is known (a box around
//   i's box, i grown by twice the largest geom radius); since they do not overlap each other,
//   their volumes sum to at most that region's, which bounds how many there are (counting the
//   smallest geoms first). Pairs with static geoms are counted exactly.
#pragma once

#include "rigidtouch/model.h"

namespace rigidtouch::geometry {

/// Most contact points one pair of geoms of these types gives in one tick: rigidtouch's narrow
/// phase (1 for a sphere, 4 for a box face manifold), MuJoCo 2.2's functions for capsules (2)
/// and meshes (3 on a plane, 5 with multiccd otherwise); 0 for pairs that never collide.
int MaxPairPoints(GeomType a, GeomType b);

/// The scene's bounds for one tick.
struct SceneCapacity {
  long collidable_pairs = 0;  // geom pairs the collision filter lets collide
  long exact_contacts = 0;    // the exact bound on points: their MaxPairPoints summed
  long pairs = 0;             // bound on candidate pairs (min of the exact and packing bounds)
  long contacts = 0;          // bound on contact points (min of the exact and packing bounds)
  bool packing = false;       // whether the packing bound applied (solid, non-overlapping geoms)
};

/// Bounds the pairs and contacts of `model` (its geoms only). O(ngeom^2) for the exact count.
SceneCapacity BoundCapacity(const Model& model);

/// Largest capacity (pairs or contacts) the bounds may reach; a scene needing more is refused.
inline constexpr long kMaxCapacity = 10'000'000;

/// Model::max_contacts for a loaded scene: BoundCapacity's contacts (at least 16) when
/// `requested` is 0, else `requested`, which must hold them. Throws Error naming the number the
/// scene needs if `requested` is smaller, or if the bound exceeds kMaxCapacity.
int MaxContactsFor(const Model& model, int requested);

}  // namespace rigidtouch::geometry
