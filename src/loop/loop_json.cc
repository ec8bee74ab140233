#include "loop/loop_json.h"

#include "dynamics/tree.h"

namespace rigidtouch::loop {

nlohmann::json ToJson(const LoopStats& stats) {
  return nlohmann::json{
      {"rate_hz", stats.rate_hz},
      {"achieved_rate_hz", stats.achieved_rate_hz},
      {"elapsed_s", stats.elapsed_s},
      {"ticks", stats.ticks},
      {"overruns", stats.overruns},
      {"skipped_periods", stats.skipped_periods},
      {"yielded_periods", stats.yielded_periods},
      {"period_error_p50_s", stats.period_error_p50_s},
      {"period_error_p99_s", stats.period_error_p99_s},
      {"period_error_p999_s", stats.period_error_p999_s},
      {"period_error_max_s", stats.period_error_max_s},
      {"period_error_mean_s", stats.period_error_mean_s},
      {"period_error_samples", stats.period_error_samples},
      {"period_error_overflow", stats.period_error_overflow},
      {"wakeup_latency_max_s", stats.wakeup_latency_max_s},
      {"realtime_priority_active", stats.realtime_priority_active},
      {"memory_locked", stats.memory_locked},
      {"pinned_cpu", stats.pinned_cpu},
      {"helper_threads", stats.helper_threads},
      {"helpers_off_loop_cpu", stats.helpers_off_loop_cpu},
      {"stop_requested", stats.stop_requested},
      {"warnings", stats.warnings},
  };
}

nlohmann::json ToJson(const TraceQueueStats& stats) {
  return nlohmann::json{
      {"pushed", stats.pushed},           {"dropped", stats.dropped},   {"written", stats.written},
      {"sink_failed", stats.sink_failed}, {"capacity", stats.capacity},
  };
}

nlohmann::json JointsJson(const Model& model, const Data& data) {
  nlohmann::json joints = nlohmann::json::array();
  for (std::size_t t = 0; t < model.trees.size() && t < data.trees.size(); ++t) {
    const ArticulatedTree& tree = model.trees[t];
    const dynamics::TreeData& d = *data.trees[t];
    for (std::size_t j = 0; j < tree.joints.size(); ++j) {
      const JointModel& jm = tree.joints[j];
      const int nq = jm.type == JointKind::kFree ? 7 : jm.type == JointKind::kBall ? 4 : 1;
      const int nv = jm.type == JointKind::kFree ? 6 : jm.type == JointKind::kBall ? 3 : 1;
      nlohmann::json q = nlohmann::json::array(), v = nlohmann::json::array();
      for (int k = 0; k < nq; ++k) q.push_back(d.qpos[jm.qpos_adr + k]);
      for (int k = 0; k < nv; ++k) v.push_back(d.qvel[jm.dof_adr + k]);
      joints.push_back({{"name", jm.name},
                        {"tree", tree.name},
                        {"type", JointKindName(jm.type)},
                        {"position", nq == 1 ? q[0] : q},
                        {"velocity", nv == 1 ? v[0] : v},
                        {"at_limit", data.joint_at_limit[t][j] != 0}});
    }
  }
  return joints;
}

}  // namespace rigidtouch::loop
