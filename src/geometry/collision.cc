#include "geometry/collision.h"

#include <mujoco/mujoco.h>

#include <algorithm>
#include <limits>

namespace rigidtouch::geometry {
namespace {

Vec3 ToLocal(const Data& data, int body, const Vec3& p_W) {
  if (body < 0) return p_W;
  const BodyState& s = data.bodies[body];
  return s.q_WB.conjugate() * (p_W - s.x_W);
}

// last tick's contacts become `previous` (the buffers trade places, no copy), and the runs of
// their geom pairs are indexed for MatchPair
void RememberPrevious(Data& data) {
  std::swap(data.contacts, data.previous);
  data.nprevious = data.ncontact;
  data.ncontact = 0;
  int nruns = 0;
  for (int begin = 0; begin < data.nprevious;) {
    const Contact& c = data.previous[begin];
    int end = begin + 1;
    while (end < data.nprevious && data.previous[end].geom_a == c.geom_a &&
           data.previous[end].geom_b == c.geom_b) {
      ++end;
    }
    data.previous_runs[nruns++] = PairRun{c.geom_a, c.geom_b, begin, end - begin};
    begin = end;
  }
  data.nprevious_runs = nruns;
  std::sort(data.previous_runs.begin(), data.previous_runs.begin() + nruns,
            [](const PairRun& x, const PairRun& y) {
              return x.geom_a != y.geom_a ? x.geom_a < y.geom_a : x.geom_b < y.geom_b;
            });
}

// matches the contacts of one geom pair [begin, end) in data.contacts against last tick's
void MatchPair(Data& data, int begin, int end) {
  const Contact& key = data.contacts[begin];
  const auto runs_end = data.previous_runs.begin() + data.nprevious_runs;
  const auto run = std::lower_bound(
      data.previous_runs.begin(), runs_end, key, [](const PairRun& r, const Contact& c) {
        return r.geom_a != c.geom_a ? r.geom_a < c.geom_a : r.geom_b < c.geom_b;
      });
  const bool found = run != runs_end && run->geom_a == key.geom_a && run->geom_b == key.geom_b;
  const auto lo = data.previous.begin() + (found ? run->begin : 0);
  const int nprev = found ? run->count : 0;
  const int ncur = end - begin;
  // a pair with one point before and now is the same contact wherever it slid
  const bool single = nprev == 1 && ncur == 1;
  // greedy nearest matching; a manifold has at most a few points
  unsigned used = 0;
  for (int c = begin; c < end; ++c) {
    Contact& con = data.contacts[c];
    int best = -1;
    double best_d2 = kMatchDistance_m * kMatchDistance_m;
    for (int k = 0; k < nprev && k < 32; ++k) {
      if (used & (1u << k)) continue;
      const double d2 = (lo[k].p_A - con.p_A).squaredNorm();
      if (single || d2 < best_d2) {
        best = k;
        best_d2 = d2;
      }
    }
    if (best >= 0) {
      used |= 1u << best;
      const Contact& prev = lo[best];
      con.id = prev.id;
      con.is_new = false;
      con.sticking = prev.sticking;
      con.anchor_A = prev.anchor_A;
      con.anchor_B = prev.anchor_B;
      con.phase = prev.phase;
    } else {
      con.id = data.next_contact_id++;
      con.is_new = true;
      con.sticking = false;
      con.anchor_A = con.p_A;
      con.anchor_B = con.p_B;
      con.phase = ContactPhase::kResting;
    }
  }
}

}  // namespace

void CollisionScratch::Reserve(const Model& model) {
  poses.assign(model.geoms.size(), GeomPose{Vec3::Zero(), Mat3::Identity()});
  broadphase.Reserve(model, std::max(64, 8 * static_cast<int>(model.geoms.size())));
  mj_contacts.assign(mjMAXCONPAIR, mjContact{});
  mj = mj_makeData(model.collision.get());
  if (mj == nullptr) throw Error("could not allocate the collision backend's data");
}

void CollisionScratch::Reset(const Model& model) {
  broadphase.Reserve(model, static_cast<int>(broadphase.pairs.size()));
}

CollisionScratch::~CollisionScratch() {
  if (mj != nullptr) mj_deleteData(mj);
}

namespace {

// appends one contact point of geoms (ga, gb), normal from gb towards ga
void AddContact(const Model& model, Data& data, int ga, int gb, const Vec3& p_W, Vec3 n_W,
                double depth_m) {
  if (data.ncontact >= static_cast<int>(data.contacts.size())) {
    auto& w = data.warnings[static_cast<int>(Warning::kContactFull)];
    if (w.last_step != data.step) {
      ++w.count;
      w.last_step = data.step;
    }
    return;
  }
  // a is dynamic, and the tool when it takes part (its forces then act along +n)
  const int tool = model.tool;
  if (model.geoms[ga].body < 0 || (model.geoms[gb].body == tool && model.geoms[ga].body != tool)) {
    std::swap(ga, gb);
    n_W = -n_W;
  }
  Contact& c = data.contacts[data.ncontact++];
  c.geom_a = ga;
  c.geom_b = gb;
  c.body_a = model.geoms[ga].body;
  c.body_b = model.geoms[gb].body;
  c.p_W = p_W;
  c.n_W = n_W;
  c.depth_m = depth_m;
  c.p_A = ToLocal(data, c.body_a, p_W);
  c.p_B = ToLocal(data, c.body_b, p_W);
  c.normal_force_N = 0.0;
  c.friction_force_W.setZero();
  c.impulse_Ns = 0.0;
  c.group = -1;
  c.id = -1;
}

int MjType(GeomType t) {
  switch (t) {
    case GeomType::kPlane:
      return mjGEOM_PLANE;
    case GeomType::kSphere:
      return mjGEOM_SPHERE;
    case GeomType::kCapsule:
      return mjGEOM_CAPSULE;
    case GeomType::kBox:
      return mjGEOM_BOX;
    case GeomType::kMesh:
      return mjGEOM_MESH;
  }
  return mjGEOM_NONE;
}

// MuJoCo's own function for one pair (capsules, meshes); it reads only the two geoms' poses
void CollideWithMuJoCo(const Model& model, Data& data, CollisionScratch& s, int g1, int g2) {
  int t1 = MjType(model.geoms[g1].type), t2 = MjType(model.geoms[g2].type);
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
  for (int i = 0; i < n; ++i) {
    const mjContact& mc = s.mj_contacts[i];
    if (!(mc.dist < 0.0)) continue;
    // MuJoCo's normal points from geom1 to geom2: ours from b to a, so a = g2
    AddContact(model, data, g2, g1, Vec3(mc.pos[0], mc.pos[1], mc.pos[2]),
               Vec3(mc.frame[0], mc.frame[1], mc.frame[2]), -mc.dist);
  }
}

}  // namespace

void DetectContacts(const Model& model, Data& data, CollisionScratch& s) {
  RememberPrevious(data);
  GeomPoses(model, data.bodies, s.poses);
  FindPairs(model, s.poses, s.broadphase);
  if (s.broadphase.dropped > 0) {
    auto& w = data.warnings[static_cast<int>(Warning::kContactFull)];
    ++w.count;
    w.last_step = data.step;
  }
  for (int k = 0; k < s.broadphase.npair; ++k) {
    const auto [g1, g2] = s.broadphase.pairs[k];
    const GeomModel& a = model.geoms[g1];
    const GeomModel& b = model.geoms[g2];
    const int begin = data.ncontact;
    if (HasNarrowPhase(a.type, b.type)) {
      const int n = Collide(a.type, a.size, s.poses[g1], b.type, b.size, s.poses[g2],
                            s.points.data(), static_cast<int>(s.points.size()));
      for (int i = 0; i < n; ++i) {
        // the narrow phase's normal points from geom 2 towards geom 1
        AddContact(model, data, g1, g2, s.points[i].p_W, s.points[i].n_W, s.points[i].depth_m);
      }
    } else {
      CollideWithMuJoCo(model, data, s, g1, g2);
    }
    const int end = data.ncontact;
    for (int c = begin; c < end; ++c) data.contacts[c].pair_points = end - begin;
    if (end > begin) MatchPair(data, begin, end);
  }
}

}  // namespace rigidtouch::geometry
