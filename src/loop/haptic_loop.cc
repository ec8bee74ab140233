#include "loop/haptic_loop.h"

#include <cmath>

namespace rigidtouch::loop {

HapticLoopResult RunHapticLoop(const Model& model, Data& data, device::Device& device,
                               const LoopOptions& options, const std::atomic<bool>* stop,
                               TraceQueue* traces) {
  HapticLoopResult r;
  RateLoop loop(options);
  const double period_s = 1.0 / options.rate_hz;
  TickInput input;
  r.timing = loop.Run(
      [&](std::int64_t, double) {
        input.device = device.Read();
        if (!input.device.valid) ++r.invalid_device_ticks;
        const DeviceCommand command = Tick(model, data, input);
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

}  // namespace rigidtouch::loop
