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

/// The share of the remaining plastic impulse that impulse i removes, `remaining` = N - i + 1
/// impulses still due, this one included: Eq. 8's equal shares 1 / (N - i + 1), or, for a train
/// with a material (RenderParams::material given), shares that follow the material's envelope
/// e^(-B t): impulse j (0-based) weighs w_j = r^j, r = e^(-B n_i h), and removes
/// w_j / sum_(k >= j) w_k = (1 - r) / (1 - r^(N - i + 1)) of what a plastic collision would remove
/// now. Every share lies in (0, 1] and the last one is 1, so each impulse stays plastic-or-less
/// (never adds energy) and the last stops the approach.
double TrainShare(const Schedule& schedule, const RenderParams& render, double timestep_s,
                  int remaining);

}  // namespace rigidtouch::contact
