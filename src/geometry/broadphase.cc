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

// CanCollide on the filters the broad phase keeps
bool CanCollide(const Broadphase::Filter& a, const Broadphase::Filter& b) {
  if (a.body == b.body) return false;  // same body, or both static
  return (a.contype & b.conaffinity) != 0 || (b.contype & a.conaffinity) != 0;
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
  filters.clear();
  for (int g = 0; g < ngeom; ++g) {
    const GeomModel& geom = model.geoms[g];
    (geom.type == GeomType::kPlane ? planes : order).push_back(g);
    filters.push_back(Filter{geom.body, geom.contype, geom.conaffinity});
  }
  for (auto* bound : {&lo_x, &hi_x, &lo_y, &hi_y, &lo_z, &hi_z}) bound->assign(order.size(), 0.0);
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
  const int n = static_cast<int>(bp.order.size());
  int* order = bp.order.data();
  double *lo_x = bp.lo_x.data(), *hi_x = bp.hi_x.data(), *lo_y = bp.lo_y.data(),
         *hi_y = bp.hi_y.data(), *lo_z = bp.lo_z.data(), *hi_z = bp.hi_z.data();
  // this tick's boxes at the geoms' places in last tick's order
  for (int i = 0; i < n; ++i) {
    const int g = order[i];
    const Aabb box = Bounds(model.geoms[g], poses[g]);
    bp.boxes[g] = box;
    lo_x[i] = box.lo.x();
    hi_x[i] = box.hi.x();
    lo_y[i] = box.lo.y();
    hi_y[i] = box.hi.y();
    lo_z[i] = box.lo.z();
    hi_z[i] = box.hi.z();
  }
  // insertion sort by lower x: linear when nothing crossed since the last tick; ties keep their
  // order, so the result depends only on the poses and the previous order (deterministic)
  for (int i = 1; i < n; ++i) {
    const double x = lo_x[i];
    if (!(lo_x[i - 1] > x)) continue;
    const int g = order[i];
    const double x1 = hi_x[i], y0 = lo_y[i], y1 = hi_y[i], z0 = lo_z[i], z1 = hi_z[i];
    int j = i;
    while (j > 0 && lo_x[j - 1] > x) {
      order[j] = order[j - 1];
      lo_x[j] = lo_x[j - 1];
      hi_x[j] = hi_x[j - 1];
      lo_y[j] = lo_y[j - 1];
      hi_y[j] = hi_y[j - 1];
      lo_z[j] = lo_z[j - 1];
      hi_z[j] = hi_z[j - 1];
      --j;
    }
    order[j] = g;
    lo_x[j] = x;
    hi_x[j] = x1;
    lo_y[j] = y0;
    hi_y[j] = y1;
    lo_z[j] = z0;
    hi_z[j] = z1;
  }
  // sweep along x; the other axes are tested first, as they reject most candidates that the
  // sweep lets through (a stack overlaps along x throughout)
  const Broadphase::Filter* filters = bp.filters.data();
  for (int i = 0; i < n; ++i) {
    const int a = order[i];
    for (int j = i + 1; j < n; ++j) {
      if (lo_x[j] > hi_x[i]) break;
      if (lo_z[i] <= hi_z[j] && lo_z[j] <= hi_z[i] && lo_y[i] <= hi_y[j] && lo_y[j] <= hi_y[i] &&
          lo_x[i] <= hi_x[j] && lo_x[j] <= hi_x[i] && CanCollide(filters[a], filters[order[j]])) {
        add(a, order[j]);
      }
    }
    for (int p : bp.planes) {
      if (CanCollide(filters[a], filters[p]) && BelowPlane(bp.boxes[a], poses[p])) add(a, p);
    }
  }
}

}  // namespace rigidtouch::geometry
