// JSON views of the loop's statistics, kept apart from the loop code so the real-time path
// never includes nlohmann/json.
#pragma once

#include <nlohmann/json.hpp>

#include "loop/rate_loop.h"
#include "loop/trace_queue.h"
#include "rigidtouch/rigidtouch.h"

namespace rigidtouch::loop {

/// All fields of LoopStats, keys with their units (e.g. "period_error_p99_s").
nlohmann::json ToJson(const LoopStats& stats);

/// All fields of TraceQueueStats.
nlohmann::json ToJson(const TraceQueueStats& stats);

/// Every joint of every tree, as `rigidtouch simulate --json` lists them: name, tree, type
/// ("hinge", "slide", "ball", "free"), position (rad or m; a ball's quaternion w x y z, a free
/// joint's position and quaternion, as arrays), velocity (rad/s or m/s; arrays for ball and free)
/// and at_limit. Empty for a scene without trees.
nlohmann::json JointsJson(const Model& model, const Data& data);

}  // namespace rigidtouch::loop
