// RunHapticLoop drives every device through the plain Device port: a simulated device advances its
// plant in EndPeriod, which the loop calls once per tick after Write.
#include "loop/haptic_loop.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <numbers>
#include <string>
#include <vector>

#include "analysis/tap_experiment.h"
#include "device/replay_device.h"
#include "device/simulated_device.h"
#include "loop/trace_queue.h"
#include "rigidtouch/device.h"
#include "test_util.h"

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
  const DeviceLimits& limits() const override { return limits_; }
  void EndPeriod(double period_s) override {
    calls += 'E';
    last_period_s = period_s;
  }
  void AnnotateTrace(TraceSample& sample) const override { sample.tap = 7; }

  std::string calls;
  double last_period_s = 0.0;

 private:
  DeviceLimits limits_;
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
  expected += "W";  // the zero wrench after the last period
  EXPECT_EQ(dev.calls, expected);
  EXPECT_DOUBLE_EQ(dev.last_period_s, 1.0 / kRateHz);
  ASSERT_EQ(samples.size(), static_cast<std::size_t>(r.timing.ticks));
  for (const TraceSample& s : samples) EXPECT_EQ(s.tap, 7);
}

// approaches the shipped wall at 0.2 m/s with one new reading (sequence) per Read; after
// `fresh_reads` it freezes: the last reading again, same sequence, for `stale_reads` (a bridge
// that died: the link still hands out its newest state), then invalid (the watchdog)
class FreezingDevice final : public device::Device {
 public:
  FreezingDevice(int fresh_reads, int stale_reads, double max_force_N, bool keep_moving = false)
      : fresh_reads_(fresh_reads), stale_reads_(stale_reads), keep_moving_(keep_moving) {
    limits_.max_force_N = max_force_N;
    commands.reserve(4000);
  }
  DeviceState Read() override {
    const int k = std::min(reads_, fresh_reads_ - 1);
    const int moved = keep_moving_ ? reads_ : k;  // a faulty bridge: new pose, old sequence
    DeviceState s;
    s.sequence = static_cast<std::uint64_t>(k) + 1;
    s.position_m = Vec3(0.0, 0.0, kStart_m - kSpeed_mps * moved / kRateHz);
    s.velocity_mps = Vec3(0.0, 0.0, -kSpeed_mps);
    s.valid = reads_ < fresh_reads_ + stale_reads_;
    ++reads_;
    return s;
  }
  void Write(const DeviceCommand& command) override {
    if (commands.size() < commands.capacity()) commands.push_back(command);
  }
  const DeviceLimits& limits() const override { return limits_; }

  static constexpr double kStart_m = 0.0058;  // the tool centre touches the wall at 0.005
  static constexpr double kSpeed_mps = 0.2;
  std::vector<DeviceCommand> commands;  // one per tick

 private:
  int fresh_reads_, stale_reads_;
  bool keep_moving_;
  int reads_ = 0;
  DeviceLimits limits_;
};

Model DirectWall(double max_force_N) {
  LoadOptions o;
  o.render.renderer = RendererKind::kTrain;  // 250 Hz: an impulse every 4 ticks
  o.device.coupling = Coupling::kDirect;
  o.device.limits.max_force_N = max_force_N;
  o.timestep_s = 1.0 / kRateHz;
  return LoadModel(std::string(RIGIDTOUCH_SOURCE_DIR) + "/scenes/wall.xml", o);
}

// a handle held 0.5 mm inside the shipped wall (the tool centre touches it at 5 mm), one new
// reading per Read; remembers every command
class PressingDevice final : public device::Device {
 public:
  PressingDevice() { commands.reserve(4000); }
  DeviceState Read() override {
    DeviceState s;
    s.sequence = ++sequence_;
    s.position_m = Vec3(0.0, 0.0, 0.0045);
    return s;
  }
  void Write(const DeviceCommand& command) override {
    if (commands.size() < commands.capacity()) commands.push_back(command);
  }
  const DeviceLimits& limits() const override { return limits_; }
  std::uint64_t sequence() const { return sequence_; }

