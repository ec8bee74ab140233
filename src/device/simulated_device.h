// A simulated hand gripping a simulated haptic device, driven through the same Device interface
// as a real one. The hand taps a wall following a script; the device samples an encoder, estimates
// velocity like a real device and displays the commanded force with a zero-order hold.
//
// Plant (world frame W, 3-D, gravity on the handle compensated by default):
//
//   (m_device + m_hand) a = F_cmd + K (x_int - x) + B (v_int - v) [+ (m_device + m_hand) a_int]
//
// x_int(t) is the scripted intended motion of the hand (equilibrium trajectory); K, B are the
// arm's stiffness and damping; the bracketed inertia feedforward is optional (HandParams).
#pragma once

#include <cstdint>
#include <vector>

#include "rigidtouch/device.h"
#include "rigidtouch/types.h"

namespace rigidtouch::device {

/// Mechanical impedance of the user's arm and hand holding the handle.
struct HandParams {
  /// Effective arm mass [kg]; van Beek et al., Sci. Rep. 2015 (arm impedance identification).
  double mass_kg = 0.554;
  /// Arm damping [N s/m]; van Beek et al., Sci. Rep. 2015.
  double damping_Ns_per_m = 6.45;
  /// Arm stiffness [N/m]; van Beek et al., Sci. Rep. 2015.
  double stiffness_N_per_m = 135.0;
  /// When true the hand adds (m_device + m_hand) a_int, an internal model of the inertia it
  /// moves, so it reaches the scripted speed within the velocity ramp instead of lagging behind
  /// the equilibrium trajectory for several time constants (2 M / B, about 0.18 s here).
  /// Assumption (the CNS adapts to a known load, Shadmehr & Mussa-Ivaldi, J. Neurosci. 1994);
  /// false gives the pure equilibrium-trajectory plant.
  bool inertia_feedforward = true;
};

/// Model of the device itself: inertia, sensing and the simulation of its continuous plant.
struct DeviceModelParams {
  /// Apparent mass of the end effector at the handle [kg]; 45 g is SensAble's PHANToM Omni
  /// specification ("apparent mass at tip").
  double apparent_mass_kg = 0.045;
  /// Encoder position resolution [m], per axis; 0 disables quantization. 0.055 mm is the nominal
  /// resolution of the PHANToM Omni / Touch (> 450 dpi) in their specifications.
  double encoder_resolution_m = 0.055e-3;
  /// Cutoff of the first-order low-pass filter on the finite-difference velocity [Hz].
  /// Assumption: 100 Hz, well above the human action band (about 10 Hz) and below the tick rate.
  double velocity_cutoff_hz = 100.0;
  /// 0: Read returns the latest sample; 1: Read returns the sample of the previous tick.
  int delay_ticks = 0;
  /// Plant integration sub-steps per haptic tick (RK4 each), at least 10.
  int substeps = 10;
  /// Nominal haptic tick rate [Hz], in [100, 100000]; Advance may be called with other steps.
  double tick_rate_hz = 1000.0;
  /// When false, gravity acts on the device's apparent mass (the hand's own weight is carried by
  /// the arm). Default true: commercial devices compensate gravity in firmware or by counterweight.
  bool gravity_compensated = true;
  /// Gravity [m/s^2] in the world frame, used only when gravity_compensated is false.
  Vec3 gravity_mps2 = Vec3(0.0, 0.0, -9.81);
};

/// The taps the hand performs. Each tap: the intended position starts at the start height above
/// the surface, moves along -normal at the approach speed to the aim point (aim depth behind the
/// surface) and stops there abruptly (the user plans to hit the wall, not to stop before it),
/// dwells, retracts along +normal at the retract speed back to the start height, then pauses.
/// Speed changes other than the approach's end follow a raised-cosine ramp of velocity_ramp_s.
/// The run starts with a pause, so every tap starts from rest.
struct TapScript {
  /// A point on the wall's surface, world frame [m].
  Vec3 surface_point_m = Vec3::Zero();
  /// Outward normal of the wall, world frame (normalized on construction; must be non-zero).
  Vec3 surface_normal = Vec3::UnitZ();
  /// Height of the start point above the surface [m], in (0, 0.5]. Assumption: 2 cm, inside the
  /// workspace of every preset's device.
  double start_height_m = 0.02;
  /// Approach speed [m/s], in (0, 2]. Assumption: 0.2 m/s, a moderate tap.
  double approach_speed_mps = 0.2;
  /// Depth of the aim point behind the surface [m], in [0, 0.1]. Assumption: 5 mm.
  double aim_depth_m = 0.005;
  /// Time the intended position stays at the aim point [s], in [0, 10]. Assumption: 0.2 s.
  double dwell_s = 0.2;
  /// Retract speed [m/s], in (0, 2]. Assumption: 0.1 m/s.
  double retract_speed_mps = 0.1;
  /// Pause at the start point before each tap and after the last one [s], in [0, 10].
  /// Assumption: 0.3 s.
  double pause_s = 0.3;
  /// Number of taps, in [1, 10000].
  int taps = 3;
  /// Relative standard deviation of the approach speed between taps, in [0, 0.5]; each tap's
  /// speed is v (1 + spread z), z standard normal, clamped to [v / 4, 2 m/s].
  double speed_spread = 0.0;
  /// Seed of the speed spread (mt19937_64 and Box-Muller, identical on every platform).
  std::uint64_t seed = 1;
  /// Duration of a raised-cosine velocity ramp [s], in [0, 0.5]; 0 gives velocity steps.
  /// Assumption: 50 ms.
  double velocity_ramp_s = 0.05;
};

/// Timing of one scripted tap, in seconds from the start of the run.
struct TapTiming {
  double start_s = 0.0;         // the approach starts (current_tap() becomes this tap)
  double approach_end_s = 0.0;  // the intended position reaches the aim point
  double dwell_end_s = 0.0;     // the retract starts
  double retract_end_s = 0.0;   // back at the start height (current_tap() becomes -1)
  double approach_speed_mps = 0.0;
};

/// A simulated hand + device. Read, Write and Advance never allocate or throw; the constructor
/// validates every parameter and throws rigidtouch::Error naming the field and its range.
///
/// One haptic tick, as loop::RunHapticLoop and the offline tap experiment drive it:
///   s = dev.Read(); cmd = Tick(model, data, s); dev.Write(cmd); dev.EndPeriod(h);
class SimulatedDevice : public Device {
 public:
  /// Builds the device at rest at the script's start point, t = 0.
  SimulatedDevice(const DeviceLimits& limits, const HandParams& hand,
                  const DeviceModelParams& model, const TapScript& script);

