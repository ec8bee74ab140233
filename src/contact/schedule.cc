#include "contact/schedule.h"

#include <cmath>
#include <sstream>

namespace rigidtouch::contact {
namespace {

// relative tolerance when a ratio of times lands on a whole number of steps up to rounding error
constexpr double kWholeStepTolerance = 1e-9;

}  // namespace

Schedule MakeSchedule(double h, const RenderParams& render) {
  Schedule s;
  if (render.renderer != RendererKind::kTrain) {
    // penalty: never due; single impulse: one impulse at onset (N = 1)
    return s;
  }
  const double n_exact = render.t_collision_s / h;  // Eq. 6
  if (n_exact < 1.0 - kWholeStepTolerance) {
    std::ostringstream msg;
    msg << "t_collision_s = " << render.t_collision_s
        << " s is shorter than one time step (h = " << h
        << " s); the collision window needs n = t_c / h >= 1 steps (Eq. 6)";
    throw Error(msg.str());
  }
  const double f_min = 1.0 / render.t_collision_s;  // at least one impulse in the window
  const double f_max = 1.0 / h;                     // at most one impulse per step
  if (render.frequency_hz < f_min * (1.0 - kWholeStepTolerance) ||
      render.frequency_hz > f_max * (1.0 + kWholeStepTolerance)) {
    std::ostringstream msg;
    msg << "frequency_hz = " << render.frequency_hz << " Hz is outside [1/t_c, 1/h] = [" << f_min
        << ", " << f_max << "] Hz: the time step allows at most one impulse per step (n_i = 1/(f h)"
        << " >= 1, Eq. 7) and the window of t_c = " << render.t_collision_s
        << " s must hold at least one impulse (n_i <= n, Eq. 6-7)";
    throw Error(msg.str());
  }
  // both are whole numbers of steps: round to the nearest step
  s.window_steps = static_cast<int>(std::lround(n_exact));
  s.interval_steps = static_cast<int>(std::lround(1.0 / (render.frequency_hz * h)));  // Eq. 7
  if (s.interval_steps < 1) s.interval_steps = 1;
  if (s.interval_steps > s.window_steps) s.interval_steps = s.window_steps;
  s.impulses =
      static_cast<int>(std::lround(static_cast<double>(s.window_steps) / s.interval_steps));
  if (s.impulses < 1) s.impulses = 1;
  return s;
}

bool ImpulseDue(const Schedule& schedule, const WindowState& window, std::int64_t step, int* index,
                int* remaining) {
  if (window.onset_step < 0 || step < window.onset_step) return false;
  const std::int64_t k = step - window.onset_step;
  if (k % schedule.interval_steps != 0) return false;
  const std::int64_t done = k / schedule.interval_steps;  // impulses scheduled before this one
  if (done >= schedule.impulses) return false;
  *index = static_cast<int>(done) + 1;
  *remaining = schedule.impulses - static_cast<int>(done);  // N - i + 1
  return true;
}

double TrainShare(const Schedule& schedule, const RenderParams& render, double timestep_s,
                  int remaining) {
  if (remaining <= 1) return 1.0;
  if (render.renderer != RendererKind::kTrain || render.material.name.empty()) {
    return 1.0 / remaining;  // Eq. 8
  }
  const double r = std::exp(-render.material.decay_per_s * schedule.interval_steps * timestep_s);
  if (!(r < 1.0)) return 1.0 / remaining;  // no decay: Eq. 8's limit
  return (1.0 - r) / (1.0 - std::pow(r, remaining));
}

}  // namespace rigidtouch::contact