  std::vector<DeviceCommand> commands;

 private:
  std::uint64_t sequence_ = 0;
  DeviceLimits limits_;
};

// a device holds its last command: when the loop stops, paced or not, the hand pressing into the
// wall gets the zero wrench last, flagged safe-fallback and answering the last state read (a
// bridge drops a command older than its newest)
TEST(HapticLoop, StopsWithTheZeroWrench) {
  for (const bool paced : {false, true}) {
    SCOPED_TRACE(paced ? "RunHapticLoop" : "RunHapticTicks");
    const Model model = DirectWall(0.0);
    Data data = MakeData(model);
    PressingDevice dev;
    const HapticLoopResult r = paced ? RunHapticLoop(model, data, dev, Options(0.05), nullptr)
                                     : RunHapticTicks(model, data, dev, kRateHz, 50, nullptr);
    const auto& c = dev.commands;
    ASSERT_GE(r.timing.ticks, 2);
    ASSERT_EQ(static_cast<std::int64_t>(c.size()), r.timing.ticks + 1);
    const DeviceCommand& last_tick = c[c.size() - 2];
    EXPECT_GT(last_tick.force_N.norm(), 0.1);  // pressing into the wall to the end
    EXPECT_FALSE(last_tick.safe_fallback);
    EXPECT_EQ(c.back().force_N, Vec3::Zero());
    EXPECT_EQ(c.back().torque_Nm, Vec3::Zero());
    EXPECT_TRUE(c.back().safe_fallback);
    EXPECT_EQ(c.back().sequence, dev.sequence());
    EXPECT_EQ(c.back().sequence, last_tick.sequence);
  }
}

// the device stops updating during contact, in the middle of a train: from the last fresh
// reading to the watchdog no impulse is applied and the force does not grow; then zero force
TEST(HapticLoop, StaleStateDuringContactAppliesNoImpulseAndHoldsTheForce) {
  const Model model = DirectWall(0.0);
  Data data = MakeData(model);
  const int fresh = 11, stale = 30;  // contact from read 5 (z = 4.8 mm): impulses at 5 and 9
  FreezingDevice dev(fresh, stale, 0.0);
  const HapticLoopResult r = RunHapticLoop(model, data, dev, Options(0.2), nullptr);
  const auto& c = dev.commands;
  ASSERT_GE(static_cast<int>(c.size()), fresh + stale + 5) << "too few ticks (loaded machine?)";

  int fresh_impulses = 0;
  for (int k = 0; k < fresh; ++k) fresh_impulses += c[k].impulsive_force_N.squaredNorm() > 0.0;
  ASSERT_GE(fresh_impulses, 2);  // a train was running when the device froze
  const double last_fresh_N = c[fresh - 1].force_N.norm();
  ASSERT_GT(last_fresh_N, 0.0);  // in contact
  for (int k = fresh; k < fresh + stale; ++k) {
    EXPECT_EQ(c[k].impulsive_force_N, Vec3::Zero()) << "tick " << k;
    EXPECT_LE(c[k].force_N.norm(), last_fresh_N) << "tick " << k;
    EXPECT_LE(c[k].force_N.norm(), c[k - 1].force_N.norm()) << "tick " << k;
    EXPECT_FALSE(c[k].safe_fallback) << "tick " << k;
  }
  for (std::size_t k = fresh + stale; k < c.size(); ++k) {
    EXPECT_EQ(c[k].force_N, Vec3::Zero()) << "tick " << k;  // the watchdog: invalid state
    EXPECT_TRUE(c[k].safe_fallback);
  }
  EXPECT_EQ(r.stale_device_ticks, stale);
}

