// The broad phase against a brute-force check of every geom pair: the same candidate pairs, in
// the sweep order that DetectContacts relies on for a deterministic contact order.
#include "geometry/broadphase.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <utility>
#include <vector>

namespace rigidtouch::geometry {
namespace {

// a random scene of `ngeom` geoms: spheres, boxes and capsules on a few bodies (some share one,
// some static), two planes, and collision filters that rule some pairs out
Model RandomModel(std::mt19937_64& rng, int ngeom) {
  std::uniform_real_distribution<double> size(0.005, 0.05);
  std::uniform_int_distribution<int> type(0, 3), body(-1, ngeom / 2), bits(0, 3);
  Model m;
  for (int g = 0; g < ngeom; ++g) {
    GeomModel geom;
    const int t = g < 2 ? -1 : type(rng);
    geom.type = t < 0    ? GeomType::kPlane
                : t == 0 ? GeomType::kSphere
                : t == 1 ? GeomType::kCapsule
                         : GeomType::kBox;
    geom.body = t < 0 ? -1 : body(rng);
    geom.size = Vec3(size(rng), size(rng), size(rng));
    geom.rbound_m = geom.size.norm();
    geom.contype = bits(rng);
    geom.conaffinity = bits(rng);
    if (g % 3 == 0) geom.contype = geom.conaffinity = 1;
    m.geoms.push_back(geom);
  }
  return m;
}

// random poses in a 0.3 m cube; the planes tilt a little about the floor at z = 0 and z = 0.1
void RandomPoses(std::mt19937_64& rng, const Model& m, std::vector<GeomPose>& poses) {
  std::uniform_real_distribution<double> x(-0.15, 0.15), tilt(-0.2, 0.2);
  for (std::size_t g = 0; g < m.geoms.size(); ++g) {
    if (m.geoms[g].type == GeomType::kPlane) {
      const Quat q(Eigen::AngleAxisd(tilt(rng), Vec3::UnitX()));
      poses[g] = GeomPose{Vec3(0.0, 0.0, 0.1 * static_cast<double>(g)), q.toRotationMatrix()};
    } else {
      poses[g] = GeomPose{Vec3(x(rng), x(rng), x(rng)), Quat::UnitRandom().toRotationMatrix()};
    }
  }
}

// every pair whose bounds overlap (or whose bound reaches below a plane), by brute force
std::vector<std::pair<int, int>> BruteForce(const Model& m, const std::vector<GeomPose>& poses) {
  auto half = [&m, &poses](int g) -> Vec3 {
    const GeomModel& geom = m.geoms[g];
    const Mat3& R = poses[g].R_WG;
    switch (geom.type) {
      case GeomType::kSphere:
        return Vec3::Constant(geom.size.x());
      case GeomType::kBox:
        return R.cwiseAbs() * geom.size;
      case GeomType::kCapsule:
        return R.col(2).cwiseAbs() * geom.size.y() + Vec3::Constant(geom.size.x());
      default:
        return Vec3::Constant(geom.rbound_m);
    }
  };
  std::vector<std::pair<int, int>> pairs;
  const int n = static_cast<int>(m.geoms.size());
  for (int a = 0; a < n; ++a) {
    for (int b = a + 1; b < n; ++b) {
      const bool pa = m.geoms[a].type == GeomType::kPlane;
      const bool pb = m.geoms[b].type == GeomType::kPlane;
      if ((pa && pb) || !CanCollide(m.geoms[a], m.geoms[b])) continue;
      if (pa || pb) {
        // the box's centre and half-size from its bounds, as the broad phase has them
        const int g = pa ? b : a, p = pa ? a : b;
        const Vec3 lo = poses[g].p_W - half(g), hi = poses[g].p_W + half(g);
        const Vec3 n_W = poses[p].R_WG.col(2);
        const Vec3 c = 0.5 * (lo + hi), h = 0.5 * (hi - lo);
        if (n_W.dot(c - poses[p].p_W) - n_W.cwiseAbs().dot(h) <= 0.0) pairs.emplace_back(g, p);
        continue;
      }
      const Vec3 lo_a = poses[a].p_W - half(a), hi_a = poses[a].p_W + half(a);
      const Vec3 lo_b = poses[b].p_W - half(b), hi_b = poses[b].p_W + half(b);
      if ((lo_a.array() <= hi_b.array()).all() && (lo_b.array() <= hi_a.array()).all()) {
        pairs.emplace_back(a, b);
      }
    }
  }
  return pairs;
}

std::vector<std::pair<int, int>> Sorted(std::vector<std::pair<int, int>> pairs) {
  for (auto& [a, b] : pairs) {
    if (a > b) std::swap(a, b);
  }
  std::sort(pairs.begin(), pairs.end());
  return pairs;
}

// over coherent motion (small steps, the sort order carried over) and random jumps (a new order
// each time), FindPairs gives the brute-force pair set, each pair once, in the sweep order: by
// the first geom's place in the order sorted by the lower bound along the sweep axis, its
// partners later in that order first, then the planes
TEST(BroadphaseTest, SamePairsAsBruteForceInSweepOrder) {
  std::mt19937_64 rng(7);
  int total = 0;
  for (int scene = 0; scene < 40; ++scene) {
    const Model m = RandomModel(rng, 10 + scene);
    std::vector<GeomPose> poses(m.geoms.size());
    RandomPoses(rng, m, poses);
    Broadphase bp;
    bp.Reserve(m, 4096);
    std::normal_distribution<double> step(0.0, 0.002);
    for (int tick = 0; tick < 30; ++tick) {
      if (tick % 10 == 9) {
        RandomPoses(rng, m, poses);
      } else {
        for (std::size_t g = 0; g < poses.size(); ++g) {
          if (m.geoms[g].type != GeomType::kPlane) poses[g].p_W += Vec3(step(rng), step(rng), 0.0);
        }
      }
      FindPairs(m, poses, bp);
      ASSERT_EQ(bp.dropped, 0);
      const std::vector<std::pair<int, int>> found(bp.pairs.begin(), bp.pairs.begin() + bp.npair);
      ASSERT_EQ(Sorted(found), Sorted(BruteForce(m, poses))) << "scene " << scene;
      total += bp.npair;
      // the order: non-plane geoms sorted by the lower bound along the sweep axis, and pairs by
      // their place in it
      std::vector<int> place(m.geoms.size(), -1);
      for (std::size_t i = 0; i < bp.order.size(); ++i) {
        place[bp.order[i]] = static_cast<int>(i);
        if (i > 0) {
          EXPECT_LE(bp.boxes[bp.order[i - 1]].lo[bp.axis], bp.boxes[bp.order[i]].lo[bp.axis]);
        }
      }
      const int nplace = static_cast<int>(bp.order.size());
      auto key = [&place, nplace](const std::pair<int, int>& p) {
        return std::make_pair(place[p.first],
                              place[p.second] >= 0 ? place[p.second] : nplace + p.second);
      };
      for (std::size_t k = 0; k < found.size(); ++k) {
        EXPECT_GE(place[found[k].first], 0);
        EXPECT_TRUE(place[found[k].second] < 0 || place[found[k].second] > place[found[k].first]);
        if (k > 0) {
          EXPECT_LT(key(found[k - 1]), key(found[k]));
        }
      }
    }
  }
  EXPECT_GT(total, 1000);  // the scenes are dense enough to test something
}

// a geom whose pose turned NaN (a diverged body) overlaps nothing, and must not keep the others
// unsorted: over coherent motion with one NaN geom in every other tick, the finite geoms' pairs
// are the brute-force set (which pairs nothing with the NaN geom)
TEST(BroadphaseTest, ANanGeomLeavesTheOthersPairsIntact) {
  std::mt19937_64 rng(5);
  int total = 0;
  for (int scene = 0; scene < 20; ++scene) {
    const Model m = RandomModel(rng, 30 + scene);
    std::vector<GeomPose> poses(m.geoms.size());
    RandomPoses(rng, m, poses);
    Broadphase bp;
    bp.Reserve(m, 4096);
    std::normal_distribution<double> step(0.0, 0.01);
    for (int tick = 0; tick < 20; ++tick) {
      for (std::size_t g = 0; g < poses.size(); ++g) {
        if (m.geoms[g].type != GeomType::kPlane) poses[g].p_W += Vec3(step(rng), step(rng), 0.0);
      }
      std::vector<GeomPose> used = poses;
      if (tick % 2 == 1) used[2 + scene % 5].p_W = Vec3::Constant(std::nan(""));
      FindPairs(m, used, bp);
      const std::vector<std::pair<int, int>> found(bp.pairs.begin(), bp.pairs.begin() + bp.npair);
      ASSERT_EQ(Sorted(found), Sorted(BruteForce(m, used)))
          << "scene " << scene << " tick " << tick;
      total += bp.npair;
    }
  }
  EXPECT_GT(total, 500);
}

// the sweep follows the axis over which the geoms spread most, and leaves the current one only
// for an axis at least kAxisSwitchRatio (2) times as wide: a column along z, a row along y, then x
// wider than y by 3/2 (kept) and by 3 (taken). Same pairs as brute force throughout.
TEST(BroadphaseTest, SweepsAlongTheAxisOfWidestSpread) {
  std::mt19937_64 rng(9);
  const Model m = RandomModel(rng, 30);
  std::vector<GeomPose> poses(m.geoms.size());
  RandomPoses(rng, m, poses);
  Broadphase bp;
  bp.Reserve(m, 4096);
  ASSERT_EQ(bp.axis, 0);
  struct Case {
    Vec3 extent_m;  // the geoms' centres spread uniformly over +-extent / 2 along each axis
    int axis;       // the sweep axis expected after it
  };
  // the geoms' own sizes (up to about 0.09 m) blur each spread a little: the ratios leave room
  const Case cases[] = {{Vec3(0.02, 0.02, 2.0), 2},
                        {Vec3(0.02, 2.0, 0.02), 1},
                        {Vec3(3.0, 2.0, 0.02), 1},
                        {Vec3(6.0, 2.0, 0.02), 0}};
  int total = 0;
  for (const Case& k : cases) {
    std::uniform_real_distribution<double> u(-0.5, 0.5);
    for (std::size_t g = 0; g < m.geoms.size(); ++g) {
      if (m.geoms[g].type == GeomType::kPlane) continue;
      poses[g].p_W = Vec3(u(rng), u(rng), u(rng)).cwiseProduct(k.extent_m);
    }
    FindPairs(m, poses, bp);
    EXPECT_EQ(bp.axis, k.axis) << k.extent_m.transpose();
    const std::vector<std::pair<int, int>> found(bp.pairs.begin(), bp.pairs.begin() + bp.npair);
    EXPECT_EQ(Sorted(found), Sorted(BruteForce(m, poses))) << k.extent_m.transpose();
    for (std::size_t i = 1; i < bp.order.size(); ++i) {
      EXPECT_LE(bp.boxes[bp.order[i - 1]].lo[bp.axis], bp.boxes[bp.order[i]].lo[bp.axis]);
    }
    total += bp.npair;
  }
  EXPECT_GT(total, 10);  // dense enough to test something
}

// a full pair list keeps the first candidates and counts the rest
TEST(BroadphaseTest, CapacityDropsAndCounts) {
  std::mt19937_64 rng(8);
  const Model m = RandomModel(rng, 40);
  std::vector<GeomPose> poses(m.geoms.size());
  RandomPoses(rng, m, poses);
  Broadphase all, few;
  all.Reserve(m, 4096);
  few.Reserve(m, 5);
  FindPairs(m, poses, all);
  FindPairs(m, poses, few);
  ASSERT_GT(all.npair, 5);
  EXPECT_EQ(few.npair, 5);
  EXPECT_EQ(few.dropped, all.npair - 5);
  for (int k = 0; k < 5; ++k) EXPECT_EQ(few.pairs[k], all.pairs[k]);
}

}  // namespace
}  // namespace rigidtouch::geometry
