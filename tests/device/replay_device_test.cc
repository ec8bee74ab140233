// The replay device reports the recorded states one period at a time, whatever is commanded, with
// the recorded annotations; past the end it reports an invalid state (zero force) and Ended.
#include "device/replay_device.h"

#include <gtest/gtest.h>

#include <vector>

namespace rigidtouch::device {
namespace {

std::vector<io::RecordSample> Samples(int n) {
  std::vector<io::RecordSample> out(static_cast<std::size_t>(n));
  for (int k = 0; k < n; ++k) {
    io::RecordSample& r = out[static_cast<std::size_t>(k)];
    r.tick = k;
    r.tap = k == 1 ? 0 : -1;
    r.state.sequence = static_cast<std::uint64_t>(10 + k);
    r.state.position_m = Vec3(0.0, 0.0, 0.01 * k);
    r.hand_force_N = Vec3(0.0, 0.0, -1.0 * k);
  }
  return out;
}

TEST(ReplayDevice, ReportsEachRecordedStateOncePerPeriodThenEnds) {
  DeviceLimits limits;
  limits.max_force_N = 3.3;
  ReplayDevice dev(Samples(3), limits);
  EXPECT_EQ(dev.limits().max_force_N, 3.3);
  EXPECT_EQ(dev.size(), 3);
  for (int k = 0; k < 3; ++k) {
    ASSERT_FALSE(dev.Ended());
    const DeviceState s = dev.Read();
    EXPECT_TRUE(s.valid);
    EXPECT_EQ(s.sequence, static_cast<std::uint64_t>(10 + k));
    EXPECT_EQ(s.position_m.z(), 0.01 * k);
    EXPECT_EQ(dev.Read().sequence, s.sequence);  // reading twice does not advance
    DeviceCommand c;
    c.force_N = Vec3(0.0, 0.0, 100.0);  // whatever is commanded, the recorded motion stays
    dev.Write(c);
    EXPECT_EQ(dev.commanded_force_N().z(), 100.0);
    TraceSample t;
    dev.AnnotateTrace(t);
    EXPECT_EQ(t.tap, k == 1 ? 0 : -1);
    EXPECT_EQ(t.hand_force_N.z(), -1.0 * k);
    dev.EndPeriod(1e-3);
  }
  EXPECT_TRUE(dev.Ended());
  EXPECT_EQ(dev.position(), 3);
  const DeviceState after = dev.Read();
  EXPECT_FALSE(after.valid);  // the loop outputs zero force past the record
  EXPECT_EQ(after.position_m.z(), 0.02);
  TraceSample t;
  dev.AnnotateTrace(t);
  EXPECT_EQ(t.tap, -1);
  dev.EndPeriod(1e-3);
  EXPECT_EQ(dev.position(), 3);
}

TEST(ReplayDevice, EmptyRecordIsRefused) {
  EXPECT_THROW(ReplayDevice({}, DeviceLimits{}), Error);
}

}  // namespace
}  // namespace rigidtouch::device
