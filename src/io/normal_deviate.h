// The one normal-deviate formula of rigidtouch, shared by the simulated device's speed spread and
// the study's random numbers. Each keeps its own uniform source (mt19937_64 there, SplitMix64
// here), so their streams stay as they were; only the transform is common.
#pragma once

#include <cmath>
#include <numbers>

namespace rigidtouch::io {

/// Box-Muller: a standard normal deviate from two independent uniforms, `u1` in (0, 1] (so that
/// the log is finite) and `u2` in [0, 1). Callers draw u1 before u2 in a separate statement: the
/// order of function arguments is unspecified, and the order of draws is part of a stream.
inline double BoxMuller(double u1, double u2) {
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
}

}  // namespace rigidtouch::io
