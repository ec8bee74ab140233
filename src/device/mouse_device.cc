#include "device/mouse_device.h"

#include <cmath>
#include <numbers>
#include <string>

namespace rigidtouch::device {
namespace {

void CheckPositive(double v, const char* name) {
  if (!(std::isfinite(v) && v > 0.0)) {
    throw Error(std::string("mouse device: ") + name + " = " + std::to_string(v) +
                " is outside (0, inf)");
  }
}

}  // namespace

MouseDevice::MouseDevice(const DeviceLimits& limits, const MouseDeviceParams& params,
                         const Vec3& start_m)
    : limits_(limits), params_(params), x_m_(start_m), sampled_m_(start_m) {
  CheckPositive(params.follow_time_constant_s, "follow_time_constant_s");
  CheckPositive(params.sensing.velocity_cutoff_hz, "velocity_cutoff_hz");
  CheckPositive(params.tap_speed_mps, "tap_speed_mps");
  CheckPositive(params.tap_depth_m, "tap_depth_m");
  CheckPositive(params.tap_retract_speed_mps, "tap_retract_speed_mps");
  if (!(params.tap_dwell_s >= 0.0) || !std::isfinite(params.tap_dwell_s)) {
    throw Error("mouse device: tap_dwell_s is outside [0, inf)");
  }
  if (!start_m.allFinite()) throw Error("mouse device: the start position is not finite");
  for (int i = 0; i < 3; ++i) target_[i].store(start_m[i], std::memory_order_relaxed);
}

void MouseDevice::SetTarget(const Vec3& target_m) noexcept {
  if (!target_m.allFinite()) return;
  for (int i = 0; i < 3; ++i) target_[i].store(target_m[i], std::memory_order_relaxed);
}

DeviceState MouseDevice::Read() {
  DeviceState s;
  s.sequence = sequence_;
  s.time_s = time_s_;
  s.position_m = sampled_m_;
  s.velocity_mps = velocity_mps_;
  return s;
}

void MouseDevice::EndPeriod(double period_s) {
  if (!(period_s > 0.0) || !std::isfinite(period_s)) return;
  time_s_ += period_s;
  if (!tapping_ && tap_requested_.exchange(false, std::memory_order_acq_rel)) {
    tapping_ = true;
    ++taps_;
    tap_start_m_ = x_m_;
    tap_t_s_ = 0.0;
  }
  if (tapping_) {
    // position-controlled tap: down at the tap speed, dwell, back up (the hand's intended path)
    tap_t_s_ += period_s;
    const double down_s = params_.tap_depth_m / params_.tap_speed_mps;
    const double up_s = params_.tap_depth_m / params_.tap_retract_speed_mps;
    double depth = 0.0;
    if (tap_t_s_ < down_s) {
      depth = params_.tap_speed_mps * tap_t_s_;
    } else if (tap_t_s_ < down_s + params_.tap_dwell_s) {
      depth = params_.tap_depth_m;
    } else if (tap_t_s_ < down_s + params_.tap_dwell_s + up_s) {
      depth = params_.tap_depth_m -
              params_.tap_retract_speed_mps * (tap_t_s_ - down_s - params_.tap_dwell_s);
    } else {
      tapping_ = false;
      for (int i = 0; i < 3; ++i) target_[i].store(tap_start_m_[i], std::memory_order_relaxed);
    }
    x_m_ = tap_start_m_ - depth * Vec3::UnitZ();
  } else {
    Vec3 target;
    for (int i = 0; i < 3; ++i) target[i] = target_[i].load(std::memory_order_relaxed);
    // first-order follower, exact for a target held over the period
    const double a = 1.0 - std::exp(-period_s / params_.follow_time_constant_s);
    x_m_ += a * (target - x_m_);
  }
  // encoder: quantized position; velocity: finite difference through a first-order low-pass
  Vec3 q = x_m_;
  const double res = params_.sensing.encoder_resolution_m;
  if (res > 0.0) {
    for (int i = 0; i < 3; ++i) q[i] = res * std::round(q[i] / res);
  }
  const Vec3 raw = (q - sampled_m_) / period_s;
  const double wc = 2.0 * std::numbers::pi * params_.sensing.velocity_cutoff_hz;
  const double alpha = 1.0 - std::exp(-wc * period_s);
  velocity_mps_ += alpha * (raw - velocity_mps_);
  sampled_m_ = q;
  ++sequence_;
}

}  // namespace rigidtouch::device
