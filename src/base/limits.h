// The collision-rendering method's limits, in one place: Configure enforces them on a model and
// the study protocol checks its walls against them, so a protocol cannot accept a wall the engine
// would refuse (or the other way round). Also how two device limits combine.
#pragma once

namespace rigidtouch::limits {

/// Longest collision-rendering window t_c: shorter than human reaction time (II.a).
inline constexpr double kMaxCollisionWindow_s = 0.1;

/// Restitution e lies in [0, 1] (Eq. 4).
inline constexpr double kMinRestitution = 0.0;
inline constexpr double kMaxRestitution = 1.0;

/// The only restitution a train allows: perfectly plastic collisions (Eq. 8).
inline constexpr double kTrainRestitution = 0.0;

/// Relative tolerance of f >= 1 / t_c (at least one impulse in the window, Eq. 6-7), so that e.g.
/// t_c = 0.1 s, f = 10 Hz is accepted despite rounding.
inline constexpr double kTrainFrequencyTolerance = 1e-9;

/// Whether a train of `frequency_hz` holds at least one impulse in a window of `t_collision_s`.
/// The upper bound f <= 1/h depends on the time step and is checked with the schedule.
constexpr bool TrainFrequencyFitsWindow(double frequency_hz, double t_collision_s) {
  return frequency_hz > 0.0 && frequency_hz * t_collision_s >= 1.0 - kTrainFrequencyTolerance;
}

/// Haptic rates the command-line tool takes (tap, serve, device-sim): one range for every
/// subcommand, from the slowest loop that still renders contact to the fastest a desktop device
/// and this host's scheduler keep up with.
inline constexpr double kMinRate_hz = 100.0;
inline constexpr double kMaxRate_hz = 20000.0;

/// Time step h in [kMinTimestep_s, kMaxTimestep_s].
inline constexpr double kMinTimestep_s = 1e-6;
inline constexpr double kMaxTimestep_s = 0.1;

/// The stricter of two device limits where 0 (or less) means unknown or unlimited: the smaller
/// positive one, 0 when neither is set.
constexpr double StricterLimit(double a, double b) {
  if (!(a > 0.0)) return b > 0.0 ? b : 0.0;
  if (!(b > 0.0)) return a;
  return a < b ? a : b;
}

}  // namespace rigidtouch::limits
