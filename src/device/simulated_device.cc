#include "device/simulated_device.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <sstream>
#include <string>

#include "io/normal_deviate.h"
#include "render/output.h"

namespace rigidtouch::device {

namespace {

// throws unless lo (<|<=) value (<|<=) hi; NaN always fails
void CheckHandRange(const char* field, double value, double lo, double hi, bool lo_open,
                    bool hi_open, const char* unit) {
  const bool above = lo_open ? value > lo : value >= lo;
  const bool below = hi_open ? value < hi : value <= hi;
  if (above && below) return;
  std::ostringstream message;
  message << "simulated device: " << field << " = " << value << " " << unit
          << " is out of range; valid: " << (lo_open ? "(" : "[") << lo << ", " << hi
          << (hi_open ? ")" : "]") << " " << unit;
  throw Error(message.str());
}

void CheckFinite(const char* field, const Vec3& value) {
  if (value.allFinite()) return;
  std::ostringstream message;
  message << "simulated device: " << field << " = (" << value.transpose() << ") must be finite";
  throw Error(message.str());
}

// uniform in (0, 1) from the top 53 bits: same sequence on every platform, unlike
// std::uniform_real_distribution whose algorithm is implementation-defined
double Uniform01(std::mt19937_64& rng) {
  return (static_cast<double>(rng() >> 11) + 0.5) * 0x1.0p-53;
}

double StandardNormal(std::mt19937_64& rng) {
  const double u1 = Uniform01(rng);
  const double u2 = Uniform01(rng);
  return io::BoxMuller(u1, u2);
}

// scalar motion profile: travelled distance, speed, acceleration
struct Profile {
  double s = 0.0;
  double s_dot = 0.0;
  double s_ddot = 0.0;
};

// raised-cosine speed ramp from 0 to v over ramp_s, tau in [0, ramp_s]
Profile RampUp(double tau_s, double v_mps, double ramp_s) {
  const double phase = std::numbers::pi * tau_s / ramp_s;
  return {v_mps * (0.5 * tau_s - ramp_s / (2.0 * std::numbers::pi) * std::sin(phase)),
          0.5 * v_mps * (1.0 - std::cos(phase)),
          v_mps * std::numbers::pi / (2.0 * ramp_s) * std::sin(phase)};
}

// raised-cosine speed ramp from v to 0 over ramp_s, tau in [0, ramp_s]
Profile RampDown(double tau_s, double v_mps, double ramp_s) {
  const double phase = std::numbers::pi * tau_s / ramp_s;
  return {v_mps * (0.5 * tau_s + ramp_s / (2.0 * std::numbers::pi) * std::sin(phase)),
          0.5 * v_mps * (1.0 + std::cos(phase)),
          -v_mps * std::numbers::pi / (2.0 * ramp_s) * std::sin(phase)};
}

}  // namespace

SimulatedDevice::SimulatedDevice(const DeviceLimits& limits, const HandParams& hand,
                                 const DeviceModelParams& model, const TapScript& script)
    : limits_(limits), hand_(hand), model_(model), script_(script) {
  CheckHandRange("limits.max_force_N", limits.max_force_N, 0.0, 1e4, false, false, "N");
  CheckHandRange("limits.max_torque_Nm", limits.max_torque_Nm, 0.0, 1e3, false, false, "N m");
  CheckHandRange("hand.mass_kg", hand.mass_kg, 0.0, 100.0, true, false, "kg");
  CheckHandRange("hand.damping_Ns_per_m", hand.damping_Ns_per_m, 0.0, 1e4, false, false, "N s/m");
  CheckHandRange("hand.stiffness_N_per_m", hand.stiffness_N_per_m, 0.0, 1e6, false, false, "N/m");
  CheckHandRange("device.apparent_mass_kg", model.apparent_mass_kg, 0.0, 100.0, false, false, "kg");
  CheckHandRange("device.encoder_resolution_m", model.encoder_resolution_m, 0.0, 0.01, false, false,
                 "m");
  CheckHandRange("device.tick_rate_hz", model.tick_rate_hz, 100.0, 1e5, false, false, "Hz");
  CheckHandRange("device.velocity_cutoff_hz", model.velocity_cutoff_hz, 0.0, 1e5, true, false,
                 "Hz");
  CheckHandRange("device.delay_ticks", model.delay_ticks, 0, 1, false, false, "ticks");
  CheckHandRange("device.substeps", model.substeps, 10, 10000, false, false, "per tick");
  CheckFinite("device.gravity_mps2", model.gravity_mps2);
  CheckFinite("tap.surface_point_m", script.surface_point_m);
  CheckFinite("tap.surface_normal", script.surface_normal);
  if (!(script.surface_normal.norm() > 1e-9)) {
    throw Error("simulated device: tap.surface_normal must be a non-zero vector");
  }
  CheckHandRange("tap.start_height_m", script.start_height_m, 0.0, 0.5, true, false, "m");
  CheckHandRange("tap.approach_speed_mps", script.approach_speed_mps, 0.0, 2.0, true, false, "m/s");
  CheckHandRange("tap.aim_depth_m", script.aim_depth_m, 0.0, 0.1, false, false, "m");
  CheckHandRange("tap.dwell_s", script.dwell_s, 0.0, 10.0, false, false, "s");
  CheckHandRange("tap.retract_speed_mps", script.retract_speed_mps, 0.0, 2.0, true, false, "m/s");
  CheckHandRange("tap.pause_s", script.pause_s, 0.0, 10.0, false, false, "s");
  CheckHandRange("tap.taps", script.taps, 1, 10000, false, false, "taps");
  CheckHandRange("tap.speed_spread", script.speed_spread, 0.0, 0.5, false, false, "(relative)");
  CheckHandRange("tap.velocity_ramp_s", script.velocity_ramp_s, 0.0, 0.5, false, false, "s");

  normal_ = script.surface_normal.normalized();
  start_point_m_ = script.surface_point_m + script.start_height_m * normal_;
  total_mass_kg_ = model.apparent_mass_kg + hand.mass_kg;
  travel_m_ = script.start_height_m + script.aim_depth_m;
  const double ramp_s = script.velocity_ramp_s;

  // the retract ramps up and down within the travel
  if (script.retract_speed_mps * ramp_s > travel_m_) {
    std::ostringstream message;
    message << "simulated device: tap.retract_speed_mps = " << script.retract_speed_mps
            << " m/s needs " << script.retract_speed_mps * ramp_s
            << " m to ramp up and down over tap.velocity_ramp_s = " << ramp_s
            << " s, more than the travel start_height_m + aim_depth_m = " << travel_m_
            << " m; valid: retract_speed_mps <= " << travel_m_ / std::max(ramp_s, 1e-300) << " m/s";
    throw Error(message.str());
  }

  std::mt19937_64 rng(script.seed);
  taps_.resize(static_cast<std::size_t>(script.taps));
  double t_s = script.pause_s;
  for (TapTiming& tap : taps_) {
    double v_mps = script.approach_speed_mps;
    if (script.speed_spread > 0.0) {
      v_mps *= 1.0 + script.speed_spread * StandardNormal(rng);
      v_mps = std::clamp(v_mps, 0.25 * script.approach_speed_mps, 2.0);
    }
    // the approach ramps up within the travel
    if (0.5 * v_mps * ramp_s > travel_m_) {
      std::ostringstream message;
      message << "simulated device: tap.approach_speed_mps = " << v_mps << " m/s needs "
              << 0.5 * v_mps * ramp_s << " m to ramp up over tap.velocity_ramp_s = " << ramp_s
              << " s, more than the travel start_height_m + aim_depth_m = " << travel_m_
              << " m; lower the speed or the ramp, or raise the start height";
      throw Error(message.str());
    }
    tap.approach_speed_mps = v_mps;
    tap.start_s = t_s;
    tap.approach_end_s = tap.start_s + 0.5 * ramp_s + travel_m_ / v_mps;
    tap.dwell_end_s = tap.approach_end_s + script.dwell_s;
    tap.retract_end_s = tap.dwell_end_s + ramp_s + travel_m_ / script.retract_speed_mps;
    t_s = tap.retract_end_s + script.pause_s;
  }
  end_s_ = t_s;

  nominal_alpha_ =
      1.0 - std::exp(-2.0 * std::numbers::pi * model.velocity_cutoff_hz / model.tick_rate_hz);

  x_m_ = start_point_m_;
  v_mps_.setZero();
  last_quantized_m_ = Quantize(x_m_);
  latest_ = {0, 0.0, last_quantized_m_, Vec3::Zero()};
  previous_ = latest_;
  int cursor = 0;
  hand_force_N_ = HandForce(IntendedAt(0.0, cursor), x_m_, v_mps_);
  grip_force_N_ =
      hand_force_N_ - hand_.mass_kg * Acceleration(IntendedAt(0.0, cursor), x_m_, v_mps_);
}

SimulatedDevice::Intended SimulatedDevice::IntendedAt(double t_s, int& cursor) const {
  const int n = static_cast<int>(taps_.size());
  while (cursor < n && t_s >= taps_[cursor].retract_end_s) ++cursor;
  Profile p;  // depth below the start point along -normal
  if (cursor < n && t_s >= taps_[cursor].start_s) {
    const TapTiming& tap = taps_[cursor];
    const double ramp_s = script_.velocity_ramp_s;
    if (t_s < tap.approach_end_s) {
      const double tau_s = t_s - tap.start_s;
      const double v_mps = tap.approach_speed_mps;
      if (tau_s < ramp_s) {
        p = RampUp(tau_s, v_mps, ramp_s);
      } else {
        // ends abruptly at the aim point: the hand plans to hit, not to stop
        p = {v_mps * (tau_s - 0.5 * ramp_s), v_mps, 0.0};
      }
    } else if (t_s < tap.dwell_end_s) {
      p = {travel_m_, 0.0, 0.0};
    } else {
      const double tau_s = t_s - tap.dwell_end_s;
      const double u_mps = script_.retract_speed_mps;
      const double retract_s = tap.retract_end_s - tap.dwell_end_s;
      Profile r;  // distance travelled back up
      if (tau_s < ramp_s) {
        r = RampUp(tau_s, u_mps, ramp_s);
      } else if (tau_s < retract_s - ramp_s) {
        r = {u_mps * (tau_s - 0.5 * ramp_s), u_mps, 0.0};
      } else {
        const Profile down = RampDown(tau_s - (retract_s - ramp_s), u_mps, ramp_s);
        r = {travel_m_ - 0.5 * u_mps * ramp_s + down.s, down.s_dot, down.s_ddot};
      }
      p = {travel_m_ - r.s, -r.s_dot, -r.s_ddot};
    }
  }
  return {start_point_m_ - p.s * normal_, -p.s_dot * normal_, -p.s_ddot * normal_};
}

Vec3 SimulatedDevice::HandForce(const Intended& in, const Vec3& x_m, const Vec3& v_mps) const {
  Vec3 force_N = hand_.stiffness_N_per_m * (in.position_m - x_m) +
                 hand_.damping_Ns_per_m * (in.velocity_mps - v_mps);
  if (hand_.inertia_feedforward) force_N += total_mass_kg_ * in.acceleration_mps2;
  return force_N;
}

Vec3 SimulatedDevice::Acceleration(const Intended& in, const Vec3& x_m, const Vec3& v_mps) const {
  Vec3 force_N = displayed_force_N_ + HandForce(in, x_m, v_mps);
  if (!model_.gravity_compensated) force_N += model_.apparent_mass_kg * model_.gravity_mps2;
  return force_N / total_mass_kg_;
}

Vec3 SimulatedDevice::Quantize(const Vec3& x_m) const {
  const double res_m = model_.encoder_resolution_m;
  if (res_m <= 0.0) return x_m;
  return Vec3(res_m * std::round(x_m.x() / res_m), res_m * std::round(x_m.y() / res_m),
              res_m * std::round(x_m.z() / res_m));
}

DeviceState SimulatedDevice::Read() {
  const Sample& sample = model_.delay_ticks == 1 ? previous_ : latest_;
  DeviceState state;
  state.sequence = sample.sequence;
  state.time_s = sample.time_s;
  state.position_m = sample.position_m;
  state.velocity_mps = sample.velocity_mps;
  state.valid = true;
  return state;
}

void SimulatedDevice::Write(const DeviceCommand& command) {
  Vec3 force_N = command.force_N;
  last_clipped_ = false;
  if (!force_N.allFinite()) {
    ++error_count_;
    displayed_force_N_.setZero();
    return;
  }
  // keep the direction (clipping per axis would turn the force), and round down to the limit
  Vec3 torque_Nm = command.torque_Nm;
  if (render::LimitForce(limits_.max_force_N, force_N, torque_Nm)) {
    last_clipped_ = true;
    ++clipped_count_;
  }
  displayed_force_N_ = force_N;
}

void SimulatedDevice::Advance(double dt_s) {
  if (!std::isfinite(dt_s) || dt_s <= 0.0) {
    ++error_count_;
    return;
  }
  const Vec3 x_start_m = x_m_;
  const double t0_s = time_s_;
  const double h_s = dt_s / model_.substeps;
  int cursor = cursor_;
  Intended in0 = IntendedAt(t0_s, cursor);
  for (int i = 0; i < model_.substeps; ++i) {
    const double t_s = t0_s + i * h_s;
    const Intended in_mid = IntendedAt(t_s + 0.5 * h_s, cursor);
    const Intended in1 = IntendedAt(t_s + h_s, cursor);
    // classical RK4 on (x, v), the displayed force held (zero-order hold)
    const Vec3 k1x = v_mps_;
    const Vec3 k1v = Acceleration(in0, x_m_, v_mps_);
    const Vec3 k2x = v_mps_ + 0.5 * h_s * k1v;
    const Vec3 k2v = Acceleration(in_mid, x_m_ + 0.5 * h_s * k1x, k2x);
    const Vec3 k3x = v_mps_ + 0.5 * h_s * k2v;
    const Vec3 k3v = Acceleration(in_mid, x_m_ + 0.5 * h_s * k2x, k3x);
    const Vec3 k4x = v_mps_ + h_s * k3v;
    const Vec3 k4v = Acceleration(in1, x_m_ + h_s * k3x, k4x);
    x_m_ += (h_s / 6.0) * (k1x + 2.0 * k2x + 2.0 * k3x + k4x);
    v_mps_ += (h_s / 6.0) * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
    in0 = in1;
  }
  time_s_ = t0_s + dt_s;
  cursor_ = cursor;

  // exact work of a held force over the step
  energy_to_user_J_ += displayed_force_N_.dot(x_m_ - x_start_m);

  hand_force_N_ = HandForce(in0, x_m_, v_mps_);
  grip_force_N_ = hand_force_N_ - hand_.mass_kg * Acceleration(in0, x_m_, v_mps_);

  // encoder sample, finite-difference velocity, first-order low-pass (exact discretization)
  const Vec3 q_m = Quantize(x_m_);
  const Vec3 v_fd_mps = (q_m - last_quantized_m_) / dt_s;
  const double alpha =
      std::abs(dt_s * model_.tick_rate_hz - 1.0) < 1e-9
          ? nominal_alpha_
          : 1.0 - std::exp(-2.0 * std::numbers::pi * model_.velocity_cutoff_hz * dt_s);
  previous_ = latest_;
  latest_.sequence = previous_.sequence + 1;
  latest_.time_s = time_s_;
  latest_.position_m = q_m;
  latest_.velocity_mps = previous_.velocity_mps + alpha * (v_fd_mps - previous_.velocity_mps);
  last_quantized_m_ = q_m;
}

Vec3 SimulatedDevice::intended_position_m() const {
  int cursor = cursor_;
  return IntendedAt(time_s_, cursor).position_m;
}

int SimulatedDevice::current_tap() const {
  int cursor = cursor_;
  const int n = static_cast<int>(taps_.size());
  while (cursor < n && time_s_ >= taps_[cursor].retract_end_s) ++cursor;
  if (cursor < n && time_s_ >= taps_[cursor].start_s) return cursor;
  return -1;
}

}  // namespace rigidtouch::device