// whatever a reading with an old sequence says (here: deeper and deeper into the wall), the
// loop does not let it raise the force above the last fresh tick's
TEST(HapticLoop, RepeatedSequenceCannotRaiseTheForce) {
  const Model model = DirectWall(0.0);
  Data data = MakeData(model);
  const int fresh = 11, stale = 30;
  FreezingDevice dev(fresh, stale, 0.0, /*keep_moving=*/true);
  const HapticLoopResult r = RunHapticLoop(model, data, dev, Options(0.1), nullptr);
  const auto& c = dev.commands;
  ASSERT_GE(static_cast<int>(c.size()), fresh + stale) << "too few ticks (loaded machine?)";
  const double last_fresh_N = c[fresh - 1].force_N.norm();
  ASSERT_GT(last_fresh_N, 0.0);
  for (int k = fresh; k < fresh + stale; ++k) {
    // k d alone would grow by k v h = 0.4 N per tick
    EXPECT_LE(c[k].force_N.norm(), last_fresh_N) << "tick " << k;
    EXPECT_GT(c[k].penalty_force_N.norm(), last_fresh_N) << "tick " << k;
  }
  EXPECT_EQ(r.held_force_ticks, stale);
}

// the loop's last guard clips every command to the device's own limit when the model has none
// (or a looser one), flags it and counts the warning; the model's stricter limit wins in Tick
TEST(HapticLoop, EveryCommandIsClippedToTheStricterOfModelAndDeviceLimits) {
  struct Case {
    double model_N, device_N, limit_N;
    bool guard_clips;
  };
  for (const Case& k :
       {Case{0.0, 1.0, 1.0, true}, Case{5.0, 1.0, 1.0, true}, Case{0.5, 1.0, 0.5, false}}) {
    const Model model = DirectWall(k.model_N);
    Data data = MakeData(model);
    FreezingDevice dev(1000, 0, k.device_N);  // keeps pressing into the wall, always fresh
    const HapticLoopResult r = RunHapticLoop(model, data, dev, Options(0.06), nullptr);
    ASSERT_GT(dev.commands.size(), 20u);
    int clipped = 0;
    for (const DeviceCommand& c : dev.commands) {
      EXPECT_LE(c.force_N.norm(), k.limit_N);
      clipped += c.clipped;
      if (c.force_N.norm() < k.limit_N * (1.0 - 1e-12)) {
        EXPECT_FALSE(c.clipped);
      }
    }
    EXPECT_GT(clipped, 0);  // the impulses and the deepening contact exceed the limit
    EXPECT_EQ(r.clipped_ticks, clipped);
    EXPECT_EQ(data.warnings[static_cast<int>(Warning::kForceClipped)].count, clipped);
    EXPECT_EQ(r.guard_clipped_ticks > 0, k.guard_clips);
    EXPECT_LE(r.max_force_N, k.limit_N);
    EXPECT_DOUBLE_EQ(r.force_limit_N, k.limit_N);
    EXPECT_TRUE(r.finite);
  }
}

// a tool of two spheres whose lower one presses into the wall 20 mm (in x) from the tool's
// centre of mass: the contact force has a lever arm, so the tick's command carries a torque. A
// device that displays no torque (max_torque_Nm 0, every preset) gets none; one with a torque limit
// gets at most that, counted as a clip; one whose limit is above the torque gets it unchanged.
class LeverDevice final : public device::Device {
 public:
  explicit LeverDevice(double max_torque_Nm) {
    limits_.max_torque_Nm = max_torque_Nm;
    commands.reserve(4000);
  }
  DeviceState Read() override {
    DeviceState s;
    s.sequence = ++sequence_;
    s.position_m = Vec3(0.0, 0.0, 0.0095);  // the lower sphere 0.5 mm inside the wall
    return s;
  }
  void Write(const DeviceCommand& command) override {
    if (commands.size() < commands.capacity()) commands.push_back(command);
  }
  const DeviceLimits& limits() const override { return limits_; }
  std::vector<DeviceCommand> commands;

 private:
  std::uint64_t sequence_ = 0;
  DeviceLimits limits_;
};

