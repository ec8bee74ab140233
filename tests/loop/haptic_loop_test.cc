// RunHapticLoop drives every device through the plain Device port: a simulated device advances its
// plant in EndPeriod, which the loop calls once per tick after Write.
#include "loop/haptic_loop.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "analysis/tap_experiment.h"
#include "device/simulated_device.h"
#include "loop/trace_queue.h"
#include "rigidtouch/device.h"

namespace rigidtouch::loop {
namespace {

constexpr double kRateHz = 1000.0;

analysis::TapSetup WallSetup() {
  analysis::TapExperimentConfig c;
  c.scene_path = std::string(RIGIDTOUCH_SOURCE_DIR) + "/scenes/wall.xml";
  c.load.device.coupling = Coupling::kDirect;
  c.rate_hz = kRateHz;
  c.script.taps = 1;
  c.script.pause_s = 0.0;  // the approach starts at t = 0: the hand moves from the first tick
  return analysis::PrepareTap(c);
}

LoopOptions Options(double duration_s) {
  LoopOptions o;
  o.rate_hz = kRateHz;
  o.duration_s = duration_s;
  return o;
}

TEST(HapticLoop, SimulatedDeviceAdvancesThroughThePlainDevicePort) {
  analysis::TapSetup setup = WallSetup();
  device::SimulatedDevice& sim = *setup.simulated;
  const Vec3 start_m = sim.true_position_m();
  Data data = MakeData(setup.model);
  std::vector<TraceSample> samples;
  samples.reserve(1000);
  TraceQueue traces(1000, VectorSink(&samples));
  device::Device& port = sim;  // the loop sees only the port
  const HapticLoopResult r = RunHapticLoop(setup.model, data, port, Options(0.1), nullptr, &traces);
  traces.Close();

  // one period of plant time per tick (skipped periods under load run no tick)
  ASSERT_GT(r.timing.ticks, 10);
  EXPECT_NEAR(sim.time_s(), static_cast<double>(r.timing.ticks) / kRateHz, 1e-9);
  EXPECT_EQ(sim.Read().sequence, static_cast<std::uint64_t>(r.timing.ticks));
  EXPECT_EQ(sim.error_count(), 0);

  // the hand followed its script towards the wall: the intended point has moved by
  // v (t - ramp / 2) once the 50 ms ramp is over, and the feedforward hand tracks it to 1 mm
  const double t_s = sim.time_s();
  const double v_mps = sim.tap_timings()[0].approach_speed_mps;
  const double ramp_s = 0.05;
  const double travel_m = t_s >= ramp_s
                              ? v_mps * (t_s - 0.5 * ramp_s)
                              : v_mps * (0.5 * t_s - ramp_s / (2.0 * std::numbers::pi) *
                                                         std::sin(std::numbers::pi * t_s / ramp_s));
  const Vec3 intended_m = sim.intended_position_m();
  EXPECT_NEAR((start_m - intended_m).z(), travel_m, 1e-9);
  EXPECT_GT((start_m - sim.true_position_m()).z(), 0.5 * travel_m);
  EXPECT_NEAR((sim.true_position_m() - intended_m).norm(), 0.0, 1e-3);

  // the trace carries what only the device knows, at the start of each period: the tap in
  // progress and the hand's force (m a_int during the ramp, a few newtons)
  ASSERT_EQ(samples.size(), static_cast<std::size_t>(r.timing.ticks));
  double max_hand_N = 0.0;
  for (const TraceSample& s : samples) {
    EXPECT_EQ(s.tap, 0);
    max_hand_N = std::max(max_hand_N, s.hand_force_N.norm());
  }
  EXPECT_GT(max_hand_N, 1.0);
}

// records the order of the port's calls
class RecordingDevice final : public device::Device {
 public:
  DeviceState Read() override {
    calls += 'R';
    DeviceState s;
    s.position_m = Vec3(0.0, 0.0, 0.1);  // well above the wall
    return s;
  }
  void Write(const DeviceCommand&) override { calls += 'W'; }
  const device::DeviceLimits& limits() const override { return limits_; }
  void EndPeriod(double period_s) override {
    calls += 'E';
    last_period_s = period_s;
  }
  void AnnotateTrace(TraceSample& sample) const override { sample.tap = 7; }

  std::string calls;
  double last_period_s = 0.0;

 private:
  device::DeviceLimits limits_;
};

TEST(HapticLoop, CallsReadWriteEndPeriodOncePerTickInOrder) {
  analysis::TapSetup setup = WallSetup();
  Data data = MakeData(setup.model);
  RecordingDevice dev;
  dev.calls.reserve(1000);
  std::vector<TraceSample> samples;
  samples.reserve(1000);
  TraceQueue traces(1000, VectorSink(&samples));
  const HapticLoopResult r = RunHapticLoop(setup.model, data, dev, Options(0.02), nullptr, &traces);
  traces.Close();
  ASSERT_GT(r.timing.ticks, 0);
  std::string expected;
  for (std::int64_t k = 0; k < r.timing.ticks; ++k) expected += "RWE";
  EXPECT_EQ(dev.calls, expected);
  EXPECT_DOUBLE_EQ(dev.last_period_s, 1.0 / kRateHz);
  ASSERT_EQ(samples.size(), static_cast<std::size_t>(r.timing.ticks));
  for (const TraceSample& s : samples) EXPECT_EQ(s.tap, 7);
}

}  // namespace
}  // namespace rigidtouch::loop
