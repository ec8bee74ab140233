#include "geometry/collision.h"

#include <mujoco/mujoco.h>

#include <algorithm>
#include <limits>

namespace rigidtouch::geometry {
namespace {

// order of contacts by geom pair, then by id, for matching with binary search
bool PairLess(const Contact& x, const Contact& y) {
  if (x.geom_a != y.geom_a) return x.geom_a < y.geom_a;
  if (x.geom_b != y.geom_b) return x.geom_b < y.geom_b;
  return x.id < y.id;
}

void WriteQpos(const Model& model, const Data& data, mjData* d) {
  for (std::size_t i = 0; i < model.bodies.size(); ++i) {
    const BodyModel& b = model.bodies[i];
    const BodyState& s = data.bodies[i];
    const Quat q_W_body = s.q_WB * b.iquat_B.conjugate();
    const Vec3 origin_W = s.x_W - q_W_body * b.ipos_B;
    mjtNum* qpos = d->qpos + b.mj_qpos_adr;
    qpos[0] = origin_W.x();
    qpos[1] = origin_W.y();
    qpos[2] = origin_W.z();
    qpos[3] = q_W_body.w();
    qpos[4] = q_W_body.x();
    qpos[5] = q_W_body.y();
    qpos[6] = q_W_body.z();
  }
}

Vec3 ToLocal(const Data& data, int body, const Vec3& p_W) {
  if (body < 0) return p_W;
  const BodyState& s = data.bodies[body];
  return s.q_WB.conjugate() * (p_W - s.x_W);
}

// matches the contacts of one geom pair [begin, end) in data.contacts against last tick's
void MatchPair(Data& data, int begin, int end) {
  const Contact& key = data.contacts[begin];
  const auto first = data.previous.begin();
  const auto last = data.previous.begin() + data.nprevious;
  auto lo = std::lower_bound(first, last, key, [](const Contact& x, const Contact& y) {
    return x.geom_a != y.geom_a ? x.geom_a < y.geom_a : x.geom_b < y.geom_b;
  });
  auto hi = lo;
  while (hi != last && hi->geom_a == key.geom_a && hi->geom_b == key.geom_b) ++hi;
  const int nprev = static_cast<int>(hi - lo);
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

void DetectContacts(const Model& model, Data& data, mjData* d) {
  const mjModel* m = model.collision.get();
  WriteQpos(model, data, d);
  mj_kinematics(m, d);
  d->ncon = 0;
  const int full_before = d->warning[mjWARN_CONTACTFULL].number;
  mj_collision(m, d);
  if (d->warning[mjWARN_CONTACTFULL].number != full_before) {
    auto& w = data.warnings[static_cast<int>(Warning::kContactFull)];
    ++w.count;
    w.last_step = data.step;
  }
  // MuJoCo geom ids equal Model::geoms indices (LoadModel copies them in order)
  int n = 0;
  const int capacity = static_cast<int>(data.contacts.size());
  for (int i = 0; i < d->ncon && n < capacity; ++i) {
    const mjContact& mc = d->contact[i];
    if (mc.exclude != 0 || !(mc.dist < 0.0)) continue;
    // MuJoCo's normal points from geom1 to geom2; ours from b to a, so a = geom2 by default
    int ga = mc.geom2, gb = mc.geom1;
    double sign = 1.0;
    const int tool = model.tool;
    const bool swap =
        model.geoms[ga].body < 0 || (model.geoms[gb].body == tool && model.geoms[ga].body != tool);
    if (swap) {
      std::swap(ga, gb);
      sign = -1.0;
    }
    Contact& c = data.contacts[n++];
    c.geom_a = ga;
    c.geom_b = gb;
    c.body_a = model.geoms[ga].body;
    c.body_b = model.geoms[gb].body;
    c.p_W = Vec3(mc.pos[0], mc.pos[1], mc.pos[2]);
    c.n_W = sign * Vec3(mc.frame[0], mc.frame[1], mc.frame[2]);
    c.depth_m = -mc.dist;
    c.p_A = ToLocal(data, c.body_a, c.p_W);
    c.p_B = ToLocal(data, c.body_b, c.p_W);
    c.normal_force_N = 0.0;
    c.friction_force_W.setZero();
    c.impulse_Ns = 0.0;
    c.group = -1;
    c.id = -1;
  }
  data.ncontact = n;
  // group by pair (MuJoCo emits a pair's points together, but swaps may interleave) and match
  std::sort(data.contacts.begin(), data.contacts.begin() + n, PairLess);
  for (int begin = 0; begin < n;) {
    int end = begin + 1;
    while (end < n && data.contacts[end].geom_a == data.contacts[begin].geom_a &&
           data.contacts[end].geom_b == data.contacts[begin].geom_b) {
      ++end;
    }
    for (int c = begin; c < end; ++c) data.contacts[c].pair_points = end - begin;
    MatchPair(data, begin, end);
    begin = end;
  }
}

void RememberContacts(Data& data) {
  std::copy(data.contacts.begin(), data.contacts.begin() + data.ncontact, data.previous.begin());
  data.nprevious = data.ncontact;
  std::sort(data.previous.begin(), data.previous.begin() + data.nprevious, PairLess);
}

}  // namespace rigidtouch::geometry
