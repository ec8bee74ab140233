// No heap allocation inside Tick after warm-up: malloc and friends are interposed for this
// executable (limit_malloc.h) and counted while a 100-box pile runs 10,000 ticks.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>

#include "limit_malloc.h"
#include "rigidtouch/rigidtouch.h"
#include "test_util.h"

namespace rigidtouch {
namespace {

TEST(TickAllocTest, NoHeapAllocationInTickOfAHundredBoxPile) {
  if (!test::kMallocCounting) GTEST_SKIP() << "malloc is owned by the sanitizer";
  const std::string path = test::WriteTempFile("pile.xml", test::PileXml(5, 5, 4, 0.051, 0.21));
  for (const RendererKind kind : {RendererKind::kTrain, RendererKind::kImpulse}) {
    LoadOptions o;
    o.render.renderer = kind;
    const Model m = LoadModel(path, o);
    Data d = MakeData(m);
    TickInput in;
    in.tool_wrench.force_N = Vec3(0.0, 0.0, -2.0);
    {
      // the probe works: an allocation is seen
      test::LimitMalloc probe_guard;
      test::ProbeAllocation();
      ASSERT_EQ(probe_guard.allocations(), 1);
    }
    for (int s = 0; s < 10; ++s) Tick(m, d, in);  // warm-up
    int max_contacts = 0, impulses = 0;
    test::LimitMalloc guard;
    for (int s = 0; s < 10000; ++s) {
      Tick(m, d, in);
      max_contacts = d.ncontact > max_contacts ? d.ncontact : max_contacts;
      impulses += d.nimpulse;
    }
    EXPECT_EQ(guard.allocations(), 0);
    EXPECT_GT(max_contacts, 300);  // the pile really was in contact
    EXPECT_GT(impulses, 0);        // and impulses ran
  }
}

}  // namespace
}  // namespace rigidtouch

namespace rigidtouch {
namespace {

// The reference solver in the tick (--reference-solver) is preallocated and cannot throw: a tick
// whose impulse problem is non-finite counts the failed solve and the non-finite state, outputs
// the safe zero force, and allocates nothing.
TEST(TickAllocTest, ReferenceSolverOnANonFiniteStateWarnsWithoutAllocatingOrThrowing) {
  if (!test::kMallocCounting) GTEST_SKIP() << "malloc is owned by the sanitizer";
  LoadOptions o;
  o.render.renderer = RendererKind::kTrain;
  o.render.reference_solver = true;
  o.contact.stiffness_N_per_m = 0.0;  // impulses alone stop the sphere
  o.contact.damping_Ns_per_m = 0.0;
  Model m = LoadModel(test::TestScene("sphere_plane.xml"), o);
  m.gravity_W.setZero();
  Data d = MakeData(m);
  d.bodies[m.tool].v_W = Vec3(0.0, 0.0, -0.3);
  int onset = -1;
  for (int s = 0; s < 200 && onset < 0; ++s) {
    Tick(m, d, {});
    if (d.nimpulse > 0) onset = static_cast<int>(d.step) - 1;
  }
  ASSERT_GE(onset, 0) << "the sphere never reached the plane";
  // tick up to the step before the train's second impulse, then poison the velocity
  while (d.step < onset + m.schedule.interval_steps) Tick(m, d, {});
  ASSERT_EQ(d.window[m.tool].onset_step, onset);
  d.bodies[m.tool].v_W.x() = NAN;
  DeviceCommand out;
  long allocations = -1;
  {
    test::LimitMalloc guard;
    EXPECT_NO_THROW(out = Tick(m, d, {}));
    allocations = guard.allocations();
  }
  EXPECT_EQ(allocations, 0);
  EXPECT_EQ(d.warnings[static_cast<int>(Warning::kSolverFailed)].count, 1);
  EXPECT_EQ(d.warnings[static_cast<int>(Warning::kNonFiniteState)].count, 1);
  EXPECT_TRUE(out.safe_fallback);
  EXPECT_EQ(out.force_N, Vec3::Zero());
  EXPECT_EQ(d.nimpulse, 0);
}

}  // namespace
}  // namespace rigidtouch

namespace rigidtouch {
namespace {

// the event renderer's transient and the passivity controller run in the render stage: a
// directly coupled tool driven into the wall and out again, tick by tick, allocates nothing
TEST(TickAllocTest, EventTransientAndPassivityControlAllocateNothing) {
  if (!test::kMallocCounting) GTEST_SKIP() << "malloc is owned by the sanitizer";
  LoadOptions o;
  o.render.renderer = RendererKind::kEvent;
  o.render.material = {"test", 20.0, 60.0, 100.0};
  o.render.passivity_control = true;
  o.device.coupling = Coupling::kDirect;
  o.device.position_resolution_m = 1e-5;
  Model m = LoadModel(test::TestScene("sphere_plane.xml"), o);
  Data d = MakeData(m);
  TickInput in;
  const Vec3 start = m.initial[m.tool].x_W;
  const auto drive = [&](int s) {
    // down at 0.2 m/s for 0.2 s, then back up
    const double v = s < 200 ? -0.2 : 0.2;
    in.device.sequence = static_cast<std::uint64_t>(s + 1);
    in.device.velocity_mps = Vec3(0.0, 0.0, v);
    in.device.position_m =
        start + Vec3(0.0, 0.0, -0.2 * 1e-3 * std::min(s, 200) + 0.2 * 1e-3 * std::max(0, s - 200));
    return Tick(m, d, in);
  };
  drive(0);  // warm-up
  double peak_transient = 0.0, dissipated = 0.0;
  test::LimitMalloc guard;
  for (int s = 1; s < 400; ++s) {
    const DeviceCommand out = drive(s);
    peak_transient = std::max(peak_transient, out.impulsive_force_N.norm());
    dissipated = d.passivity.dissipated_J;
  }
  EXPECT_EQ(guard.allocations(), 0);
  EXPECT_GT(peak_transient, 0.0);  // the transient ran
  EXPECT_GE(dissipated, 0.0);
}

}  // namespace
}  // namespace rigidtouch
