// The broad phase against a brute-force check of every geom pair: the same candidate pairs, in
// the sweep order that DetectContacts relies on for a deterministic contact order.
#include "geometry/broadphase.h"
#include "draw.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
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
    geom.size = test::Draw3(size, rng);
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
      poses[g] = GeomPose{test::Draw3(x, rng), Quat::UnitRandom().toRotationMatrix()};
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
          if (m.geoms[g].type != GeomType::kPlane) poses[g].p_W += test::Draw2(step, rng, 0.0);
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
        if (m.geoms[g].type != GeomType::kPlane) poses[g].p_W += test::Draw2(step, rng, 0.0);
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
      poses[g].p_W = test::Draw3(u, rng).cwiseProduct(k.extent_m);
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

// the sweep as it was before the float blocks (one place at a time, double bounds only), kept
// here as the reference for the order of the pairs: the same bounds, the same insertion sort
// carried over the ticks, the same axis rule, the same pair order
class ReferenceSweep {
 public:
  explicit ReferenceSweep(const Model& m) {
    for (int g = 0; g < static_cast<int>(m.geoms.size()); ++g) {
      (m.geoms[g].type == GeomType::kPlane ? planes_ : order_).push_back(g);
    }
  }

  std::vector<std::pair<int, int>> Find(const Model& m, const std::vector<GeomPose>& poses) {
    const int n = static_cast<int>(order_.size());
    std::vector<Aabb> boxes(m.geoms.size());
    Vec3 least = Vec3::Constant(kInf), most = -least;
    for (int g : order_) {
      const GeomModel& geom = m.geoms[g];
      Vec3 half;
      switch (geom.type) {
        case GeomType::kSphere:
          half.setConstant(geom.size.x());
          break;
        case GeomType::kBox:
          half = poses[g].R_WG.cwiseAbs() * geom.size;
          break;
        case GeomType::kCapsule:
          half = poses[g].R_WG.col(2).cwiseAbs() * geom.size.y() + Vec3::Constant(geom.size.x());
          break;
        default:
          half.setConstant(geom.rbound_m);
          break;
      }
      boxes[g] = Aabb{poses[g].p_W - half, poses[g].p_W + half};
      least = least.cwiseMin(boxes[g].lo);
      most = most.cwiseMax(boxes[g].lo);
    }
    const Vec3 spread = most - least;
    int widest = 0;
    for (int a = 1; a < 3; ++a) {
      if (spread[a] > spread[widest]) widest = a;
    }
    auto key = [&boxes, this](int g) {
      const double l = boxes[g].lo[axis_];
      return std::isnan(l) ? kInf : l;
    };
    if (widest != axis_ && spread[widest] > 2.0 * spread[axis_]) {
      axis_ = widest;
      std::sort(order_.begin(), order_.end(), [&key](int g1, int g2) {
        return key(g1) < key(g2) || (key(g1) == key(g2) && g1 < g2);
      });
    }
    for (int i = 1; i < n; ++i) {  // stable insertion sort from last tick's order
      const int g = order_[i];
      int j = i;
      for (; j > 0 && key(order_[j - 1]) > key(g); --j) order_[j] = order_[j - 1];
      order_[j] = g;
    }
    std::vector<std::pair<int, int>> pairs;
    auto add = [&m, &pairs](int a, int b) {
      if (!std::binary_search(m.excluded_geom_pairs.begin(), m.excluded_geom_pairs.end(),
                              std::pair<int, int>(std::min(a, b), std::max(a, b)))) {
        pairs.emplace_back(a, b);
      }
    };
    const int as = axis_, ap = (as + 1) % 3, aq = (as + 2) % 3;
    for (int i = 0; i < n; ++i) {
      const int a = order_[i];
      const Aabb& A = boxes[a];
      for (int j = i + 1; j < n; ++j) {
        const Aabb& B = boxes[order_[j]];
        if (key(order_[j]) > A.hi[as]) break;
        if (A.lo[aq] <= B.hi[aq] && B.lo[aq] <= A.hi[aq] && A.lo[ap] <= B.hi[ap] &&
            B.lo[ap] <= A.hi[ap] && key(a) <= B.hi[as] && key(order_[j]) <= A.hi[as] &&
            CanCollide(m.geoms[a], m.geoms[order_[j]])) {
          add(a, order_[j]);
        }
      }
      for (int p : planes_) {
        const Vec3 n_W = poses[p].R_WG.col(2);
        const Vec3 c = 0.5 * (A.lo + A.hi), h = 0.5 * (A.hi - A.lo);
        if (CanCollide(m.geoms[a], m.geoms[p]) &&
            n_W.dot(c - poses[p].p_W) - n_W.cwiseAbs().dot(h) <= 0.0) {
          add(a, p);
        }
      }
    }
    return pairs;
  }

