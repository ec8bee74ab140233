#include "geometry/broadphase.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>

#if defined(__SSE2__)
#include <immintrin.h>
#endif

namespace rigidtouch::geometry {
namespace {

// the sweep moves to another axis only when the boxes spread over it more than this many times as
// far as over the current one, so that a scene about as wide as it is deep keeps its order
constexpr double kAxisSwitchRatio = 2.0;

// places per block of the sweep the two threads share
constexpr int kPlaceBlock = 32;

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

// signed distance of the box below the plane's surface, > 0 if some part is below
bool BelowPlane(const Aabb& box, const GeomPose& plane) {
  const Vec3 n = plane.R_WG.col(2);
  const Vec3 c = 0.5 * (box.lo + box.hi);
  const Vec3 h = 0.5 * (box.hi - box.lo);
  return n.dot(c - plane.p_W) - n.cwiseAbs().dot(h) <= 0.0;
}

// x as a float: the nearest, or the largest float of x's sign beyond float's range (where the
// conversion would be undefined); NaN stays NaN. The map never decreases as x grows, so a <= b
// gives FloatOf(a) <= FloatOf(b) (exactly what the float test needs to pass every pair the
// double test passes), and FloatOf(a) > FloatOf(b) gives a > b (what stopping the scan needs).
float FloatOf(double x) {
  constexpr double kMax = std::numeric_limits<float>::max();
  return static_cast<float>(std::clamp(x, -kMax, kMax));
}

// places a float block of the sweep tests at once: 4 with SSE2, 8 with AVX2 (chosen at run time:
// the pairs are the same, as the blocks only filter candidates for the double test)
constexpr int kMaxLanes = 8;

// the sweep's float bounds, in sweep order
struct FloatBounds {
  const float *lo_s, *hi_s, *lo_p, *hi_p, *lo_q, *hi_q;
};

// writes to `hits` the places j > i, in order, whose float boxes overlap place i's, from i + 1 to
// the end of the first block in which a float lower bound along the sweep axis exceeds i's upper
// bound (the double sweep stops before it); returns how many. Every place past n is NaN, so a
// block reaching past n is safe to read and its extra lanes never pass.
int ScanPortable(const FloatBounds& f, int i, int n, int* hits) {
  int count = 0;
#if defined(__SSE2__)
  constexpr int kLanes = 4;
  const __m128 ls_i = _mm_set1_ps(f.lo_s[i]), hs_i = _mm_set1_ps(f.hi_s[i]);
  const __m128 lp_i = _mm_set1_ps(f.lo_p[i]), hp_i = _mm_set1_ps(f.hi_p[i]);
  const __m128 lq_i = _mm_set1_ps(f.lo_q[i]), hq_i = _mm_set1_ps(f.hi_q[i]);
  for (int j = i + 1; j < n; j += kLanes) {
    __m128 m = _mm_cmple_ps(_mm_loadu_ps(f.lo_s + j), hs_i);
    m = _mm_and_ps(m, _mm_cmple_ps(_mm_loadu_ps(f.lo_q + j), hq_i));
    m = _mm_and_ps(m, _mm_cmple_ps(lq_i, _mm_loadu_ps(f.hi_q + j)));
    m = _mm_and_ps(m, _mm_cmple_ps(_mm_loadu_ps(f.lo_p + j), hp_i));
    m = _mm_and_ps(m, _mm_cmple_ps(lp_i, _mm_loadu_ps(f.hi_p + j)));
    m = _mm_and_ps(m, _mm_cmple_ps(ls_i, _mm_loadu_ps(f.hi_s + j)));
    for (unsigned bits = static_cast<unsigned>(_mm_movemask_ps(m)); bits != 0; bits &= bits - 1) {
      hits[count++] = j + std::countr_zero(bits);
    }
    if (f.lo_s[j + kLanes - 1] > f.hi_s[i]) break;
  }
#else
  constexpr int kLanes = 4;
  for (int j = i + 1; j < n; j += kLanes) {
    for (int k = j; k < j + kLanes; ++k) {
      if (f.lo_s[k] <= f.hi_s[i] && f.lo_q[k] <= f.hi_q[i] && f.lo_q[i] <= f.hi_q[k] &&
          f.lo_p[k] <= f.hi_p[i] && f.lo_p[i] <= f.hi_p[k] && f.lo_s[i] <= f.hi_s[k]) {
        hits[count++] = k;
      }
    }
    if (f.lo_s[j + kLanes - 1] > f.hi_s[i]) break;
  }
#endif
  return count;
}

#if defined(__SSE2__) && defined(__x86_64__) && defined(__GNUC__)
#define RIGIDTOUCH_SWEEP_AVX2 1
// ScanPortable eight places at a time
__attribute__((target("avx2"))) int ScanAvx2(const FloatBounds& f, int i, int n, int* hits) {
  constexpr int kLanes = 8;
  int count = 0;
  const __m256 ls_i = _mm256_set1_ps(f.lo_s[i]), hs_i = _mm256_set1_ps(f.hi_s[i]);
  const __m256 lp_i = _mm256_set1_ps(f.lo_p[i]), hp_i = _mm256_set1_ps(f.hi_p[i]);
  const __m256 lq_i = _mm256_set1_ps(f.lo_q[i]), hq_i = _mm256_set1_ps(f.hi_q[i]);
  for (int j = i + 1; j < n; j += kLanes) {
    // ordered comparisons: false for a NaN, as <= is
    __m256 m = _mm256_cmp_ps(_mm256_loadu_ps(f.lo_s + j), hs_i, _CMP_LE_OQ);
    m = _mm256_and_ps(m, _mm256_cmp_ps(_mm256_loadu_ps(f.lo_q + j), hq_i, _CMP_LE_OQ));
    m = _mm256_and_ps(m, _mm256_cmp_ps(lq_i, _mm256_loadu_ps(f.hi_q + j), _CMP_LE_OQ));
    m = _mm256_and_ps(m, _mm256_cmp_ps(_mm256_loadu_ps(f.lo_p + j), hp_i, _CMP_LE_OQ));
    m = _mm256_and_ps(m, _mm256_cmp_ps(lp_i, _mm256_loadu_ps(f.hi_p + j), _CMP_LE_OQ));
    m = _mm256_and_ps(m, _mm256_cmp_ps(ls_i, _mm256_loadu_ps(f.hi_s + j), _CMP_LE_OQ));
    for (unsigned bits = static_cast<unsigned>(_mm256_movemask_ps(m)); bits != 0;
         bits &= bits - 1) {
      hits[count++] = j + std::countr_zero(bits);
    }
    if (f.lo_s[j + kLanes - 1] > f.hi_s[i]) break;
  }
  return count;
}
#endif

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
    filters.push_back(CollisionFilter(model, g));
  }
  axis = 0;
  for (auto* bound : {&lo_s, &hi_s, &lo_p, &hi_p, &lo_q, &hi_q}) bound->assign(order.size(), 0.0);
  for (auto* bound : {&flo_s, &fhi_s, &flo_p, &fhi_p, &flo_q, &fhi_q}) {
    bound->assign(order.size() + kMaxLanes - 1, std::numeric_limits<float>::quiet_NaN());
  }
  hits.assign(order.size(), 0);
  upper_hits.assign(order.size(), 0);
  block_begin.assign(order.size() / kPlaceBlock + 1, 0);
  block_count.assign(order.size() / kPlaceBlock + 1, 0);
#if defined(RIGIDTOUCH_SWEEP_AVX2)
  wide = __builtin_cpu_supports("avx2") != 0;
#else
  wide = false;
#endif
  pairs.assign(pair_capacity, {-1, -1});
  upper_pairs.assign(pair_capacity, {-1, -1});
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
  // same body, same link, or both static
  if (a.body == b.body && a.tree == b.tree && a.link == b.link) return false;
  return (a.contype & b.conaffinity) != 0 || (b.contype & a.conaffinity) != 0;
}

