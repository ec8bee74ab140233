#include "loop/haptic_loop.h"

#include <chrono>
#include <cmath>
#include <thread>

#include "base/limits.h"
#include "engine/workspace.h"
#include "render/output.h"

namespace rigidtouch::loop {
namespace {

void ZeroWrench(DeviceCommand& command) {
  command.force_N.setZero();
  command.torque_Nm.setZero();
}

// One period of the loop: Read, Tick, guard, Write, trace and record, EndPeriod. The paced and
// the unpaced runs call the same step, so every device and every pace shares one path.
class HapticStep {
 public:
  HapticStep(const Model& model, Data& data, device::Device& device, double period_s,
             TraceQueue* traces, RecordQueue* records, TickObserver* observer, HapticLoopResult& r)
      : model_(model),
        data_(data),
        device_(device),
        period_s_(period_s),
        traces_(traces),
        records_(records),
        observer_(observer),
        r_(r) {}

  bool operator()() {
    input_.device = device_.Read();
    const bool valid = input_.device.valid;
    if (!valid) ++r_.invalid_device_ticks;
    // a new sequence is a new reading; after an invalid tick any sequence is (resync)
    const bool fresh = !valid || !have_sequence_ || input_.device.sequence != last_sequence_;
    input_.device.fresh = fresh;
    if (!fresh) ++r_.stale_device_ticks;
    have_sequence_ = valid;
    last_sequence_ = input_.device.sequence;

    DeviceCommand command = Tick(model_, data_, input_);

    // last guards before Write, whatever the tick did: nothing non-finite, nothing above
    // the stricter of the model's and the device's force limits
    const std::int64_t tick_step = data_.step - 1;  // Tick has advanced data.step
    if (!command.force_N.allFinite() || !command.torque_Nm.allFinite()) {
      ZeroWrench(command);
      command.safe_fallback = true;
      ++r_.non_finite_commands;
    }
    const double limit_N =
        limits::StricterLimit(model_.device.limits.max_force_N, device_.limits().max_force_N);
    r_.force_limit_N = limit_N;
    // the torque within the device's own torque limit (none for a 3-DoF force device)
    const bool torque_clipped =
        render::LimitTorque(device_.limits().max_torque_Nm, command.torque_Nm);
    const bool force_clipped = render::LimitForce(limit_N, command.force_N, command.torque_Nm);
    if (force_clipped || torque_clipped) {
      ++r_.guard_clipped_ticks;
      command.clipped = true;
    }
    if (force_clipped) {
      data_.WarnAt(Warning::kForceClipped, tick_step);
      if (command.impulsive_force_N.squaredNorm() > 0.0) {
        data_.WarnAt(Warning::kImpulseClipped, tick_step);
      }
    }
    // a stale state must not make the force grow (docs/device-protocol.md, Watchdogs)
    if (valid && !fresh) {
      if (command.force_N.norm() > last_fresh_force_N_) {
        if (last_fresh_force_N_ > 0.0) {
          render::LimitForce(last_fresh_force_N_, command.force_N, command.torque_Nm);
        } else {
          ZeroWrench(command);
        }
        ++r_.held_force_ticks;
      }
    } else {
      last_fresh_force_N_ = command.force_N.norm();
    }

    device_.Write(command);
    if (command.safe_fallback) ++r_.safe_fallback_ticks;
    if (command.clipped) ++r_.clipped_ticks;
    const double f = command.force_N.norm();
    if (!std::isfinite(f)) r_.finite = false;
    if (f > r_.max_force_N) r_.max_force_N = f;
    for (int k = 0; k < data_.nimpulse; ++k) r_.impulses += data_.impulses[k].tool ? 1 : 0;
    if (traces_ != nullptr || records_ != nullptr || observer_ != nullptr) {
      TraceSample s = MakeTraceSample(model_, data_, command);
      // before EndPeriod: the sample describes the start of the period, as the offline
      // tap experiment's does
      device_.AnnotateTrace(s);
      if (traces_ != nullptr) traces_->Push(s);
      if (records_ != nullptr) {
        // the session's tick, continuous over loop runs on the same Data (a viewer's renderer
        // switch restarts the loop)
        record_.tick = tick_step;
        record_.state = input_.device;
        record_.command = command;
        record_.tap = s.tap;
        record_.hand_force_N = s.hand_force_N;
        records_->Push(record_);
      }
      if (observer_ != nullptr) observer_->OnTick(model_, data_, s);
    }
    device_.EndPeriod(period_s_);
    return !device_.Ended();
  }

  // after the last period: the zero wrench, flagged safe-fallback, answering the last state read
  // (so that a bridge does not drop it as older than the last command). A device holds its last
  // command until the next Write, and a bridge until its watchdog trips: without this, the last
  // tick's force would go on pushing the hand after the loop stopped.
  void Release() {
    DeviceCommand zero;
    zero.sequence = input_.device.sequence;
    zero.safe_fallback = true;
    device_.Write(zero);
  }

 private:
  const Model& model_;
  Data& data_;
  device::Device& device_;
  const double period_s_;
  TraceQueue* traces_;
  RecordQueue* records_;
  TickObserver* observer_;
  HapticLoopResult& r_;
  TickInput input_;
  io::RecordSample record_;
  bool have_sequence_ = false;  // a valid state was read on the previous tick
  std::uint64_t last_sequence_ = 0;
  double last_fresh_force_N_ = 0.0;
};

}  // namespace

HapticLoopResult RunHapticLoop(const Model& model, Data& data, device::Device& device,
                               const LoopOptions& options, const std::atomic<bool>* stop,
                               TraceQueue* traces, RecordQueue* records, TickObserver* observer) {
  HapticLoopResult r;
  // the tick's worker keeps off the loop's CPU when it is pinned (LoopOptions::helper_threads)
  LoopOptions with_worker = options;
  if (data.workspace != nullptr && data.workspace->worker != nullptr) {
    with_worker.helper_threads.push_back(data.workspace->worker->native_handle());
  }
  RateLoop loop(with_worker);
  HapticStep step(model, data, device, 1.0 / options.rate_hz, traces, records, observer, r);
  r.timing = loop.Run([&step](std::int64_t, double) { return step(); }, stop);
  step.Release();
  return r;
}

HapticLoopResult RunHapticTicks(const Model& model, Data& data, device::Device& device,
                                double rate_hz, std::int64_t ticks, const std::atomic<bool>* stop,
                                TraceQueue* traces, RecordQueue* records, TickObserver* observer) {
  HapticLoopResult r;
  HapticStep step(model, data, device, 1.0 / rate_hz, traces, records, observer, r);
  const auto t0 = std::chrono::steady_clock::now();
  r.timing.rate_hz = rate_hz;
  for (std::int64_t k = 0; k < ticks; ++k) {
    if (stop != nullptr && stop->load(std::memory_order_relaxed)) {
      r.timing.stop_requested = true;
      break;
    }
    ++r.timing.ticks;
    if (!step()) break;
  }
  step.Release();
  r.timing.elapsed_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (r.timing.elapsed_s > 0.0) {
    r.timing.achieved_rate_hz = static_cast<double>(r.timing.ticks) / r.timing.elapsed_s;
  }
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