 private:
  static constexpr double kInf = std::numeric_limits<double>::infinity();
  std::vector<int> order_, planes_;
  int axis_ = 0;
};

// a settled-looking pile: nx x ny x nz boxes of half-size 25 mm, 51 mm apart, each on its own
// body and turned by up to 0.02 rad, a floor, a 5 mm tool sphere above it, and two excluded body
// pairs
Model PileModel(int nx, int ny, int nz, std::vector<GeomPose>& poses, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> tilt(-0.02, 0.02);
  Model m;
  GeomModel floor;
  floor.type = GeomType::kPlane;
  floor.contype = floor.conaffinity = 1;
  m.geoms.push_back(floor);
  poses.assign(1, GeomPose{Vec3::Zero(), Mat3::Identity()});
  for (int z = 0; z < nz; ++z) {
    for (int y = 0; y < ny; ++y) {
      for (int x = 0; x < nx; ++x) {
        GeomModel box;
        box.type = GeomType::kBox;
        box.body = static_cast<int>(m.geoms.size());
        box.size = Vec3::Constant(0.025);
        box.rbound_m = box.size.norm();
        box.contype = box.conaffinity = 1;
        m.geoms.push_back(box);
        const Vec3 axis = test::Draw3(tilt, rng);
        poses.push_back(
            GeomPose{Vec3(0.051 * x, 0.051 * y, 0.025 + 0.0501 * z),
                     Quat(Eigen::AngleAxisd(axis.norm(), axis.normalized())).toRotationMatrix()});
      }
    }
  }
  GeomModel tool;
  tool.type = GeomType::kSphere;
  tool.body = static_cast<int>(m.geoms.size());
  tool.size = Vec3::Constant(0.005);
  tool.rbound_m = 0.005;
  tool.contype = tool.conaffinity = 1;
  m.geoms.push_back(tool);
  poses.push_back(GeomPose{Vec3(0.051, 0.051, 0.0501 * nz + 0.004), Mat3::Identity()});
  m.excluded_geom_pairs = {{1, 2}, {1, 1 + nx}};
  return m;
}

