// JSON views of the loop's statistics, kept apart from the loop code so the real-time path
// never includes nlohmann/json.
#pragma once

#include <nlohmann/json.hpp>

#include "loop/rate_loop.h"
#include "loop/trace_queue.h"

namespace rigidtouch::loop {

/// All fields of LoopStats, keys with their units (e.g. "period_error_p99_s").
nlohmann::json ToJson(const LoopStats& stats);

/// All fields of TraceQueueStats.
nlohmann::json ToJson(const TraceQueueStats& stats);

}  // namespace rigidtouch::loop
