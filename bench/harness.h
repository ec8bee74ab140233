// Runs one engine on one scene the same way for every engine: load, warm up, check the quality
// gates, snapshot, then measure steps (or strikes) one at a time with a steady clock.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "bench/engine.h"
#include "bench/scene.h"
#include "bench/stats.h"

namespace rigidtouch::bench {

/// What the quality gates saw; a run whose gates fail is reported, loudly, as not comparable.
struct GateReport {
  bool finite = true;                     ///< no NaN or infinity in any position or velocity
  long warnings = 0;                      ///< engine warnings (e.g. MuJoCo's full contact buffer)
  double deepest_penetration_m = 0;       ///< over every step run
  long steps = 0;                         ///< every step run (warm-up, gates, measurement)
  long steps_over_penetration = 0;        ///< steps whose deepest penetration broke the limit
  double watch_displacement_m = -1;       ///< the watched body's largest displacement; -1: no gate
  long strikes_missed = 0;                ///< strikes without tool contact in `strike_max_steps`
  double deepest_tool_penetration_m = 0;  ///< over the steps after the warm-up
  long steps_over_tool_penetration = 0;   ///< of them, steps over Scene::max_tool_penetration_m
  double largest_limit_overshoot = 0;     ///< Scene::limit_joint beyond its range, after warm-up
  long steps_over_limit = 0;              ///< of them, steps over Scene::max_limit_overshoot
  long gated_steps = 0;                   ///< steps after the warm-up (the two gates above)
  std::vector<std::string> failures;      ///< one sentence per failed gate, with the measured value

  /// Returns true when every gate passed.
  bool ok() const { return failures.empty(); }
};

/// The outcome of one engine on one scene.
struct RunResult {
  std::string scene;
  std::string engine;
  TimeSummary time;                        ///< per measured step
  std::vector<std::int64_t> durations_ns;  ///< every measured step, in measurement order
  double mean_contacts = 0.0;              ///< contact points per measured step
  GateReport gates;
  std::string configuration;  ///< Engine::Configuration() of the run
};

/// One engine on one scene. Prepare() once, MeasureOne() as often as the scene says (at most
/// `scene.measured_steps` times: the duration buffer is preallocated), then Finish().
class SceneRun {
 public:
  /// Keeps references: `engine` and `scene` must outlive the run.
  SceneRun(Engine& engine, const Scene& scene);

  /// Loads the scene, warms up, runs the watch gate from the snapshot and restores it. Throws
  /// `rigidtouch::Error` when the scene does not load.
  void Prepare();

  /// Measures one step of the settled scene (restoring the snapshot at each batch start), or
  /// one strike: restore, place the tool, step until its first contact and time that step.
  /// Returns the measured duration in nanoseconds (-1 when a strike found no contact).
  std::int64_t MeasureOne();

  /// Summarises the measured durations and evaluates the gates.
  RunResult Finish();

  /// Returns the durations measured so far, in nanoseconds, in measurement order.
  const std::vector<std::int64_t>& durations_ns() const { return durations_ns_; }

  /// Returns the number of steps the last strike took, the measured one included.
  int last_strike_steps() const { return last_strike_steps_; }

 private:
  void Track();             // gate bookkeeping after every step, outside the timed region
  void TrackArticulated();  // the tool-contact and joint-limit gates, after the warm-up
  std::int64_t TimedStep();
  std::int64_t MeasureSteady();
  std::int64_t MeasureStrike();

  Engine& engine_;
  const Scene& scene_;
  std::vector<std::int64_t> durations_ns_;
  GateReport gates_;
  double contact_sum_ = 0.0;
  int step_in_batch_ = 0;
  int last_strike_steps_ = 0;
  bool past_warmup_ = false;
};

/// Returns how far `q` lies outside [lo, hi] (0 inside).
double LimitOvershoot(double q, double lo, double hi);

/// Measures several prepared runs of one scene in interleaved blocks: `block` measurements of the
/// first run, then of the next, and so on, the runs' order rotating by one from block to block,
/// until each run has `measurements`. Every engine then sees the same stretches of a shared
/// machine's changing speed (slow and fast periods of seconds, 1.2-1.6 times apart on the
/// development machine), so their ratios do not depend on which engine ran in a slow period. Throws
/// `Error` when `block` < 1.
void MeasureInterleaved(std::span<SceneRun* const> runs, int measurements, int block);

/// Times a constant-work job (loop::ReferenceJob: a dependent floating-point chain over a buffer
/// in the first-level cache) calibrated to take about `target_ns`, `samples` times, exactly as
/// steps are timed: what the machine alone (preemption, interrupts, a virtual machine's steal)
/// does to a step of that length. Its p99.9 / median is the floor under any engine's at that step
/// time.
TimeSummary ConstantWorkProbe(double target_ns, int samples);

/// Returns the height (world z) at which to place the centre of a sphere of radius `radius_m`
/// straight above the centre of a cube (half-size `half_size_m`, centre `position_m`, orientation
/// `orientation`) so that the gap between the sphere and the cube's upward face, measured along
/// that face's normal, is `gap_m`. The upward face is the one whose normal has the largest z.
double StrikeStartHeight(const Vec3& position_m, const Quat& orientation, double half_size_m,
                         double gap_m, double radius_m);

}  // namespace rigidtouch::bench