  /// The latest encoder sample (or the previous tick's, with delay_ticks = 1): quantized
  /// position, filtered finite-difference velocity and the sample's time stamp.
  DeviceState Read() override;
  /// Stores the force to display during the following Advance calls (zero-order hold). The
  /// force is clipped to limits().max_force_N (if > 0) keeping its direction; a non-finite
  /// force is counted as an error and replaced by zero. Torque is ignored (3-DOF device).
  void Write(const DeviceCommand& command) override;
  /// Display limits of this device.
  const DeviceLimits& limits() const override { return limits_; }
  /// Advances the plant by the loop's period: the device lives in loop time.
  void EndPeriod(double period_s) override { Advance(period_s); }
  /// Sets the sample's tap index and the hand's force at the current time.
  void AnnotateTrace(TraceSample& sample) const override {
    sample.tap = current_tap();
    sample.hand_force_N = hand_force_N_;
  }

  /// Integrates the hand + device plant over dt_s with `substeps` RK4 steps, the displayed force
  /// held constant, then samples the encoder. A non-finite or non-positive dt_s is counted as
  /// an error and ignored.
  void Advance(double dt_s);

  /// Force the hand applies to the hand + handle mass at the current time (impedance plus
  /// feedforward), world frame [N].
  const Vec3& hand_force_N() const { return hand_force_N_; }
  /// Force at the grip, on the handle alone: hand_force_N() - m_hand a [N].
  const Vec3& grip_force_N() const { return grip_force_N_; }
  /// True position of the handle [m].
  const Vec3& true_position_m() const { return x_m_; }
  /// True velocity of the handle [m/s].
  const Vec3& true_velocity_mps() const { return v_mps_; }
  /// Scripted intended position of the hand at the current time [m].
  Vec3 intended_position_m() const;
  /// The force displayed since the last Write, after clipping [N].
  const Vec3& displayed_force_N() const { return displayed_force_N_; }
  /// Whether the last Write was clipped by the force limit.
  bool last_command_clipped() const { return last_clipped_; }
  /// Number of Write calls whose force was clipped.
  std::int64_t clipped_count() const { return clipped_count_; }
  /// Number of rejected inputs (non-finite force, bad dt_s).
  std::int64_t error_count() const { return error_count_; }
  /// Time since the start of the run [s].
  double time_s() const { return time_s_; }
  /// Index of the tap in progress, -1 during pauses and after the last tap.
  int current_tap() const;
  /// True once the last tap and its final pause are over.
  bool finished() const { return time_s_ >= end_s_; }
  /// Timing of every scripted tap.
  const std::vector<TapTiming>& tap_timings() const { return taps_; }
  /// Duration of the whole script [s].
  double duration_s() const { return end_s_; }
  /// Nominal tick [s] = 1 / tick_rate_hz.
  double tick_s() const { return 1.0 / model_.tick_rate_hz; }

