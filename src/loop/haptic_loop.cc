#include "loop/haptic_loop.h"

#include <chrono>
#include <cmath>
#include <thread>

#include "render/limits.h"
#include "render/output.h"

namespace rigidtouch::loop {
namespace {

void ZeroWrench(DeviceCommand& command) {
  command.force_N.setZero();
  command.torque_Nm.setZero();
}

}  // namespace

HapticLoopResult RunHapticLoop(const Model& model, Data& data, device::Device& device,
                               const LoopOptions& options, const std::atomic<bool>* stop,
                               TraceQueue* traces) {
  HapticLoopResult r;
  RateLoop loop(options);
  const double period_s = 1.0 / options.rate_hz;
  TickInput input;
  bool have_sequence = false;  // a valid state was read on the previous tick
  std::uint64_t last_sequence = 0;
  double last_fresh_force_N = 0.0;
  r.timing = loop.Run(
      [&](std::int64_t, double) {
        input.device = device.Read();
        const bool valid = input.device.valid;
        if (!valid) ++r.invalid_device_ticks;
        // a new sequence is a new reading; after an invalid tick any sequence is (resync)
        const bool fresh = !valid || !have_sequence || input.device.sequence != last_sequence;
        input.device.fresh = fresh;
        if (!fresh) ++r.stale_device_ticks;
        have_sequence = valid;
        last_sequence = input.device.sequence;

        DeviceCommand command = Tick(model, data, input);

        // last guards before Write, whatever the tick did: nothing non-finite, nothing above
        // the stricter of the model's and the device's force limits
        const std::int64_t tick_step = data.step - 1;  // Tick has advanced data.step
        if (!command.force_N.allFinite() || !command.torque_Nm.allFinite()) {
          ZeroWrench(command);
          command.safe_fallback = true;
          ++r.non_finite_commands;
        }
        const double limit_N =
            render::StricterLimit(model.device.max_force_N, device.limits().max_force_N);
        r.force_limit_N = limit_N;
        if (render::LimitForce(limit_N, command.force_N, command.torque_Nm)) {
          ++r.guard_clipped_ticks;
          command.clipped = true;
          data.WarnAt(Warning::kForceClipped, tick_step);
          if (command.impulsive_force_N.squaredNorm() > 0.0) {
            data.WarnAt(Warning::kImpulseClipped, tick_step);
          }
        }
        // a stale state must not make the force grow (docs/device-protocol.md, Watchdogs)
        if (valid && !fresh) {
          if (command.force_N.norm() > last_fresh_force_N) {
            if (last_fresh_force_N > 0.0) {
              render::LimitForce(last_fresh_force_N, command.force_N, command.torque_Nm);
            } else {
              ZeroWrench(command);
            }
            ++r.held_force_ticks;
          }
        } else {
          last_fresh_force_N = command.force_N.norm();
        }

        device.Write(command);
        if (command.safe_fallback) ++r.safe_fallback_ticks;
        if (command.clipped) ++r.clipped_ticks;
        const double f = command.force_N.norm();
        if (!std::isfinite(f)) r.finite = false;
        if (f > r.max_force_N) r.max_force_N = f;
        for (int k = 0; k < data.nimpulse; ++k) r.impulses += data.impulses[k].tool ? 1 : 0;
        if (traces != nullptr) {
          TraceSample s = MakeTraceSample(model, data, command);
          // before EndPeriod: the sample describes the start of the period, as the offline
          // tap experiment's does
          device.AnnotateTrace(s);
          traces->Push(s);
        }
        device.EndPeriod(period_s);
        return true;
      },
      stop);
  return r;
}

bool AwaitFirstState(device::Device& device, double timeout_s, const std::atomic<bool>* stop) {
  using Clock = std::chrono::steady_clock;
  const auto deadline = Clock::now() + std::chrono::duration<double>(timeout_s);
  DeviceCommand zero;
  zero.safe_fallback = true;
  for (;;) {
    if (device.Read().valid) return true;
    device.Write(zero);
    if (Clock::now() >= deadline) return false;
    if (stop != nullptr && stop->load()) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
}

}  // namespace rigidtouch::loop
