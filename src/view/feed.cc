#include "view/feed.h"

#include <algorithm>
#include <cmath>

#include "dynamics/tree.h"

namespace rigidtouch::view {

int FirstViewLink(const Model& model, int t) {
  int first = 0;
  for (int k = 0; k < t; ++k) first += static_cast<int>(model.trees[k].link_names.size());
  return first;
}

void SnapshotTrees(const Model& model, const Data& data, ViewSnapshot& v) noexcept {
  v.nlink = 0;
  v.njoint = 0;
  for (std::size_t t = 0; t < model.trees.size() && t < data.trees.size(); ++t) {
    const dynamics::TreeData& d = *data.trees[t];
    for (std::size_t l = 0; l < d.x_W.size() && v.nlink < kMaxViewLinks; ++l, ++v.nlink) {
      v.link_x_W[v.nlink] = d.x_W[l];
      v.link_R_WB[v.nlink] = d.R_WB[l];
    }
    for (const JointModel& j : model.trees[t].joints) {
      if (j.type != JointKind::kHinge && j.type != JointKind::kSlide) continue;
      if (v.njoint == kMaxViewJoints) break;
      v.joint_q[v.njoint++] = d.qpos[j.qpos_adr];
    }
  }
}

ViewFeed::ViewFeed(double rate_hz, std::size_t scope_capacity)
    : period_s_(1.0 / rate_hz), scope_(scope_capacity) {}

void ViewFeed::OnTick(const Model& model, const Data& data, const TraceSample& sample) noexcept {
  // the period as this thread lives it, over windows of one second
  const auto now = std::chrono::steady_clock::now();
  if (have_last_) {
    const double dt = std::chrono::duration<double>(now - last_tick_).count();
    const double e = std::abs(dt - period_s_);
    window_error_max_s_ = std::max(window_error_max_s_, e);
    window_error_sum_s_ += e;
    window_elapsed_s_ += dt;
    ++window_ticks_;
    if (window_elapsed_s_ >= 1.0) {
      rate_hz_ = static_cast<double>(window_ticks_) / window_elapsed_s_;
      error_max_s_ = window_error_max_s_;
      error_mean_s_ = window_error_sum_s_ / static_cast<double>(window_ticks_);
      window_elapsed_s_ = window_error_max_s_ = window_error_sum_s_ = 0.0;
      window_ticks_ = 0;
    }
  }
  last_tick_ = now;
  have_last_ = true;

  ScopeSample s;
  s.time_s = sample.time_s;
  s.penalty_N = sample.penalty_force_N.norm();
  s.impulsive_N = sample.impulsive_force_N.norm();
  s.total_N = sample.device_force_N.norm();
  s.penetration_m = sample.penetration_m;
  s.impulses = sample.impulses;
  if (!scope_.push(s)) ++scope_dropped_;

  ViewSnapshot& v = snapshots_.back();
  v.step = sample.step;
  v.time_s = sample.time_s;
  v.nbody = std::min<int>(static_cast<int>(data.bodies.size()), kMaxViewBodies);
  for (int b = 0; b < v.nbody; ++b) {
    v.x_W[b] = data.bodies[b].x_W;
    v.q_WB[b] = data.bodies[b].q_WB;
  }
  SnapshotTrees(model, data, v);
  v.ncontact = std::min(data.ncontact, kMaxViewContacts);
  for (int k = 0; k < v.ncontact; ++k) {
    const Contact& c = data.contacts[k];
    v.contacts[k].p_W = c.p_W;
    v.contacts[k].n_W = c.n_W;
    v.contacts[k].depth_m = c.depth_m;
    v.contacts[k].tool = c.body_a == model.tool || c.body_b == model.tool;
  }
  v.sample = sample;
  v.measured_rate_hz = rate_hz_;
  v.period_error_max_s = error_max_s_;
  v.period_error_mean_s = error_mean_s_;
  v.scope_dropped = scope_dropped_;
  std::uint32_t w = 0;
  for (std::size_t k = 0; k < data.warnings.size() && k < 32; ++k) {
    if (data.warnings[k].count > 0) w |= 1u << k;
  }
  v.warnings = w;
  snapshots_.Publish();
}

}  // namespace rigidtouch::view
