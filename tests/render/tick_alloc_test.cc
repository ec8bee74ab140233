// No heap allocation inside Tick after warm-up: malloc and friends are interposed for this
// executable (limit_malloc.h) and counted while a 100-box pile runs 10,000 ticks.
#include <gtest/gtest.h>

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
      void* volatile probe = std::malloc(64);
      std::free(probe);
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