  /// Energy the device port delivered to the user since the start [J]: the sum over Advance
  /// calls of F_displayed . (x_end - x_start), exact for a force held over the step. Positive
  /// means energy flowed from the device into the hand; a passive renderer keeps it <= 0 over
  /// whole taps (which start and end out of contact).
  double energy_to_user_J() const { return energy_to_user_J_; }

 private:
  struct Intended {
    Vec3 position_m;
    Vec3 velocity_mps;
    Vec3 acceleration_mps2;
  };
  struct Sample {
    std::uint64_t sequence = 0;
    double time_s = 0.0;
    Vec3 position_m = Vec3::Zero();
    Vec3 velocity_mps = Vec3::Zero();
  };

  // intended motion at time t; `cursor` is a tap index hint that only moves forward
  Intended IntendedAt(double t_s, int& cursor) const;
  // force on the hand + handle mass from the hand (impedance and feedforward) at a state
  Vec3 HandForce(const Intended& in, const Vec3& x_m, const Vec3& v_mps) const;
  Vec3 Acceleration(const Intended& in, const Vec3& x_m, const Vec3& v_mps) const;
  Vec3 Quantize(const Vec3& x_m) const;

  // configuration, fixed after construction
  DeviceLimits limits_;
  HandParams hand_;
  DeviceModelParams model_;
  TapScript script_;
  Vec3 normal_ = Vec3::UnitZ();
  Vec3 start_point_m_ = Vec3::Zero();
  double total_mass_kg_ = 0.0;
  double travel_m_ = 0.0;  // start height + aim depth
  std::vector<TapTiming> taps_;
  double end_s_ = 0.0;
  double nominal_alpha_ = 1.0;  // low-pass coefficient at the nominal tick

  // plant state
  double time_s_ = 0.0;
  Vec3 x_m_ = Vec3::Zero();
  Vec3 v_mps_ = Vec3::Zero();
  int cursor_ = 0;

  // actuator
  Vec3 displayed_force_N_ = Vec3::Zero();
  bool last_clipped_ = false;

  // sensing
  Sample latest_;
  Sample previous_;
  Vec3 last_quantized_m_ = Vec3::Zero();

  // outputs and counters
  Vec3 hand_force_N_ = Vec3::Zero();
  Vec3 grip_force_N_ = Vec3::Zero();
  double energy_to_user_J_ = 0.0;
  std::int64_t clipped_count_ = 0;
  std::int64_t error_count_ = 0;
};

}  // namespace rigidtouch::device
