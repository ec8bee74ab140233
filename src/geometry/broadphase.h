// Broad phase: which geom pairs may touch this tick. Sweep and prune over axis-aligned boxes along
// the world axis over which they spread most (as MuJoCo sweeps along its principal axis), with an
// insertion sort that is linear when the order barely changes between ticks. The sweep tests
// float copies of the bounds several geoms at a time (SIMD) and the double bounds only for the
// candidates they let through, which gives the plain double sweep's pairs in its order. Planes are
// infinite and are paired with every geom that may collide with them.
#pragma once

#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "geometry/narrow_phase.h"
#include "parallel/worker.h"
#include "rigidtouch/model.h"

namespace rigidtouch::geometry {

/// Axis-aligned bounding box in the world frame.
struct Aabb {
  Vec3 lo = Vec3::Zero();
  Vec3 hi = Vec3::Zero();
};

/// Preallocated broad-phase state; the sort order persists across ticks.
struct Broadphase {
  std::vector<Aabb> boxes;  // (ngeom)
  std::vector<int> order;   // (non-plane geoms) sorted by boxes[i].lo[axis]
  std::vector<int> planes;  // static plane geoms
  int axis = 0;             // the sweep axis (0 x, 1 y, 2 z)
  // the boxes in sweep order, one array per bound (order[i]'s at i), for a compact inner loop:
  // bounds along the sweep axis (lo_s, hi_s) and the two others in cyclic order (_p, _q)
  std::vector<double> lo_s, hi_s, lo_p, hi_p, lo_q, hi_q;  // (non-plane geoms)
  // the same bounds as floats (each rounded to the nearest), for a wide first test of the sweep;
  // NaN past the last geom, so that a block read there overlaps nothing
  std::vector<float> flo_s, fhi_s, flo_p, fhi_p, flo_q, fhi_q;  // (non-plane geoms + 7)
  std::vector<int> hits;  // (non-plane geoms) the places whose float boxes overlap one place's
  std::vector<int> upper_hits;  // (non-plane geoms) the same for the worker's part of the sweep
  bool wide = false;            // the float test runs eight places at once (AVX2, from the CPU)
  // each geom's collision filter from the model (CollisionFilter, in Reserve), read for every
  // candidate pair
  struct Filter {
    // what moves the geom: its body's index, nbody + the link's place among every tree's links
    // (LinkOwner), or -1 for static geometry
    int owner = -1;
    // the owner of its link's parent link when MuJoCo's parent filter applies (a link geom whose
    // parent is a link, Model::filter_parent): the two never collide; else -2, which is no owner
    int parent = -2;
    int contype = 0, conaffinity = 0;
  };
  std::vector<Filter> filters;             // (ngeom)
  std::vector<std::pair<int, int>> pairs;  // (capacity) candidate pairs, geom indices
  // (capacity) with a worker: the pairs of the blocks of places the worker swept (from the last
  // block down), appended to `pairs` in block order
  std::vector<std::pair<int, int>> upper_pairs;
  // with a worker: the blocks of places the two threads take (from the front and the back), and
  // where each of the worker's blocks begins in upper_pairs and how many pairs it has
  parallel::TwoEndedRange place_blocks;
  std::vector<int> block_begin, block_count;  // (places / block + 1)
  bool shared = false;                        // this tick's sweep is shared (BeginSharedSweep)
  parallel::WakeCounter
      back_blocks_done;  // the worker's blocks swept since the start, each once recorded
  std::uint32_t back_done_before = 0;  // its value when this tick's sweep began
  long resweeps = 0;  // ticks whose worker's blocks did not fit upper_pairs and were swept again
  int npair = 0;
  int dropped = 0;  // candidates beyond capacity this tick

  /// Sizes the buffers for `model`; `pair_capacity` candidate pairs at most.
  void Reserve(const Model& model, int pair_capacity);
};

/// World poses of every geom from the body states.
void GeomPoses(const Model& model, std::span<const BodyState> bodies, std::span<GeomPose> poses);

/// Whether two geoms may collide at all: different owners (bodies, links of trees), not both
/// static, and MuJoCo's filter (contype1 & conaffinity2) || (contype2 & conaffinity1). Without
/// the parent filter of links, which needs the trees: CanCollide(model, a, b) has it.
bool CanCollide(const GeomModel& a, const GeomModel& b);

/// The owner number of link `link` of tree `tree` in Broadphase::Filter: nbody + the link's place
/// among every tree's links, in tree order.
int LinkOwner(const Model& model, int tree, int link);

/// Geom g's collision filter (Broadphase::Filter).
Broadphase::Filter CollisionFilter(const Model& model, int g);

/// Whether two collision filters may collide: different owners, not a link and its parent link
/// (Filter::parent), and the contype/conaffinity bits. Static geometry (owner -1) never collides
/// with static geometry; a link collides with it, with free bodies and with other links.
bool CanCollide(const Broadphase::Filter& a, const Broadphase::Filter& b);

/// CanCollide of geoms a and b of `model`, with MuJoCo 2.2.2's filter in full: the bits, not one
/// body (after welding: one link, or both static), and not a link and its parent link unless the
/// scene disables filterparent (Model::filter_parent). <contact><exclude> is applied apart
/// (Model::excluded_geom_pairs).
bool CanCollide(const Model& model, int a, int b);

/// With fewer boxes (non-plane geoms) than this, one thread sweeps: the hand-off would cost more.
inline constexpr int kMinBoxesForTwoThreads = 256;

/// Fills bp.pairs with the candidate pairs for the current poses, in a deterministic order. With
/// a worker (threads 2) and enough boxes the two threads share the sweep in blocks of places, taken
/// from both ends: the same pairs in the same order.
void FindPairs(const Model& model, std::span<const GeomPose> poses, Broadphase& bp,
               parallel::Worker* worker = nullptr);

/// FindPairs in parts, for a caller whose worker is already running a job of the caller's (the
/// collision stage's first job): on this thread PreparePairs (this tick's boxes, sweep axis and
/// order) and BeginSharedSweep (true: a worker and enough boxes to share), then, once the worker
/// may start, EndSharedSweep, which sweeps from the front, waits for the blocks the worker took
/// and appends their pairs in order. The worker calls SweepBack after BeginSharedSweep has returned
/// (the caller tells it when); a worker that calls it late, or never, finds no blocks left. The
/// same pairs in the same order as FindPairs.
void PreparePairs(const Model& model, std::span<const GeomPose> poses, Broadphase& bp);
bool BeginSharedSweep(Broadphase& bp, bool with_worker);
void SweepBack(const Model& model, std::span<const GeomPose> poses, Broadphase& bp);
void EndSharedSweep(const Model& model, std::span<const GeomPose> poses, Broadphase& bp);

}  // namespace rigidtouch::geometry