int LinkOwner(const Model& model, int tree, int link) {
  int owner = static_cast<int>(model.bodies.size());
  for (int t = 0; t < tree; ++t) owner += static_cast<int>(model.trees[t].link_names.size());
  return owner + link;
}

Broadphase::Filter CollisionFilter(const Model& model, int g) {
  const GeomModel& geom = model.geoms[g];
  Broadphase::Filter f{geom.body, -2, geom.contype, geom.conaffinity};
  if (geom.body >= 0 || geom.tree < 0) return f;
  f.owner = LinkOwner(model, geom.tree, geom.link);
  // MuJoCo's weldparent test applies between two links (neither welded to the world): a tree's
  // root link still collides with the static geometry it hangs from
  const int parent = model.trees[geom.tree].link_parent[geom.link];
  if (model.filter_parent && parent >= 0) f.parent = LinkOwner(model, geom.tree, parent);
  return f;
}

bool CanCollide(const Broadphase::Filter& a, const Broadphase::Filter& b) {
  if (a.owner == b.owner) return false;  // same body or link, or both static
  if (a.parent == b.owner || b.parent == a.owner) return false;  // a link and its parent
  return (a.contype & b.conaffinity) != 0 || (b.contype & a.conaffinity) != 0;
}

bool CanCollide(const Model& model, int a, int b) {
  return CanCollide(CollisionFilter(model, a), CollisionFilter(model, b));
}

