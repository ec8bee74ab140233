#include "bench/harness.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>

#include "loop/reference_job.h"

namespace rigidtouch::bench {
namespace {

using Clock = std::chrono::steady_clock;

std::string Millimetres(double metres) {
  std::ostringstream out;
  out.precision(3);
  out << metres * 1e3 << " mm";
  return out.str();
}

}  // namespace

TimeSummary ConstantWorkProbe(double target_ns, int samples) {
  // sized to the target by the median of 201 runs at each of the calibration's two rounds (so
  // the clock's own cost and the job's start-up are folded in)
  loop::ReferenceJob job;
  const long units = loop::CalibrateUnits(target_ns, 1000, 10'000'000,
                                          [&job](long u) { return job.MedianNs(u, 201); });
  std::vector<std::int64_t> durations(static_cast<std::size_t>(std::max(samples, 1)));
  for (std::int64_t& t : durations) t = job.TimedRunNs(units);
  return Summarize(durations);
}

void MeasureInterleaved(std::span<SceneRun* const> runs, int measurements, int block) {
  if (block < 1)
    throw Error("interleaved measurement: block must be at least 1, got " + std::to_string(block));
  const int n = static_cast<int>(runs.size());
  for (int done = 0, b = 0; done < measurements; done += block, ++b) {
    const int count = std::min(block, measurements - done);
    for (int k = 0; k < n; ++k) {
      SceneRun& run = *runs[static_cast<std::size_t>((b + k) % n)];
      for (int i = 0; i < count; ++i) run.MeasureOne();
    }
  }
}

double StrikeStartHeight(const Vec3& position_m, const Quat& orientation, double half_size_m,
                         double gap_m, double radius_m) {
  // the face normals are the body axes and their opposites; the upward one has the largest |z|
  const Mat3 rotation = orientation.toRotationMatrix();
  const double normal_z = rotation.row(2).cwiseAbs().maxCoeff();
  // the face plane is at distance half-size from the centre along the normal, and the sphere's
  // centre at gap + radius from the plane: both distances grow by 1 / n_z along the vertical
  return position_m.z() + (half_size_m + gap_m + radius_m) / normal_z;
}

SceneRun::SceneRun(Engine& engine, const Scene& scene) : engine_(engine), scene_(scene) {}

double LimitOvershoot(double q, double lo, double hi) {
  if (!std::isfinite(q)) return std::numeric_limits<double>::infinity();
  return std::max({0.0, lo - q, q - hi});
}

void SceneRun::Track() {
  if (!engine_.StateIsFinite()) gates_.finite = false;
  const double penetration_m = engine_.DeepestPenetration_m();
  gates_.deepest_penetration_m = std::max(gates_.deepest_penetration_m, penetration_m);
  ++gates_.steps;
  if (!(penetration_m < scene_.max_penetration_m)) ++gates_.steps_over_penetration;
  if (past_warmup_) TrackArticulated();
}

void SceneRun::TrackArticulated() {
  const bool tool_gate = std::isfinite(scene_.max_tool_penetration_m);
  const bool limit_gate = !scene_.limit_joint.empty();
  if (!tool_gate && !limit_gate) return;
  ++gates_.gated_steps;
  if (tool_gate) {
    const double depth_m = engine_.BodyPenetration_m(scene_.tool_body);
    gates_.deepest_tool_penetration_m =
        std::max(gates_.deepest_tool_penetration_m, std::isfinite(depth_m) ? depth_m : 1e300);
    if (!(depth_m < scene_.max_tool_penetration_m)) ++gates_.steps_over_tool_penetration;
  }
  if (limit_gate) {
    const double over =
        LimitOvershoot(engine_.JointPosition(scene_.limit_joint), scene_.limit_lo, scene_.limit_hi);
    gates_.largest_limit_overshoot =
        std::max(gates_.largest_limit_overshoot, std::isfinite(over) ? over : 1e300);
    if (!(over < scene_.max_limit_overshoot)) ++gates_.steps_over_limit;
  }
}

void SceneRun::Prepare() {
  engine_.Load(scene_);
  past_warmup_ = false;
  durations_ns_.clear();
  durations_ns_.reserve(static_cast<std::size_t>(scene_.measured_steps));
  for (int i = 0; i < scene_.warmup_steps; ++i) {
    engine_.Step();
    Track();
  }
  engine_.SaveSnapshot();
  past_warmup_ = true;
  if (!scene_.watch_body.empty()) {
    const Vec3 start_m = engine_.BodyPosition(scene_.watch_body);
    double largest_m = 0.0;
    for (int i = 0; i < scene_.watch_steps; ++i) {
      engine_.Step();
      Track();
      largest_m = std::max(largest_m, (engine_.BodyPosition(scene_.watch_body) - start_m).norm());
    }
    gates_.watch_displacement_m = std::isfinite(largest_m) ? largest_m : 1e300;
    engine_.RestoreSnapshot();
  }
  step_in_batch_ = 0;
}

std::int64_t SceneRun::TimedStep() {
  const auto start = Clock::now();
  engine_.Step();
  const auto stop = Clock::now();
  return std::chrono::duration_cast<std::chrono::nanoseconds>(stop - start).count();
}

std::int64_t SceneRun::MeasureSteady() {
  if (step_in_batch_ == scene_.batch_steps) {
    engine_.RestoreSnapshot();
    step_in_batch_ = 0;
  }
  ++step_in_batch_;
  const std::int64_t duration_ns = TimedStep();
  Track();
  contact_sum_ += engine_.ContactCount();
  durations_ns_.push_back(duration_ns);
  return duration_ns;
}

std::int64_t SceneRun::MeasureStrike() {
  engine_.RestoreSnapshot();
  const Vec3 target_m = engine_.BodyPosition(scene_.strike_target);
  const Vec3 tool_m(target_m.x(), target_m.y(),
                    StrikeStartHeight(target_m, engine_.BodyOrientation(scene_.strike_target),
                                      scene_.strike_target_half_size_m, scene_.strike_gap_m,
                                      scene_.tool_radius_m));
  engine_.SetBodyMotion(scene_.tool_body, tool_m, Vec3(0.0, 0.0, -scene_.strike_speed_mps));
  // every approach step is timed the same way; only the first one with tool contact counts
  for (int step = 1; step <= scene_.strike_max_steps; ++step) {
    const std::int64_t duration_ns = TimedStep();
    Track();
    if (engine_.BodyContactCount(scene_.tool_body) > 0) {
      last_strike_steps_ = step;
      contact_sum_ += engine_.ContactCount();
      durations_ns_.push_back(duration_ns);
      return duration_ns;
    }
  }
  last_strike_steps_ = scene_.strike_max_steps;
  ++gates_.strikes_missed;
  return -1;
}

std::int64_t SceneRun::MeasureOne() {
  if (durations_ns_.size() >= static_cast<std::size_t>(scene_.measured_steps)) {
    throw Error("scene " + scene_.name + ": more than measured_steps = " +
                std::to_string(scene_.measured_steps) + " measurements requested");
  }
  return scene_.kind == SceneKind::kStrike ? MeasureStrike() : MeasureSteady();
}

RunResult SceneRun::Finish() {
  RunResult result;
  result.scene = scene_.name;
  result.engine = std::string(engine_.Name());
  result.configuration = engine_.Configuration();
  result.mean_contacts =
      durations_ns_.empty() ? 0.0 : contact_sum_ / static_cast<double>(durations_ns_.size());
  result.durations_ns = durations_ns_;
  std::vector<std::int64_t> sorted_ns = durations_ns_;
  result.time = Summarize(sorted_ns);

  gates_.warnings = engine_.WarningCount();
  gates_.failures.clear();
  if (!gates_.finite) gates_.failures.push_back("a position or velocity became NaN or infinite");
  if (gates_.warnings > 0) {
    gates_.failures.push_back("the engine raised " + std::to_string(gates_.warnings) + " warnings");
  }
  if (gates_.watch_displacement_m >= 0 &&
      !(gates_.watch_displacement_m < scene_.max_watch_displacement_m)) {
    gates_.failures.push_back(scene_.watch_body + " moved " +
                              Millimetres(gates_.watch_displacement_m) + " over " +
                              std::to_string(scene_.watch_steps) + " steps (limit " +
                              Millimetres(scene_.max_watch_displacement_m) + ")");
  }
  if (!(gates_.deepest_penetration_m < scene_.max_penetration_m)) {
    gates_.failures.push_back("deepest penetration " + Millimetres(gates_.deepest_penetration_m) +
                              " (limit " + Millimetres(scene_.max_penetration_m) + "), over the " +
                              "limit in " + std::to_string(gates_.steps_over_penetration) + " of " +
                              std::to_string(gates_.steps) + " steps");
  }
  if (gates_.steps_over_tool_penetration > 0) {
    gates_.failures.push_back("deepest tool penetration " +
                              Millimetres(gates_.deepest_tool_penetration_m) + " (limit " +
                              Millimetres(scene_.max_tool_penetration_m) + "), over the limit in " +
                              std::to_string(gates_.steps_over_tool_penetration) + " of " +
                              std::to_string(gates_.gated_steps) + " steps after the warm-up");
  }
  if (gates_.steps_over_limit > 0) {
    std::ostringstream text;
    text.precision(3);
    text << "joint " << scene_.limit_joint << " passed its range [" << scene_.limit_lo << ", "
         << scene_.limit_hi << "] by up to " << gates_.largest_limit_overshoot << " (limit "
         << scene_.max_limit_overshoot << "), in " << gates_.steps_over_limit << " of "
         << gates_.gated_steps << " steps after the warm-up";
    gates_.failures.push_back(text.str());
  }
  if (gates_.strikes_missed > 0) {
    gates_.failures.push_back(std::to_string(gates_.strikes_missed) +
                              " strikes reached no contact within " +
                              std::to_string(scene_.strike_max_steps) + " steps");
  }
  result.gates = gates_;
  return result;
}

}  // namespace rigidtouch::bench