TEST(HapticLoop, TheTorqueIsWithinTheDevicesTorqueLimitOrZero) {
  // in this process's own folder: two runs of the suite at once do not share the file
  const std::string scene = test::WriteTempFile(
      "lever_tool.xml", R"(<mujoco><worldbody><geom name="wall" type="plane" size="1 1 0.1"/>
      <body name="tool" pos="0 0 0.1"><freejoint/>
        <geom type="sphere" size="0.005" pos="0.02 0 -0.005" mass="0.05"/>
        <geom type="sphere" size="0.005" pos="-0.02 0 0.005" mass="0.05"/>
      </body></worldbody></mujoco>)");
  LoadOptions o;
  o.device.coupling = Coupling::kDirect;
  o.timestep_s = 1.0 / kRateHz;
  const Model model = LoadModel(scene, o);
  // a limit above it: the torque the tick computes
  double free_Nm = 0.0;
  {
    Data data = MakeData(model);
    LeverDevice dev(1e3);
    const HapticLoopResult r = RunHapticTicks(model, data, dev, kRateHz, 50, nullptr);
    ASSERT_EQ(dev.commands.size(), 51u);
    for (const DeviceCommand& c : dev.commands) {
      // the penalty force acts 20 mm from the centre of mass along x (closed form, to rounding)
      EXPECT_NEAR(c.torque_Nm.norm(), 0.02 * c.penalty_force_N.norm(), 1e-12);
      free_Nm = std::max(free_Nm, c.torque_Nm.norm());
    }
    EXPECT_EQ(r.guard_clipped_ticks, 0);
  }
  ASSERT_GT(free_Nm, 0.01);
  for (const double limit_Nm : {0.0, 0.5 * free_Nm}) {
    SCOPED_TRACE(limit_Nm);
    Data data = MakeData(model);
    LeverDevice dev(limit_Nm);
    const HapticLoopResult r = RunHapticTicks(model, data, dev, kRateHz, 50, nullptr);
    double most_Nm = 0.0;
    for (const DeviceCommand& c : dev.commands) {
      EXPECT_LE(c.torque_Nm.norm(), limit_Nm);
      EXPECT_GT(c.force_N.norm() + (c.safe_fallback ? 1.0 : 0.0), 0.0);  // force still sent
      most_Nm = std::max(most_Nm, c.torque_Nm.norm());
    }
    // the force is not clipped: a torque clip is a clip, not Warning::kForceClipped
    EXPECT_EQ(data.warnings[static_cast<int>(Warning::kForceClipped)].count, 0);
    if (limit_Nm > 0.0) {
      EXPECT_NEAR(most_Nm, limit_Nm, 1e-12 * limit_Nm);  // clipped, not zeroed
      EXPECT_GT(r.guard_clipped_ticks, 0);
      EXPECT_EQ(r.clipped_ticks, r.guard_clipped_ticks);
    } else {
      EXPECT_EQ(r.guard_clipped_ticks, 0);  // no torque is not a clip
    }
  }
}

// with threads 2 the tick's worker is the loop's helper: kept off the loop's CPU when the loop is
// pinned, so that the two never share a CPU
TEST(HapticLoop, TheTicksWorkerKeepsOffThePinnedLoopsCpu) {
  const int target = test::LastCpuOfSeveral();
  if (target < 0) GTEST_SKIP() << "needs two CPUs";
  for (const int threads : {1, 2}) {
    LoadOptions o;
    o.device.coupling = Coupling::kDirect;
    o.timestep_s = 1.0 / kRateHz;
    o.threads = threads;
    const Model model = LoadModel(std::string(RIGIDTOUCH_SOURCE_DIR) + "/scenes/wall.xml", o);
    Data data = MakeData(model);
    FreezingDevice dev(1000, 0, 0.0);
    LoopOptions options = Options(0.02);
    options.cpu = target;
    const HapticLoopResult r = RunHapticLoop(model, data, dev, options, nullptr);
    EXPECT_EQ(r.timing.helper_threads, threads - 1) << threads << " threads";
    if (r.timing.pinned_cpu == target) {
      EXPECT_EQ(r.timing.helpers_off_loop_cpu, threads - 1) << threads << " threads";
    }
  }
}

