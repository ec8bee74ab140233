#include "loop/loop_json.h"

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

}  // namespace rigidtouch::loop
