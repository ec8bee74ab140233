// The collision-rendering schedule of an impulse train (Eq. 6, Eq. 7; docs/method.md).
#pragma once

#include <cstdint>

#include "rigidtouch/data.h"
#include "rigidtouch/model.h"

namespace rigidtouch::contact {

/// Derives n, n_i and N from the time step and render parameters. Throws Error naming the
/// parameter when t_c or f lies outside the bounds that Eq. 6-7 imply.
Schedule MakeSchedule(double timestep_s, const RenderParams& render);

/// Whether an impulse is due at `step` for a group whose window is `window`; if so, sets
/// `index` (i, 1-based) and `remaining` (N - i + 1, the divisor of Eq. 8).
bool ImpulseDue(const Schedule& schedule, const WindowState& window, std::int64_t step, int* index,
                int* remaining);

}  // namespace rigidtouch::contact
