// A run whose state went non-finite is an error of `simulate` and `tap` (issue 16): the tick's
// guard puts the state back to the initial one and counts Warning::kNonFiniteState, so the run
// completes and its results are printed, then the command names what happened on stderr and
// exits with status 2 (bad input: the scene or its parameters cannot be simulated stably).
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "rigidtouch/types.h"

namespace rigidtouch::cli {

/// When the state first (or, where only that is known, last) went non-finite in a run.
struct NonFiniteReport {
  int count = 0;           // ticks whose state went non-finite (each reset to the initial state)
  std::int64_t step = -1;  // the step of the first of them (of the last when `first` is false)
  double time_s = 0.0;     // the simulated time at that step [s]
  bool first = true;
};

/// The error message: how often, when, what went non-finite, what the run did and what to try.
inline std::string NonFiniteMessage(const NonFiniteReport& r) {
  std::ostringstream m;
  m << "the simulated state became non-finite (a body's position, velocity or orientation was "
       "NaN or infinite) in "
    << r.count << (r.count == 1 ? " step" : " steps") << ", " << (r.first ? "first" : "last")
    << " at step " << r.step << " (t = " << r.time_s
    << " s); each time the state was reset to the initial one, so the results after it are not "
       "a continuous run. The scene cannot be simulated stably with these parameters: try a "
       "smaller time step, heavier bodies or a lower contact stiffness";
  return m.str();
}

/// The JSON member "non_finite_state" of a run: null if the state stayed finite.
inline nlohmann::json NonFiniteJson(const NonFiniteReport& r) {
  if (r.count == 0) return nullptr;
  return {{"count", r.count},
          {r.first ? "first_step" : "last_step", r.step},
          {r.first ? "first_time_s" : "last_time_s", r.time_s},
          {"error", NonFiniteMessage(r)}};
}

/// Throws Error (exit status 2) with NonFiniteMessage if the state went non-finite.
inline void ThrowIfNonFinite(const NonFiniteReport& r) {
  if (r.count > 0) throw Error(NonFiniteMessage(r));
}

}  // namespace rigidtouch::cli
