// No heap allocation inside Tick after warm-up (STYLE.md 2): malloc and friends are interposed
// for this executable and counted while a 100-box pile runs 10,000 ticks.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>

#include "rigidtouch/rigidtouch.h"
#include "test_util.h"

#ifndef RIGIDTOUCH_SANITIZE  // the sanitizers own malloc; this test runs in the plain build

extern "C" {
void* __libc_malloc(std::size_t);
void* __libc_calloc(std::size_t, std::size_t);
void* __libc_realloc(void*, std::size_t);
void* __libc_memalign(std::size_t, std::size_t);
void __libc_free(void*);
}

namespace {
std::atomic<bool> counting{false};
std::atomic<long> allocations{0};
void Count() {
  if (counting.load(std::memory_order_relaxed)) allocations.fetch_add(1);
}
}  // namespace

extern "C" {
void* malloc(std::size_t n) {
  Count();
  return __libc_malloc(n);
}
void* calloc(std::size_t n, std::size_t s) {
  Count();
  return __libc_calloc(n, s);
}
void* realloc(void* p, std::size_t n) {
  Count();
  return __libc_realloc(p, n);
}
void* memalign(std::size_t a, std::size_t n) {
  Count();
  return __libc_memalign(a, n);
}
void* aligned_alloc(std::size_t a, std::size_t n) {
  Count();
  return __libc_memalign(a, n);
}
int posix_memalign(void** p, std::size_t a, std::size_t n) {
  Count();
  *p = __libc_memalign(a, n);
  return *p ? 0 : 12;  // ENOMEM
}
void free(void* p) {
  __libc_free(p);
}
}

namespace rigidtouch {
namespace {

TEST(TickAllocTest, NoHeapAllocationInTickOfAHundredBoxPile) {
  const std::string path = test::WriteTempFile("pile.xml", test::PileXml(5, 5, 4, 0.051, 0.21));
  for (const RendererKind kind : {RendererKind::kTrain, RendererKind::kImpulse}) {
    LoadOptions o;
    o.render.renderer = kind;
    const Model m = LoadModel(path, o);
    Data d = MakeData(m);
    TickInput in;
    in.tool_wrench.force_N = Vec3(0.0, 0.0, -2.0);
    // the probe works: an allocation outside the tick is seen
    counting = true;
    void* probe = std::malloc(64);
    counting = false;
    std::free(probe);
    ASSERT_EQ(allocations.load(), 1);
    allocations = 0;
    for (int s = 0; s < 10; ++s) Tick(m, d, in);  // warm-up
    int max_contacts = 0, impulses = 0;
    counting = true;
    for (int s = 0; s < 10000; ++s) {
      Tick(m, d, in);
      max_contacts = d.ncontact > max_contacts ? d.ncontact : max_contacts;
      impulses += d.nimpulse;
    }
    counting = false;
    EXPECT_EQ(allocations.load(), 0);
    EXPECT_GT(max_contacts, 300);  // the pile really was in contact
    EXPECT_GT(impulses, 0);        // and impulses ran
  }
}

}  // namespace
}  // namespace rigidtouch

#else
TEST(TickAllocTest, SkippedUnderSanitizers) {
  GTEST_SKIP() << "malloc is owned by the sanitizer";
}
#endif