// A pile of 360 boxes over 80 ticks: jitter that reorders the sweep, a column pushed sideways, a
// stretch along z that moves the sweep to that axis, a geom whose pose turns NaN, a huge geom
// (bounds of +-inf), and one at infinity (a NaN lower bound below an infinite upper one). Every
// tick FindPairs gives exactly the pair list of the plain double sweep (ReferenceSweep, same
// order) with the eight-wide and the four-wide float blocks, and the brute-force pair set
// whenever no bound is NaN beside an infinite one (there the plain sweep's +inf for a NaN lower
// bound pairs the geom at infinity with the huge one, which brute force does not).
TEST(BroadphaseTest, FloatBlocksGiveThePlainSweepsPairsInItsOrder) {
  std::mt19937_64 rng(19);
  std::vector<GeomPose> poses;
  Model m = PileModel(6, 6, 10, poses, rng);
  const int nbox = 360, huge = nbox + 2;
  // two more geoms on bodies of their own, parked beside the pile until their ticks
  for (int k = 0; k < 2; ++k) {
    GeomModel box = m.geoms[1];
    box.body = static_cast<int>(m.geoms.size());
    m.geoms.push_back(box);
    // turned so that each bound sums three nonzero terms (a size of 1.7e308 then overflows)
    poses.push_back(GeomPose{
        Vec3(-0.2 - 0.06 * k, 0.0, 0.3),
        Quat(Eigen::AngleAxisd(0.7, Vec3(1.0, 2.0, 3.0).normalized())).toRotationMatrix()});
  }
  // two small spheres that touch exactly: the upper x bound of one is the lower of the other
  // (-0.1171875, binary fractions throughout), which only a test by <= pairs
  const int touching = static_cast<int>(m.geoms.size());
  for (int k = 0; k < 2; ++k) {
    GeomModel ball = m.geoms[touching - 3];  // the tool
    ball.body = static_cast<int>(m.geoms.size());
    ball.size = Vec3::Constant(0.0078125);
    m.geoms.push_back(ball);
    poses.push_back(GeomPose{Vec3(-0.125 + 0.015625 * k, 0.0, 0.25), Mat3::Identity()});
  }
  Broadphase wide, narrow, shared;
  wide.Reserve(m, 1 << 16);
  narrow.Reserve(m, 1 << 16);
  narrow.wide = false;
  shared.Reserve(m, 1 << 16);
  parallel::Worker worker;  // `shared` sweeps half of the places on it
  ReferenceSweep reference(m);
  std::normal_distribution<double> jitter(0.0, 1e-4);
  int total = 0, compared = 0, axis_switches = 0;
  for (int tick = 0; tick < 80; ++tick) {
    std::vector<GeomPose> used = poses;
    for (int g = 1; g <= nbox; ++g) used[g].p_W += test::Draw3(jitter, rng);
    if (tick >= 20) {  // a column slides by up to 3 mm into its neighbour
      for (int g = 1; g <= nbox; g += 36) used[g].p_W.x() += 1e-4 * (tick - 20);
    }
    if (tick >= 50) {  // stretched along z, three times as tall: the sweep turns to z
      for (int g = 1; g <= nbox; ++g) used[g].p_W.z() *= 3.0 + 0.01 * (tick - 50);
    }
    bool brute_force_agrees = true;
    if (tick % 7 == 3) used[1 + tick % nbox].p_W = Vec3::Constant(std::nan(""));
    if (tick % 5 == 1) {
      m.geoms[huge].size = Vec3::Constant(1.7e308);  // |R| size sums overflow: bounds +-inf
      used[huge].p_W = Vec3(0.1, 0.1, 0.1);
    } else {
      m.geoms[huge].size = Vec3::Constant(0.025);
    }
    if (tick % 10 == 6) {  // a huge box at infinity: NaN lower and +inf upper bound on the axis
      m.geoms[huge].size = Vec3::Constant(1.7e308);
      used[huge].p_W = Vec3(0.1, 0.1, 0.1);
      used[huge].p_W[wide.axis] = std::numeric_limits<double>::infinity();
      used[huge + 1].p_W = Vec3(0.1, 0.1, 0.1);
      m.geoms[huge + 1].size = Vec3::Constant(1.7e308);
      brute_force_agrees = false;
    } else {
      used[huge + 1].p_W = poses[huge + 1].p_W;
      m.geoms[huge + 1].size = Vec3::Constant(0.025);
    }
    const int axis_before = wide.axis;
    FindPairs(m, used, wide);
    FindPairs(m, used, narrow);
    FindPairs(m, used, shared, &worker);
    axis_switches += wide.axis != axis_before ? 1 : 0;
    const std::vector<std::pair<int, int>> expected = reference.Find(m, used);
    const std::vector<std::pair<int, int>> found(wide.pairs.begin(),
                                                 wide.pairs.begin() + wide.npair);
    const std::vector<std::pair<int, int>> found4(narrow.pairs.begin(),
                                                  narrow.pairs.begin() + narrow.npair);
    ASSERT_EQ(wide.dropped, 0);
    ASSERT_EQ(found, expected) << "tick " << tick;
    ASSERT_EQ(found4, expected) << "tick " << tick;
    const std::vector<std::pair<int, int>> found_shared(shared.pairs.begin(),
                                                        shared.pairs.begin() + shared.npair);
    ASSERT_EQ(found_shared, expected) << "tick " << tick;
    ASSERT_EQ(shared.dropped, 0);
    EXPECT_NE(std::find(expected.begin(), expected.end(), std::pair(touching, touching + 1)),
              expected.end())
        << "tick " << tick;
    if (!brute_force_agrees) {  // the case is exercised: the plain sweep pairs the two
      const std::pair<int, int> both[] = {{huge, huge + 1}, {huge + 1, huge}};
      EXPECT_TRUE(std::find_first_of(expected.begin(), expected.end(), both, both + 2) !=
                  expected.end())
          << "tick " << tick;
    } else {
      std::vector<std::pair<int, int>> brute = BruteForce(m, used);
      std::erase_if(brute, [&m](const std::pair<int, int>& p) {
        const int a = std::min(p.first, p.second), b = std::max(p.first, p.second);
        return std::binary_search(m.excluded_geom_pairs.begin(), m.excluded_geom_pairs.end(),
                                  std::pair<int, int>(a, b));
      });
      ASSERT_EQ(Sorted(found), Sorted(brute)) << "tick " << tick;
      ++compared;
    }
    total += wide.npair;
  }
  EXPECT_EQ(axis_switches, 1);  // x to z, once
  EXPECT_EQ(compared, 72);
  EXPECT_GT(total, 80 * 900);  // a box touches about five others in the pile
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

// the sweep shared by two threads (each half of the places into its own list, appended) keeps
// and drops what one sweep does, wherever the capacity ends: in the first half's pairs, at its
// end, or in the second half's
TEST(BroadphaseTest, TwoThreadsKeepAndDropAsOne) {
  std::mt19937_64 rng(23);
  std::vector<GeomPose> poses;
  const Model m = PileModel(8, 8, 10, poses, rng);
  Broadphase all;
  all.Reserve(m, 1 << 16);
  FindPairs(m, poses, all);
  ASSERT_GT(all.npair, 1000);
  parallel::Worker worker;
  for (const int capacity : {5, all.npair / 3, all.npair / 2, 2 * all.npair / 3, all.npair - 1,
                             all.npair, all.npair + 7}) {
    Broadphase some;
    some.Reserve(m, capacity);
    // the worker's share depends on when it wakes: several sweeps, each checked
    for (int round = 0; round < 20; ++round) {
      FindPairs(m, poses, some, &worker);
      const int kept = std::min(capacity, all.npair);
      ASSERT_EQ(some.npair, kept) << capacity;
      EXPECT_EQ(some.dropped, all.npair - kept) << capacity;
      for (int k = 0; k < kept; ++k) {
        ASSERT_EQ(some.pairs[k], all.pairs[k]) << capacity << " " << k;
      }
    }
  }
}

// the worker's blocks are the last ones: when they overflow its list while the tick's thread's
// list has room, they are swept again in order. A long row of boxes apart (no pairs) and then 64
// boxes in one place (2016 pairs, all in the last two blocks): the worker's first block alone
// overflows a capacity of 300, and the tick's thread has none. Sweeps until that has happened.
TEST(BroadphaseTest, TheWorkersOverflowingBlocksAreSweptAgainInOrder) {
  Model m;
  std::vector<GeomPose> poses;
  for (int i = 0; i < 3000 + 64; ++i) {
    GeomModel box;
    box.type = GeomType::kBox;
    box.body = i;
    box.size = Vec3::Constant(0.025);
    box.rbound_m = box.size.norm();
    box.contype = box.conaffinity = 1;
    m.geoms.push_back(box);
    const double x = i < 3000 ? 0.1 * i : 301.0;
    poses.push_back(GeomPose{Vec3(x, 0.0, 1.0), Mat3::Identity()});
  }
  Broadphase all;
  all.Reserve(m, 1 << 16);
  FindPairs(m, poses, all);
  ASSERT_EQ(all.npair, 64 * 63 / 2);
  parallel::Worker worker;
  Broadphase some;
  some.Reserve(m, 300);
  for (int round = 0; round < 5000 && some.resweeps == 0; ++round) {
    FindPairs(m, poses, some, &worker);
    ASSERT_EQ(some.npair, 300);
    ASSERT_EQ(some.dropped, all.npair - 300);
    for (int k = 0; k < 300; ++k) ASSERT_EQ(some.pairs[k], all.pairs[k]) << round << " " << k;
  }
  EXPECT_GT(some.resweeps, 0);
}

}  // namespace
}  // namespace rigidtouch::geometry