namespace {

// candidate pairs as one part of the sweep writes them
struct PairSink {
  std::pair<int, int>* pairs;
  int capacity;
  int count = 0;
  int dropped = 0;
};

// appends candidate pair (a, b) unless the scene excludes it (`excluded`: MJCF
// <contact><exclude> as geom pairs, sorted; empty in most scenes); beyond the sink's capacity it
// counts the pair as dropped
void AddPair(const std::vector<std::pair<int, int>>& excluded, PairSink& out, int a, int b) {
  if (!excluded.empty() &&
      std::binary_search(excluded.begin(), excluded.end(),
                         std::pair<int, int>(std::min(a, b), std::max(a, b)))) {
    return;
  }
  if (out.count < out.capacity) {
    out.pairs[out.count++] = {a, b};
  } else {
    ++out.dropped;
  }
}

// the float copies of the bounds, in sweep order (Sweep)
void FloatBoundsOf(Broadphase& bp) {
  const int n = static_cast<int>(bp.order.size());
  for (int i = 0; i < n; ++i) {
    bp.flo_s[i] = FloatOf(bp.lo_s[i]);
    bp.fhi_s[i] = FloatOf(bp.hi_s[i]);
    bp.flo_p[i] = FloatOf(bp.lo_p[i]);
    bp.fhi_p[i] = FloatOf(bp.hi_p[i]);
    bp.flo_q[i] = FloatOf(bp.lo_q[i]);
    bp.fhi_q[i] = FloatOf(bp.hi_q[i]);
  }
}

// the pairs of the boxes in sweep order (bp.order and the bounds at their places): those of the
// plain sweep (for each place i, the places j > i in order whose double boxes overlap i's, then
// the planes), which float copies of the bounds find faster: a block of places is tested at once
// against i's float box. Every bound goes through the same non-decreasing FloatOf, so the float
// test passes every pair the double test passes; the double test then decides each pair the
// float test let through, in order. The scan stops after the block where a float lower bound
// exceeds i's float upper bound: the double bounds compare the same way, so the double sweep has
// stopped by then, and the places past its stop within the block fail the double test (their
// lower bounds are larger still). This sweeps places [begin, end) only (each with every place
// after it, then the planes), in order, into `out`, with `hits` as scratch.
void Sweep(const Model& model, std::span<const GeomPose> poses, const Broadphase& bp, int begin,
           int end, int* hits, PairSink& out) {
  const int n = static_cast<int>(bp.order.size());
  const int* order = bp.order.data();
  const double *lo_s = bp.lo_s.data(), *hi_s = bp.hi_s.data(), *lo_p = bp.lo_p.data(),
               *hi_p = bp.hi_p.data(), *lo_q = bp.lo_q.data(), *hi_q = bp.hi_q.data();
  const Broadphase::Filter* filters = bp.filters.data();
  const std::vector<std::pair<int, int>>& excluded = model.excluded_geom_pairs;
  const FloatBounds fb{bp.flo_s.data(), bp.fhi_s.data(), bp.flo_p.data(),
                       bp.fhi_p.data(), bp.flo_q.data(), bp.fhi_q.data()};
  for (int i = begin; i < end; ++i) {
    const int a = order[i];
#if defined(RIGIDTOUCH_SWEEP_AVX2)
    const int nhit = bp.wide ? ScanAvx2(fb, i, n, hits) : ScanPortable(fb, i, n, hits);
#else
    const int nhit = ScanPortable(fb, i, n, hits);
#endif
    for (int k = 0; k < nhit; ++k) {
      // the plain sweep's test of places i < j
      const int j = hits[k];
      if (lo_q[i] <= hi_q[j] && lo_q[j] <= hi_q[i] && lo_p[i] <= hi_p[j] && lo_p[j] <= hi_p[i] &&
          lo_s[i] <= hi_s[j] && lo_s[j] <= hi_s[i] && CanCollide(filters[a], filters[order[j]])) {
        AddPair(excluded, out, a, order[j]);
      }
    }
    for (int p : bp.planes) {
      if (CanCollide(filters[a], filters[p]) && BelowPlane(bp.boxes[a], poses[p])) {
        AddPair(excluded, out, a, p);
      }
    }
  }
}

// the blocks of places one thread sweeps: from the front (t = 0, into `out` in order) or the
// back (t = 1, each block's place in `out` recorded, and counted in bp.back_blocks_done once
// recorded); returns how many it took (from the front: blocks 0 to that count - 1)
int SweepBlocks(const Model& model, std::span<const GeomPose> poses, Broadphase& bp, PairSink& out,
                int t) {
  const int n = static_cast<int>(bp.order.size());
  int taken = 0;
  for (;;) {
    const int block = t == 0 ? bp.place_blocks.TakeFront() : bp.place_blocks.TakeBack();
    if (block < 0) return taken;
    ++taken;
    const int begin = block * kPlaceBlock, end = std::min(n, begin + kPlaceBlock);
    if (t == 0) {
      Sweep(model, poses, bp, begin, end, bp.hits.data(), out);
    } else {
      const int first = out.count + out.dropped;
      Sweep(model, poses, bp, begin, end, bp.upper_hits.data(), out);
      bp.block_begin[block] = first;
      bp.block_count[block] = out.count + out.dropped - first;
      bp.back_blocks_done.Increment();
    }
  }
}

struct SweepJob {
  const Model* model;
  std::span<const GeomPose> poses;
  Broadphase* bp;
};

void RunSweepJob(void* context) {
  const auto* job = static_cast<const SweepJob*>(context);
  SweepBack(*job->model, job->poses, *job->bp);
}

}  // namespace

