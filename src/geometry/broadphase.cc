#include "geometry/broadphase.h"

namespace rigidtouch::geometry {
namespace {

Aabb Bounds(const GeomModel& g, const GeomPose& pose) {
  Vec3 half;
  switch (g.type) {
    case GeomType::kSphere:
      half.setConstant(g.size.x());
      break;
    case GeomType::kBox:
      half = pose.R_WG.cwiseAbs() * g.size;
      break;
    case GeomType::kCapsule:
      half = pose.R_WG.col(2).cwiseAbs() * g.size.y() + Vec3::Constant(g.size.x());
      break;
    default:  // mesh: MuJoCo's bounding sphere
      half.setConstant(g.rbound_m);
      break;
  }
  return Aabb{pose.p_W - half, pose.p_W + half};
}

bool Overlap(const Aabb& a, const Aabb& b) {
  return a.lo.x() <= b.hi.x() && b.lo.x() <= a.hi.x() && a.lo.y() <= b.hi.y() &&
         b.lo.y() <= a.hi.y() && a.lo.z() <= b.hi.z() && b.lo.z() <= a.hi.z();
}

// signed distance of the box below the plane's surface, > 0 if some part is below
bool BelowPlane(const Aabb& box, const GeomPose& plane) {
  const Vec3 n = plane.R_WG.col(2);
  const Vec3 c = 0.5 * (box.lo + box.hi);
  const Vec3 h = 0.5 * (box.hi - box.lo);
  return n.dot(c - plane.p_W) - n.cwiseAbs().dot(h) <= 0.0;
}

}  // namespace

void Broadphase::Reserve(const Model& model, int pair_capacity) {
  const int ngeom = static_cast<int>(model.geoms.size());
  boxes.assign(ngeom, Aabb{});
  order.clear();
  planes.clear();
  for (int g = 0; g < ngeom; ++g) {
    (model.geoms[g].type == GeomType::kPlane ? planes : order).push_back(g);
  }
  pairs.assign(pair_capacity, {-1, -1});
  npair = 0;
  dropped = 0;
}

void GeomPoses(const Model& model, std::span<const BodyState> bodies, std::span<GeomPose> poses) {
  for (std::size_t g = 0; g < model.geoms.size(); ++g) {
    const GeomModel& geom = model.geoms[g];
    if (geom.body < 0) {
      poses[g] = GeomPose{geom.pos_B, geom.quat_B.toRotationMatrix()};
    } else {
      const BodyState& s = bodies[geom.body];
      poses[g] = GeomPose{s.x_W + s.q_WB * geom.pos_B, (s.q_WB * geom.quat_B).toRotationMatrix()};
    }
  }
}

bool CanCollide(const GeomModel& a, const GeomModel& b) {
  if (a.body == b.body) return false;  // same body, or both static
  return (a.contype & b.conaffinity) != 0 || (b.contype & a.conaffinity) != 0;
}

void FindPairs(const Model& model, std::span<const GeomPose> poses, Broadphase& bp) {
  const int capacity = static_cast<int>(bp.pairs.size());
  bp.npair = 0;
  bp.dropped = 0;
  auto add = [&bp, capacity](int a, int b) {
    if (bp.npair < capacity) {
      bp.pairs[bp.npair++] = {a, b};
    } else {
      ++bp.dropped;
    }
  };
  for (int g : bp.order) bp.boxes[g] = Bounds(model.geoms[g], poses[g]);
  // insertion sort by lower x: linear when nothing crossed since the last tick; ties keep their
  // order, so the result depends only on the poses and the previous order (deterministic)
  for (std::size_t i = 1; i < bp.order.size(); ++i) {
    const int g = bp.order[i];
    const double x = bp.boxes[g].lo.x();
    std::size_t j = i;
    while (j > 0 && bp.boxes[bp.order[j - 1]].lo.x() > x) {
      bp.order[j] = bp.order[j - 1];
      --j;
    }
    bp.order[j] = g;
  }
  for (std::size_t i = 0; i < bp.order.size(); ++i) {
    const int a = bp.order[i];
    const Aabb& box_a = bp.boxes[a];
    for (std::size_t j = i + 1; j < bp.order.size(); ++j) {
      const int b = bp.order[j];
      if (bp.boxes[b].lo.x() > box_a.hi.x()) break;
      if (Overlap(box_a, bp.boxes[b]) && CanCollide(model.geoms[a], model.geoms[b])) add(a, b);
    }
    for (int p : bp.planes) {
      if (CanCollide(model.geoms[a], model.geoms[p]) && BelowPlane(box_a, poses[p])) add(a, p);
    }
  }
}

}  // namespace rigidtouch::geometry
