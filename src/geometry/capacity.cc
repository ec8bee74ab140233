#include "geometry/capacity.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "geometry/broadphase.h"

namespace rigidtouch::geometry {
namespace {

// volume of a solid geom [m^3]; 0 for a plane or a mesh (whose volume the model does not keep)
double Volume(const GeomModel& g) {
  const double pi = std::numbers::pi;
  switch (g.type) {
    case GeomType::kSphere:
      return 4.0 / 3.0 * pi * std::pow(g.size.x(), 3);
    case GeomType::kBox:
      return 8.0 * g.size.x() * g.size.y() * g.size.z();
    case GeomType::kCapsule:
      return pi * g.size.x() * g.size.x() * 2.0 * g.size.y() +
             4.0 / 3.0 * pi * std::pow(g.size.x(), 3);
    default:
      return 0.0;
  }
}

// volume of the geom grown by `d` (Steiner's formula for the box; a sphere or a capsule grows
// its radius)
double GrownVolume(const GeomModel& g, double d) {
  const double pi = std::numbers::pi;
  switch (g.type) {
    case GeomType::kSphere:
      return 4.0 / 3.0 * pi * std::pow(g.size.x() + d, 3);
    case GeomType::kBox: {
      const double a = g.size.x(), b = g.size.y(), c = g.size.z();
      return 8.0 * a * b * c + 8.0 * (a * b + b * c + c * a) * d + 2.0 * pi * (a + b + c) * d * d +
             4.0 / 3.0 * pi * d * d * d;
    }
    case GeomType::kCapsule: {
      const double r = g.size.x() + d;
      return pi * r * r * 2.0 * g.size.y() + 4.0 / 3.0 * pi * r * r * r;
    }
    default:
      return 0.0;
  }
}

// whether the geom takes part in any collision at all
bool Collides(const GeomModel& g) {
  return g.contype != 0 || g.conaffinity != 0;
}

}  // namespace

int MaxPairPoints(GeomType a, GeomType b) {
  if (a > b) std::swap(a, b);  // kPlane < kSphere < kCapsule < kBox < kMesh
  if (a == GeomType::kPlane && b == GeomType::kPlane) return 0;
  if (b == GeomType::kMesh) return a == GeomType::kPlane ? 3 : 5;
  if (a == GeomType::kSphere) return 1;  // with a sphere, capsule, box or mesh (above)
  if (a == GeomType::kPlane && b == GeomType::kSphere) return 1;
  if (a == GeomType::kCapsule || b == GeomType::kCapsule) return 2;
  return 4;  // box with plane or box: one face manifold
}

SceneCapacity BoundCapacity(const Model& model) {
  const std::vector<GeomModel>& geoms = model.geoms;
  const int ngeom = static_cast<int>(geoms.size());
  SceneCapacity cap;
  // exact counts, and per dynamic geom its dynamic partners
  long static_pairs = 0, static_contacts = 0, dynamic_pairs = 0, dynamic_contacts = 0;
  std::vector<long> partners(ngeom, 0);
  std::vector<Broadphase::Filter> filters;
  for (int g = 0; g < ngeom; ++g) filters.push_back(CollisionFilter(model, g));
  for (int i = 0; i < ngeom; ++i) {
    for (int j = i + 1; j < ngeom; ++j) {
      // link geoms count with the static ones (exactly): with static geometry and other links
      if (!CanCollide(filters[i], filters[j])) continue;
      const long points = MaxPairPoints(geoms[i].type, geoms[j].type);
      if (geoms[i].body < 0 || geoms[j].body < 0) {
        ++static_pairs;
        static_contacts += points;
      } else {
        ++dynamic_pairs;
        dynamic_contacts += points;
        ++partners[i];
        ++partners[j];
      }
    }
  }
  cap.collidable_pairs = static_pairs + dynamic_pairs;
  cap.exact_contacts = static_contacts + dynamic_contacts;
  cap.pairs = cap.collidable_pairs;
  cap.contacts = cap.exact_contacts;

  // the packing bound holds for solids that do not overlap: one colliding primitive per body
  std::vector<int> per_body(model.bodies.size(), 0);
  std::vector<double> volumes;
  double largest_radius = 0.0;
  unsigned types = 0;  // bit t: a dynamic geom of GeomType t collides
  bool solid = true;
  for (const GeomModel& g : geoms) {
    if (g.body < 0 || !Collides(g)) continue;
    const double v = Volume(g);
    solid = solid && v > 0.0 && std::isfinite(v) && ++per_body[g.body] == 1;
    volumes.push_back(v);
    largest_radius = std::max(largest_radius, g.rbound_m);
    types |= 1u << static_cast<int>(g.type);
  }
  // the most points of any pair of dynamic geoms
  int most_points = 0;
  for (int a = 0; a < 5; ++a) {
    for (int b = 0; b < 5; ++b) {
      if ((types >> a & 1u) != 0 && (types >> b & 1u) != 0) {
        most_points = std::max(most_points,
                               MaxPairPoints(static_cast<GeomType>(a), static_cast<GeomType>(b)));
      }
    }
  }
  if (!solid || volumes.empty() || !std::isfinite(largest_radius)) return cap;
  std::sort(volumes.begin(), volumes.end());
  std::vector<double> prefix(volumes.size() + 1, 0.0);
  for (std::size_t k = 0; k < volumes.size(); ++k) prefix[k + 1] = prefix[k] + volumes[k];
  // how many non-overlapping dynamic geoms fit in `room` [m^3], the smallest first
  auto fit = [&prefix](double room) {
    const auto end = std::upper_bound(prefix.begin(), prefix.end(), room);
    return std::max(0L, static_cast<long>(end - prefix.begin()) - 1);
  };
  // twice the numbers, so that each pair counted from both ends sums to an integer
  long twice_pairs = 0, twice_contacts = 0;
  for (int i = 0; i < ngeom; ++i) {
    const GeomModel& g = geoms[i];
    if (g.body < 0 || !Collides(g)) continue;
    const double v = Volume(g);
    // a geom whose bounding box overlaps i's lies in the cube of half-side r_i + 2 r_max about
    // i's centre (a bounding box is within a geom's bounding radius of its centre)
    const double half = g.rbound_m + 2.0 * largest_radius;
    const long overlapping = std::min(partners[i], fit(8.0 * half * half * half - v));
    // a geom that touches i lies within its diameter of i
    const long touching = std::min(partners[i], fit(GrownVolume(g, 2.0 * largest_radius) - v));
    twice_pairs += overlapping;
    twice_contacts += touching * most_points;
  }
  const long packed_pairs = (twice_pairs + 1) / 2, packed_contacts = (twice_contacts + 1) / 2;
  cap.packing = packed_pairs < dynamic_pairs || packed_contacts < dynamic_contacts;
  cap.pairs = static_pairs + std::min(dynamic_pairs, packed_pairs);
  cap.contacts = static_contacts + std::min(dynamic_contacts, packed_contacts);
  return cap;
}

int MaxContactsFor(const Model& model, int requested) {
  const SceneCapacity cap = BoundCapacity(model);
  const long needed = std::max(16L, cap.contacts);
  const std::string scene = "scene file '" + model.source + "'";
  if (cap.pairs > kMaxCapacity || needed > kMaxCapacity) {
    throw Error(
        scene + " can produce up to " + std::to_string(cap.pairs) + " geom pairs and " +
        std::to_string(needed) + " contacts in one step, more than the " +
        std::to_string(kMaxCapacity) +
        " rigidtouch preallocates; use fewer geoms or contype/conaffinity to exclude pairs");
  }
  if (requested > 0 && requested < needed) {
    throw Error(scene + " needs room for " + std::to_string(needed) +
                " contacts (its geoms can produce that many in one step), but max_contacts is " +
                std::to_string(requested) + "; raise max_contacts to at least " +
                std::to_string(needed) + " or leave it at 0 to size it from the scene");
  }
  return requested > 0 ? requested : static_cast<int>(needed);
}

}  // namespace rigidtouch::geometry