bool BeginSharedSweep(Broadphase& bp, bool with_worker) {
  const int n = static_cast<int>(bp.order.size());
  bp.shared = with_worker && n >= kMinBoxesForTwoThreads;
  bp.place_blocks.Reset(0, bp.shared ? (n + kPlaceBlock - 1) / kPlaceBlock : 0);
  bp.back_done_before = bp.back_blocks_done.Load(std::memory_order_relaxed);
  return bp.shared;
}

void SweepBack(const Model& model, std::span<const GeomPose> poses, Broadphase& bp) {
  PairSink upper{bp.upper_pairs.data(), static_cast<int>(bp.upper_pairs.size())};
  SweepBlocks(model, poses, bp, upper, 1);
}

// the sweep from the front until the threads meet; the worker's blocks (from the back) waited
// for and their pairs appended in block order. If the back's buffer ran out (it holds the last
// blocks, not the first), the back's blocks are swept again here, in order.
void EndSharedSweep(const Model& model, std::span<const GeomPose> poses, Broadphase& bp) {
  const int n = static_cast<int>(bp.order.size());
  const int capacity = static_cast<int>(bp.pairs.size());
  PairSink lower{bp.pairs.data(), capacity};
  if (!bp.shared) {
    Sweep(model, poses, bp, 0, n, bp.hits.data(), lower);
    bp.npair = lower.count;
    bp.dropped = lower.dropped;
    return;
  }
  const int nblock = (n + kPlaceBlock - 1) / kPlaceBlock;
  const int front = SweepBlocks(model, poses, bp, lower, 0);
  // every block is taken now; those the worker took are done when it has counted them
  const auto target = bp.back_done_before + static_cast<std::uint32_t>(nblock - front);
  for (std::uint32_t now = bp.back_blocks_done.Load(); now != target;) {
    now = bp.back_blocks_done.AwaitChange(now, parallel::Worker::kDefaultSpins,
                                          parallel::Worker::kTickSleepLimitNs);
  }
  bool overflowed = false;
  for (int b = front; b < nblock; ++b)
    overflowed |= bp.block_begin[b] + bp.block_count[b] > capacity;
  if (overflowed) {
    ++bp.resweeps;
    Sweep(model, poses, bp, front * kPlaceBlock, n, bp.hits.data(), lower);
  } else {
    for (int b = front; b < nblock; ++b) {
      const auto* from = bp.upper_pairs.data() + bp.block_begin[b];
      const int kept = std::min(capacity - lower.count, bp.block_count[b]);
      std::copy(from, from + kept, bp.pairs.data() + lower.count);
      lower.count += kept;
      lower.dropped += bp.block_count[b] - kept;
    }
  }
  bp.npair = lower.count;
  bp.dropped = lower.dropped;
}