// no answering device: AwaitFirstState gives up after its timeout, having written only zero
// wrenches flagged safe-fallback; a device that answers is found at once
TEST(HapticLoop, AwaitFirstStateTimesOutWithoutADevice) {
  FreezingDevice silent(1, 0, 0.0);  // every reading invalid
  silent.Read();
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_FALSE(AwaitFirstState(silent, 0.05, nullptr));
  const double waited_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_GE(waited_s, 0.05);
  EXPECT_LT(waited_s, 1.0);
  ASSERT_FALSE(silent.commands.empty());
  for (const DeviceCommand& c : silent.commands) {
    EXPECT_EQ(c.force_N, Vec3::Zero());
    EXPECT_TRUE(c.safe_fallback);
  }
  FreezingDevice present(10, 0, 0.0);
  EXPECT_TRUE(AwaitFirstState(present, 0.05, nullptr));
  EXPECT_TRUE(present.commands.empty());
}

}  // namespace
}  // namespace rigidtouch::loop

namespace rigidtouch::loop {
namespace {

// --record's path: every tick's state and command reach the record queue; replaying the recorded
// states through the same model, unpaced, reproduces every command bit for bit and ends with the
// record (the device's Ended), not before or after
TEST(HapticLoop, RecordedSessionReplaysToTheSameCommandsBitForBit) {
  analysis::TapSetup setup = WallSetup();
  Data data = MakeData(setup.model);
  std::vector<io::RecordSample> recorded;
  recorded.reserve(400);
  {
    RecordQueue records(400, [&](std::span<const io::RecordSample> b) {
      recorded.insert(recorded.end(), b.begin(), b.end());
    });
    const HapticLoopResult r = RunHapticTicks(setup.model, data, *setup.simulated, kRateHz, 300,
                                              nullptr, nullptr, &records);
    records.Close();
    ASSERT_EQ(r.timing.ticks, 300);
    ASSERT_GT(r.impulses, 0);  // the tap reached the wall within 0.3 s
    EXPECT_EQ(records.stats().dropped, 0u);
  }
  ASSERT_EQ(recorded.size(), 300u);
  for (std::size_t k = 0; k < recorded.size(); ++k) ASSERT_EQ(recorded[k].tick, std::int64_t(k));

  analysis::TapSetup again = WallSetup();  // same model, fresh data
  Data replay_data = MakeData(again.model);
  device::ReplayDevice replay(recorded, again.device);
  std::vector<io::RecordSample> replayed;
  replayed.reserve(400);
  RecordQueue records(400, [&](std::span<const io::RecordSample> b) {
    replayed.insert(replayed.end(), b.begin(), b.end());
  });
  // asked for more ticks than recorded: the replay's end stops the run
  const HapticLoopResult r =
      RunHapticTicks(again.model, replay_data, replay, kRateHz, 1000, nullptr, nullptr, &records);
  records.Close();
  EXPECT_EQ(r.timing.ticks, 300);
  ASSERT_EQ(replayed.size(), recorded.size());
  int in_contact = 0;
  for (std::size_t k = 0; k < recorded.size(); ++k) {
    const DeviceCommand& a = recorded[k].command;
    const DeviceCommand& b = replayed[k].command;
    // exact equality: the replay must compute the same doubles, not close ones
    ASSERT_EQ(a.force_N, b.force_N) << "tick " << k;
    ASSERT_EQ(a.penalty_force_N, b.penalty_force_N) << "tick " << k;
    ASSERT_EQ(a.impulsive_force_N, b.impulsive_force_N) << "tick " << k;
    ASSERT_EQ(a.clipped, b.clipped) << "tick " << k;
    ASSERT_EQ(recorded[k].state.position_m, replayed[k].state.position_m) << "tick " << k;
    ASSERT_EQ(recorded[k].tap, replayed[k].tap);
    ASSERT_EQ(recorded[k].hand_force_N, replayed[k].hand_force_N);
    in_contact += a.force_N.norm() > 0.0 ? 1 : 0;
  }
  EXPECT_GT(in_contact, 10);
}

}  // namespace
}  // namespace rigidtouch::loop
