#include "geometry/collision.h"

#include <mujoco/mujoco.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <string>

#include "geometry/capacity.h"

namespace rigidtouch::geometry {
namespace {

// what the narrow phase makes of a geom of this kind at this pose
GeomCheck CheckPose(GeomCheck kind, const GeomPose& pose) {
  return kind == GeomCheck::kAccepted && !PoseFinite(pose) ? GeomCheck::kRejected : kind;
}

// the static geoms' poses (as GeomPoses gives them) and checks, which only the model changes
void SetStaticPoses(const Model& model, CollisionScratch& s) {
  for (std::size_t g = 0; g < model.geoms.size(); ++g) {
    const GeomModel& geom = model.geoms[g];
    if (geom.body >= 0) continue;
    s.poses[g] = GeomPose{geom.pos_B, geom.quat_B.toRotationMatrix()};
    s.geom_check[g] = CheckPose(s.geom_kind[g], s.poses[g]);
  }
}

}  // namespace

void CollisionScratch::Reserve(const Model& model) {
  poses.assign(model.geoms.size(), GeomPose{Vec3::Zero(), Mat3::Identity()});
  // every pair the scene can produce in one tick (BoundCapacity): none is dropped
  const long pair_capacity = BoundCapacity(model).pairs;
  if (pair_capacity > kMaxCapacity) {
    throw Error("the scene can produce up to " + std::to_string(pair_capacity) +
                " geom pairs in one step, more than the " + std::to_string(kMaxCapacity) +
                " rigidtouch preallocates");
  }
  broadphase.Reserve(model, static_cast<int>(pair_capacity));
  mj_contacts.assign(mjMAXCONPAIR, mjContact{});
  geom_kind.clear();
  for (const GeomModel& g : model.geoms) {
    geom_kind.push_back(!HasNarrowPhase(g.type, GeomType::kSphere) ? GeomCheck::kMuJoCo
                        : SizeValid(g.type, g.size)                ? GeomCheck::kAccepted
                                                                   : GeomCheck::kRejected);
  }
  geom_check = geom_kind;
  const bool any_mujoco =
      std::find(geom_kind.begin(), geom_kind.end(), GeomCheck::kMuJoCo) != geom_kind.end();
  moving.clear();
  for (std::size_t g = 0; g < model.geoms.size(); ++g) {
    const GeomModel& geom = model.geoms[g];
    if (geom.body < 0) continue;
    // the bound on the geom's own rotation keeps the tick's test of the body's (UpdatePoses)
    // sufficient for a finite rotation matrix; MuJoCo gives unit quaternions
    const bool centre_only = geom.type == GeomType::kSphere && !any_mujoco &&
                             geom.quat_B.coeffs().cwiseAbs().maxCoeff() <= 2.0;
    // +0 in every component, not -0
    const bool at_origin = geom.pos_B.x() == 0.0 && geom.pos_B.y() == 0.0 &&
                           geom.pos_B.z() == 0.0 && !std::signbit(geom.pos_B.x()) &&
                           !std::signbit(geom.pos_B.y()) && !std::signbit(geom.pos_B.z());
    const Quat& q = geom.quat_B;
    const bool identity = q.w() == 1.0 && q.x() == 0.0 && q.y() == 0.0 && q.z() == 0.0 &&
                          !std::signbit(q.x()) && !std::signbit(q.y()) && !std::signbit(q.z());
    moving.push_back(MovingGeom{static_cast<int>(g), centre_only, centre_only && at_origin,
                                !centre_only && at_origin && identity});
  }
  SetStaticPoses(model, *this);
  matching.Reserve(model.max_contacts, static_cast<int>(model.geoms.size()));
  mj = mj_makeData(model.collision.get());
  if (mj == nullptr) throw Error("could not allocate the collision backend's data");
}

void CollisionScratch::Reset(const Model& model) {
  matching.Reset();
  broadphase.Reserve(model, static_cast<int>(broadphase.pairs.size()));
  SetStaticPoses(model, *this);
}

void CollisionScratch::ReserveTwoThreads(const Model& model) {
  pair_points.assign(broadphase.pairs.size(), PairPoints{});
  pair_first.assign(broadphase.pairs.size(), 0);
  pair_run.assign(broadphase.pairs.size(), 0);
  pair_new.assign(broadphase.pairs.size(), 0);
  for (auto& points : thread_points) points.assign(model.max_contacts + kMaxPairContacts, {});
}

CollisionScratch::~CollisionScratch() {
  if (mj != nullptr) mj_deleteData(mj);
}

namespace {

// one geom pair's points as they are written: geoms in contact order (a is dynamic, and the tool
// when it takes part: its forces then act along +n), with the frames of p_A and p_B
struct PairWriter {
  int ga = -1, gb = -1;
  int body_a = -1, body_b = -1;
  bool flip = false;           // the caller's normal points from a towards b: reversed when written
  const Mat3* R_WA = nullptr;  // body rotations of dynamic bodies (Data::R_WB)
  const Mat3* R_WB = nullptr;
  Vec3 x_A, x_B;  // body positions
  // a link geom's pose (its side's points are kept in the geom's frame, which moves with the link)
  const GeomPose* link_A = nullptr;
  const GeomPose* link_B = nullptr;
};

// how a geom moves, for the order of a contact's sides: 2 on a body, 1 on a link, 0 static
int Mobility(const GeomModel& g) {
  return g.body >= 0 ? 2 : g.tree >= 0 ? 1 : 0;
}

// the writer for points of geoms (ga, gb) whose normals point from gb towards ga. Side a is the
// more mobile geom (a body before a link before static geometry; two links keep their order),
// and the tool when it takes part
PairWriter BeginPair(const Model& model, const Data& data, const CollisionScratch& s, int ga,
                     int gb) {
  PairWriter w;
  const int tool = model.tool;
  const GeomModel &a = model.geoms[ga], &b = model.geoms[gb];
  w.flip = Mobility(a) < Mobility(b) || (b.body == tool && a.body != tool);
  if (w.flip) std::swap(ga, gb);
  w.ga = ga;
  w.gb = gb;
  w.body_a = model.geoms[ga].body;
  w.body_b = model.geoms[gb].body;
  if (w.body_a >= 0) {
    w.R_WA = &data.R_WB[w.body_a];
    w.x_A = data.bodies[w.body_a].x_W;
  }
  if (w.body_b >= 0) {
    w.R_WB = &data.R_WB[w.body_b];
    w.x_B = data.bodies[w.body_b].x_W;
  }
  if (w.body_a < 0 && model.geoms[ga].tree >= 0) w.link_A = &s.poses[ga];
  if (w.body_b < 0 && model.geoms[gb].tree >= 0) w.link_B = &s.poses[gb];
  return w;
}

// how many of `n` points of one pair the contact list has room for; a full contact list counts
// Warning::kContactFull (once per step)
int Room(Data& data, int n) {
  const int room = static_cast<int>(data.contacts.size()) - data.ncontact;
  if (n <= room) return n;
  data.Warn(Warning::kContactFull);
  return room;
}

// writes one contact point of the pair into c. The id is left to MatchPair and AssignNewIds.
void WriteContact(Contact& c, const PairWriter& w, const Vec3& p_W, const Vec3& n_W,
                  double depth_m) {
  c.geom_a = w.ga;
  c.geom_b = w.gb;
  c.body_a = w.body_a;
  c.body_b = w.body_b;
  c.p_W = p_W;
  c.n_W = w.flip ? Vec3(-n_W) : n_W;
  c.depth_m = depth_m;
  // in the bodies' frames (a link geom's own frame; the world's for a static geom)
  c.p_A = w.body_a >= 0 ? Vec3(w.R_WA->transpose() * (p_W - w.x_A))
          : w.link_A    ? Vec3(w.link_A->R_WG.transpose() * (p_W - w.link_A->p_W))
                        : p_W;
  c.p_B = w.body_b >= 0 ? Vec3(w.R_WB->transpose() * (p_W - w.x_B))
          : w.link_B    ? Vec3(w.link_B->R_WG.transpose() * (p_W - w.link_B->p_W))
                        : p_W;
  c.normal_force_N = 0.0;
  c.friction_force_N_W.setZero();
  c.impulse_Ns = 0.0;
  c.group = -1;
}

// appends one contact point of the pair, for which Room has made room
void AddContact(Data& data, const PairWriter& w, const Vec3& p_W, const Vec3& n_W, double depth_m) {
  WriteContact(data.contacts[data.ncontact++], w, p_W, n_W, depth_m);
}

// MuJoCo's own function for one pair (capsules, meshes, cylinders, ellipsoids); it reads only the
// two geoms' poses
void CollideWithMuJoCo(const Model& model, Data& data, CollisionScratch& s, int g1, int g2) {
  // the compiled model's types: GeomType::kMesh also stands for cylinders and ellipsoids
  const int* mj_type = model.collision->geom_type;
  int t1 = mj_type[model.geoms[g1].mj_geom], t2 = mj_type[model.geoms[g2].mj_geom];
  if (t1 > t2) {  // MuJoCo's table is filled for type1 <= type2
    std::swap(g1, g2);
    std::swap(t1, t2);
  }
  const mjfCollision fn = mjCOLLISIONFUNC[t1][t2];
  if (fn == nullptr) return;
  for (const int g : {g1, g2}) {
    const GeomPose& pose = s.poses[g];
    const int mg = model.geoms[g].mj_geom;
    for (int k = 0; k < 3; ++k) {
      s.mj->geom_xpos[3 * mg + k] = pose.p_W[k];
      for (int j = 0; j < 3; ++j) s.mj->geom_xmat[9 * mg + 3 * k + j] = pose.R_WG(k, j);
    }
  }
  const int n = fn(model.collision.get(), s.mj, s.mj_contacts.data(), model.geoms[g1].mj_geom,
                   model.geoms[g2].mj_geom, 0.0);
  // MuJoCo's normal points from geom1 to geom2: ours from b to a, so a = g2
  const PairWriter w = BeginPair(model, data, s, g2, g1);
  for (int i = 0; i < n; ++i) {
    const mjContact& mc = s.mj_contacts[i];
    if (!(mc.dist < 0.0) || Room(data, 1) < 1) continue;
    AddContact(data, w, Vec3(mc.pos[0], mc.pos[1], mc.pos[2]),
               Vec3(mc.frame[0], mc.frame[1], mc.frame[2]), -mc.dist);
  }
}

// whether every component of q is finite and nonzero
bool NonzeroFinite(const Quat& q) {
  const auto c = q.coeffs().array();
  return (c != 0.0).all() && (c.abs() <= std::numeric_limits<double>::max()).all();
}

// the moving geoms' poses as GeomPoses gives them, and Collide's checks of its arguments, once
// per geom rather than once per pair (the static geoms' are set by Reserve). Reads the bodies'
// rotation matrices of this tick (Data::R_WB).
void UpdatePoses(const Model& model, const Data& data, CollisionScratch& s) {
  // a quaternion whose squared norm is at most this (so finite, its components at most 1e100)
  // gives a finite rotation matrix, even times a geom quaternion of components at most 2
  // (Reserve): no product in toRotationMatrix overflows. A NaN fails the comparison.
  constexpr double kBoundedQuatSquaredNorm = 1e200;
  for (const MovingGeom& m : s.moving) {
    const GeomModel& geom = model.geoms[m.geom];
    const BodyState& b = data.bodies[geom.body];
    GeomPose& pose = s.poses[m.geom];
    const GeomCheck kind = s.geom_kind[m.geom];
    if (m.centre_only && b.q_WB.coeffs().squaredNorm() <= kBoundedQuatSquaredNorm) {
      // a finite q turns (+0, +0, +0) into (+0, +0, +0): every product is a signed zero, and the
      // sums start from +0 (+0 + -0 is +0); adding +0 keeps x_W's bits but for -0, as the full
      // expression does
      pose.p_W = m.at_body_origin ? Vec3(b.x_W + Vec3::Zero()) : Vec3(b.x_W + b.q_WB * geom.pos_B);
      // the rotation matrix would be finite, so PoseFinite is whether the centre is
      s.geom_check[m.geom] =
          kind == GeomCheck::kAccepted && !pose.p_W.allFinite() ? GeomCheck::kRejected : kind;
    } else if (m.body_frame && NonzeroFinite(b.q_WB)) {
      // q_WB * (+0, +0, +0, 1) is q_WB bit for bit when no component of q_WB is zero or not
      // finite (each product by 0 or 1 is exact, and a signed zero added to a nonzero term leaves
      // it), so the geom's rotation matrix is the body's, from the same quaternion; the centre is
      // x_W + (+0, +0, +0) as for a sphere above
      pose.p_W = b.x_W + Vec3::Zero();
      pose.R_WG = data.R_WB[geom.body];
      s.geom_check[m.geom] = CheckPose(kind, pose);
    } else {
      pose.p_W = b.x_W + b.q_WB * geom.pos_B;
      pose.R_WG = (b.q_WB * geom.quat_B).toRotationMatrix();
      s.geom_check[m.geom] = CheckPose(kind, pose);
    }
  }
}

// one pair's contacts on the tick's thread, written to the contact list (not yet matched)
void CollidePair(const Model& model, Data& data, CollisionScratch& s, int g1, int g2) {
  const GeomModel& a = model.geoms[g1];
  const GeomModel& b = model.geoms[g2];
  const GeomCheck c1 = s.geom_check[g1], c2 = s.geom_check[g2];
  // HasNarrowPhase(a.type, b.type), and Collide's checks of its arguments
  if (c1 != GeomCheck::kMuJoCo && c2 != GeomCheck::kMuJoCo &&
      !(a.type == GeomType::kPlane && b.type == GeomType::kPlane)) {
    const int n = c1 == GeomCheck::kAccepted && c2 == GeomCheck::kAccepted
                      ? CollideAccepted(a.type, a.size, s.poses[g1], b.type, b.size, s.poses[g2],
                                        s.points.data(), kMaxPairContacts)
                      : 0;
    if (n > 0) {
      // the narrow phase's normal points from geom 2 towards geom 1
      const PairWriter w = BeginPair(model, data, s, g1, g2);
      const int fit = Room(data, n);
      for (int i = 0; i < fit; ++i) {
        AddContact(data, w, s.points[i].p_W, s.points[i].n_W, s.points[i].depth_m);
      }
    }
  } else {
    CollideWithMuJoCo(model, data, s, g1, g2);
  }
}

// the narrow phase of pairs [begin, end) into point buffer t, without touching Data: what
// CollidePair computes, for either thread. MuJoCo's pairs (and any beyond the buffer) are left to
// the tick's thread.
void NarrowRange(const Model& model, CollisionScratch& s, int begin, int end, int t) {
  ContactPoint* points = s.thread_points[t].data();
  const int capacity = static_cast<int>(s.thread_points[t].size());
  // counted here and stored once: the two threads' counters share a cache line, and a store per
  // pair moved it between the cores at every pair
  int used = s.thread_used[t];
  for (int k = begin; k < end; ++k) {
    const auto [g1, g2] = s.broadphase.pairs[k];
    const GeomModel& a = model.geoms[g1];
    const GeomModel& b = model.geoms[g2];
    const GeomCheck c1 = s.geom_check[g1], c2 = s.geom_check[g2];
    CollisionScratch::PairPoints& out = s.pair_points[k];
    if (c1 == GeomCheck::kMuJoCo || c2 == GeomCheck::kMuJoCo ||
        used + kMaxPairContacts > capacity) {
      out = {0, -1, t};
    } else if ((a.type == GeomType::kPlane && b.type == GeomType::kPlane) ||
               c1 != GeomCheck::kAccepted || c2 != GeomCheck::kAccepted) {
      out = {used, 0, t};
    } else {
      out = {used,
             CollideAccepted(a.type, a.size, s.poses[g1], b.type, b.size, s.poses[g2],
                             points + used, kMaxPairContacts),
             t};
      used += out.count;
    }
  }
  s.thread_used[t] = used;
}

// pairs per block the two threads take from the pair list
constexpr int kPairBlock = 16;

// the blocks of the pair list one thread takes, from the front (t = 0) or the back (t = 1)
void NarrowBlocks(const Model& model, CollisionScratch& s, int t) {
  const int npair = s.broadphase.npair;
  for (;;) {
    const int block = t == 0 ? s.pair_blocks.TakeFront() : s.pair_blocks.TakeBack();
    if (block < 0) return;
    NarrowRange(model, s, block * kPairBlock, std::min(npair, (block + 1) * kPairBlock), t);
  }
}

// returns once the tick's thread has raised s.progress by `steps` from `before`
void AwaitProgress(const CollisionScratch& s, std::uint32_t before, std::uint32_t steps) {
  for (std::uint32_t now = s.progress.Load(); now - before < steps;) {
    now = s.progress.AwaitChange(now, parallel::Worker::kDefaultSpins,
                                 parallel::Worker::kTickSleepLimitNs);
  }
}

// the worker's first job of the tick: last tick's contacts indexed while the tick's thread
// prepares the sweep (neither reads what the other writes), then the sweep's blocks from the back
// once it may be shared, then the narrow phase's blocks from the back once the pairs are found.
// Run by the tick's thread instead (Finish), both have happened and every block is taken.
void RunRememberAndNarrowJob(void* context) {
  const auto* job = static_cast<const CollisionScratch::NarrowJob*>(context);
  CollisionScratch& s = *job->scratch;
  RememberPrevious(*job->data, s.matching);
  AwaitProgress(s, job->progress_before, 1);
  SweepBack(*job->model, s.poses, s.broadphase);
  AwaitProgress(s, job->progress_before, 2);
  NarrowBlocks(*job->model, s, 1);
}

// writes and matches the points of pairs [begin, end) at the places WritePlaces gave them
void WriteRange(const Model& model, Data& data, CollisionScratch& s, int begin, int end) {
  for (int k = begin; k < end; ++k) {
    const CollisionScratch::PairPoints found = s.pair_points[k];
    s.pair_new[k] = 0;
    if (found.count == 0) continue;
    const auto [g1, g2] = s.broadphase.pairs[k];
    const ContactPoint* p = s.thread_points[found.thread].data() + found.offset;
    const PairWriter w = BeginPair(model, data, s, g1, g2);
    const int first = s.pair_first[k];
    for (int i = 0; i < found.count; ++i) {
      WriteContact(data.contacts[first + i], w, p[i].p_W, p[i].n_W, p[i].depth_m);
    }
    s.pair_new[k] = MatchPair(data, s.matching, first, first + found.count) ? 1 : 0;
    data.runs[s.pair_run[k]] = PairRun{w.ga, w.gb, w.body_a, w.body_b, first, found.count};
  }
}

// the blocks of the pair list one thread writes, from the front (t = 0) or the back (t = 1)
void WriteBlocks(const Model& model, Data& data, CollisionScratch& s, int t) {
  const int npair = s.broadphase.npair;
  for (;;) {
    const int block = t == 0 ? s.pair_blocks.TakeFront() : s.pair_blocks.TakeBack();
    if (block < 0) return;
    WriteRange(model, data, s, block * kPairBlock, std::min(npair, (block + 1) * kPairBlock));
  }
}

void RunWriteJob(void* context) {
  const auto* job = static_cast<const CollisionScratch::NarrowJob*>(context);
  WriteBlocks(*job->model, *job->data, *job->scratch, 1);
}

// the first contact and the run of each pair in the contact list, as one thread writing in pair
// order would place them, and the contacts' and runs' counts in *total and *nruns; false if some
// pair is left to the tick's thread (its count is not known yet) or the points do not all fit (the
// one-thread path then counts the warning and drops the same points)
bool WritePlaces(const Data& data, CollisionScratch& s, int* total, int* nruns) {
  const int npair = s.broadphase.npair;
  int next = data.ncontact, run = data.nruns;
  for (int k = 0; k < npair; ++k) {
    const int count = s.pair_points[k].count;
    if (count < 0) return false;
    s.pair_first[k] = next;
    s.pair_run[k] = run;
    next += count;
    run += count > 0 ? 1 : 0;
  }
  *total = next;
  *nruns = run;
  return next <= static_cast<int>(data.contacts.size()) &&
         run <= static_cast<int>(data.runs.size());
}

// fewer pairs than this are not worth the hand-off to the worker
constexpr int kMinPairsForTwoThreads = 32;

// the worker's first job posted (RunRememberAndNarrowJob); finds the pairs and then shares the
// narrow phase with the worker (blocks of the pair list taken from both ends) if there are enough
// pairs; returns when the worker's job is done (last tick's contacts indexed)
bool FindPairsAndNarrow(const Model& model, Data& data, CollisionScratch& s,
                        parallel::Worker& worker) {
  const std::uint32_t before = s.progress.Load();
  s.job = {&model, &s, &data, before};
  worker.Post(&RunRememberAndNarrowJob, &s.job);
  UpdatePoses(model, data, s);
  PreparePairs(model, s.poses, s.broadphase);
  BeginSharedSweep(s.broadphase, true);
  s.progress.Publish(before + 1);
  EndSharedSweep(model, s.poses, s.broadphase);
  const int npair = s.broadphase.npair;
  const bool share = npair >= kMinPairsForTwoThreads;
  s.thread_used = {0, 0};
  s.pair_blocks.Reset(0, share ? (npair + kPairBlock - 1) / kPairBlock : 0);
  s.progress.Publish(before + 2);
  if (share) NarrowBlocks(model, s, 0);
  worker.Finish();
  return share;
}

// after the narrow phase on two threads, the contacts written and matched in pair order: on both
// threads again when every pair's count is known and fits, each pair at the place one thread
// would give it and the new contacts numbered afterwards in contact order; otherwise on the
// tick's thread. Either way the same contacts, bit for bit, as CollidePair's and MatchAndNumber's
void WriteOnTwoThreads(const Model& model, Data& data, CollisionScratch& s,
                       parallel::Worker& worker) {
  const int npair = s.broadphase.npair;
  const int nblock = (npair + kPairBlock - 1) / kPairBlock;
  int total = 0, nruns = 0;
  if (WritePlaces(data, s, &total, &nruns)) {
    s.pair_blocks.Reset(0, nblock);
    worker.Post(&RunWriteJob, &s.job);
    WriteBlocks(model, data, s, 0);
    worker.Finish();
    for (int k = 0; k < npair; ++k) {
      if (s.pair_new[k]) {
        AssignNewIds(data, s.matching, s.pair_first[k], s.pair_first[k] + s.pair_points[k].count);
      }
    }
    data.ncontact = total;
    data.nruns = nruns;
    ++s.written_on_two_threads;
    return;
  }
  for (int k = 0; k < npair; ++k) {
    const auto [g1, g2] = s.broadphase.pairs[k];
    const int begin = data.ncontact;
    const CollisionScratch::PairPoints found = s.pair_points[k];
    if (found.count < 0) {
      CollidePair(model, data, s, g1, g2);
    } else if (found.count > 0) {
      const ContactPoint* p = s.thread_points[found.thread].data() + found.offset;
      const PairWriter w = BeginPair(model, data, s, g1, g2);
      const int fit = Room(data, found.count);
      for (int i = 0; i < fit; ++i) AddContact(data, w, p[i].p_W, p[i].n_W, p[i].depth_m);
    }
    if (data.ncontact > begin) MatchAndNumber(data, s.matching, begin, data.ncontact);
  }
}

}  // namespace

void DetectContacts(const Model& model, Data& data, CollisionScratch& s, parallel::Worker* worker) {
  if (worker != nullptr) {
    const bool shared = FindPairsAndNarrow(model, data, s, *worker);
    if (s.broadphase.dropped > 0) data.Warn(Warning::kContactFull);
    if (shared) {
      WriteOnTwoThreads(model, data, s, *worker);
      return;
    }
  } else {
    UpdatePoses(model, data, s);
    FindPairs(model, s.poses, s.broadphase);
    if (s.broadphase.dropped > 0) data.Warn(Warning::kContactFull);
    RememberPrevious(data, s.matching);
  }
  for (int k = 0; k < s.broadphase.npair; ++k) {
    const auto [g1, g2] = s.broadphase.pairs[k];
    const int begin = data.ncontact;
    CollidePair(model, data, s, g1, g2);
    if (data.ncontact > begin) MatchAndNumber(data, s.matching, begin, data.ncontact);
  }
}

}  // namespace rigidtouch::geometry
