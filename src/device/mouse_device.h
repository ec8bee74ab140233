// A device driven by the mouse (`view --device mouse`): the viewer sets where the handle should go
// (the view plane from the cursor, depth from the wheel) and the handle follows it as a light
// handle held by a hand would, sampled as a real device's encoders are: quantized position and a
// low-pass filtered finite-difference velocity (the simulated device's model and parameters). A
// key starts a scripted tap from where the tool is, straight down along -z. A mouse displays no
// force: commands are kept for display only.
#pragma once

#include <atomic>
#include <cstdint>

#include "device/simulated_device.h"
#include "rigidtouch/device.h"

namespace rigidtouch::device {

/// Parameters of the mouse-driven handle.
struct MouseDeviceParams {
  /// Time constant with which the handle follows the cursor's target [s]; the cursor moves in
  /// display-rate steps (60 Hz), the handle continuously. Assumption: 20 ms.
  double follow_time_constant_s = 0.02;
  /// Encoder resolution and velocity filter, as on the simulated device.
  DeviceModelParams sensing;
  /// The tap the key starts: speed down and depth below the start [m/s, m], dwell [s] and speed
  /// back up [m/s]. Assumptions: 0.2 m/s, 3 cm, 0.1 s, 0.1 m/s.
  double tap_speed_mps = 0.2;
  double tap_depth_m = 0.03;
  double tap_dwell_s = 0.1;
  double tap_retract_speed_mps = 0.1;
};

/// A Device whose handle follows a target set from another thread (the viewer's). Read, Write and
/// EndPeriod never allocate, lock or throw; SetTarget and RequestTap are lock-free.
class MouseDevice : public Device {
 public:
  /// Starts at rest at `start_m`. Throws Error naming a parameter out of range.
  MouseDevice(const DeviceLimits& limits, const MouseDeviceParams& params, const Vec3& start_m);

  DeviceState Read() override;
  void Write(const DeviceCommand& command) override { commanded_force_N_ = command.force_N; }
  const DeviceLimits& limits() const override { return limits_; }
  /// Moves the handle towards the target (or along the tap) by one period and samples it.
  void EndPeriod(double period_s) override;
  /// The tap in progress (counting from 0), -1 outside a tap.
  void AnnotateTrace(TraceSample& sample) const override { sample.tap = tapping_ ? taps_ : -1; }

  /// Any thread: where the handle should go [m]. Ignored during a tap.
  void SetTarget(const Vec3& target_m) noexcept;
  /// Any thread: starts a tap from where the handle is (ignored while one runs).
  void RequestTap() noexcept { tap_requested_.store(true, std::memory_order_release); }
  /// Loop thread: the handle's true position [m].
  const Vec3& position_m() const { return x_m_; }
  const Vec3& commanded_force_N() const { return commanded_force_N_; }

 private:
  DeviceLimits limits_;
  MouseDeviceParams params_;
  std::atomic<double> target_[3];
  static_assert(std::atomic<double>::is_always_lock_free);
  std::atomic<bool> tap_requested_{false};
  Vec3 x_m_ = Vec3::Zero();           // true handle position
  Vec3 sampled_m_ = Vec3::Zero();     // last encoder reading
  Vec3 velocity_mps_ = Vec3::Zero();  // filtered estimate
  std::uint64_t sequence_ = 0;
  double time_s_ = 0.0;
  bool tapping_ = false;
  int taps_ = -1;  // index of the current or last tap
  Vec3 tap_start_m_ = Vec3::Zero();
  double tap_t_s_ = 0.0;
  Vec3 commanded_force_N_ = Vec3::Zero();
};

}  // namespace rigidtouch::device