void FindPairs(const Model& model, std::span<const GeomPose> poses, Broadphase& bp,
               parallel::Worker* worker) {
  PreparePairs(model, poses, bp);
  // with a worker, the threads take blocks of places from both ends: the front's pairs go to
  // bp.pairs in order, the back's to bp.upper_pairs block by block (the last block first)
  const bool shared = BeginSharedSweep(bp, worker != nullptr);
  SweepJob job{&model, poses, &bp};
  if (shared) worker->Post(&RunSweepJob, &job);
  EndSharedSweep(model, poses, bp);
  if (shared) worker->Finish();
}

void PreparePairs(const Model& model, std::span<const GeomPose> poses, Broadphase& bp) {
  bp.npair = 0;
  bp.dropped = 0;
  const int n = static_cast<int>(bp.order.size());
  int* order = bp.order.data();
  double *lo_s = bp.lo_s.data(), *hi_s = bp.hi_s.data(), *lo_p = bp.lo_p.data(),
         *hi_p = bp.hi_p.data(), *lo_q = bp.lo_q.data(), *hi_q = bp.hi_q.data();
  // the bounds of order[i]'s box at i: along the sweep axis (s) and the two others (p, q). A NaN
  // lower bound along the sweep axis is kept as +inf, as the fresh sort below counts it: a NaN
  // would stop the insertion sort from moving other boxes past it, leaving the order unsorted
  // and the sweep blind to pairs of finite boxes; the box overlaps nothing either way
  auto place = [&bp, order, lo_s, hi_s, lo_p, hi_p, lo_q, hi_q](int i) {
    const Aabb& box = bp.boxes[order[i]];
    const int as = bp.axis, ap = (as + 1) % 3, aq = (as + 2) % 3;
    lo_s[i] = std::isnan(box.lo[as]) ? std::numeric_limits<double>::infinity() : box.lo[as];
    hi_s[i] = box.hi[as];
    lo_p[i] = box.lo[ap];
    hi_p[i] = box.hi[ap];
    lo_q[i] = box.lo[aq];
    hi_q[i] = box.hi[aq];
  };
  // this tick's boxes at the geoms' places in last tick's order, and how far their lower corners
  // spread along each axis
  Vec3 least = Vec3::Constant(std::numeric_limits<double>::infinity()), most = -least;
  for (int i = 0; i < n; ++i) {
    const int g = order[i];
    bp.boxes[g] = Bounds(model.geoms[g], poses[g]);
    place(i);
    least = least.cwiseMin(bp.boxes[g].lo);
    most = most.cwiseMax(bp.boxes[g].lo);
  }
  const Vec3 spread = most - least;
  int widest = 0;
  for (int a = 1; a < 3; ++a) {
    if (spread[a] > spread[widest]) widest = a;
  }
  if (widest != bp.axis && spread[widest] > kAxisSwitchRatio * spread[bp.axis]) {
    // a new sweep axis: sort afresh (ties by geom index, so the order depends only on the poses;
    // a NaN bound counts as +inf, which keeps the comparison a strict weak order)
    bp.axis = widest;
    const int a = widest;
    const auto key = [&bp, a](int g) {
      const double l = bp.boxes[g].lo[a];
      return std::isnan(l) ? std::numeric_limits<double>::infinity() : l;
    };
    std::sort(order, order + n, [&key](int g1, int g2) {
      const double l1 = key(g1), l2 = key(g2);
      return l1 < l2 || (l1 == l2 && g1 < g2);
    });
    for (int i = 0; i < n; ++i) place(i);
  }
  // insertion sort by the lower bound: linear when nothing crossed since the last tick; ties keep
  // their order, so the result depends only on the poses and the previous order (deterministic)
  for (int i = 1; i < n; ++i) {
    const double x = lo_s[i];
    if (!(lo_s[i - 1] > x)) continue;
    const int g = order[i];
    const double x1 = hi_s[i], p0 = lo_p[i], p1 = hi_p[i], q0 = lo_q[i], q1 = hi_q[i];
    int j = i;
    while (j > 0 && lo_s[j - 1] > x) {
      order[j] = order[j - 1];
      lo_s[j] = lo_s[j - 1];
      hi_s[j] = hi_s[j - 1];
      lo_p[j] = lo_p[j - 1];
      hi_p[j] = hi_p[j - 1];
      lo_q[j] = lo_q[j - 1];
      hi_q[j] = hi_q[j - 1];
      --j;
    }
    order[j] = g;
    lo_s[j] = x;
    hi_s[j] = x1;
    lo_p[j] = p0;
    hi_p[j] = p1;
    lo_q[j] = q0;
    hi_q[j] = q1;
  }
  FloatBoundsOf(bp);
}

}  // namespace rigidtouch::geometry
