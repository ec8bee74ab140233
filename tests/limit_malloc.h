// Counts the heap allocations of the calling thread by interposing the C allocator (Drake's
// LimitMalloc idea). Every allocation ends here: operator new, Eigen's dynamic matrices, C code
// and the standard library alike, which a replaced operator new alone cannot see. The interposed
// functions are in limit_malloc.cc, linked into every test executable (tests/CMakeLists.txt):
// they count only while a guard lives on the calling thread.
//
//   test::LimitMalloc guard;       // counts this thread's allocations from here
//   Tick(model, data, input);
//   EXPECT_EQ(guard.allocations(), 0);
//
// Sanitizers own malloc; under them kMallocCounting is false, nothing is interposed, and tests
// that need the count skip (GTEST_SKIP) instead of asserting nothing.
#pragma once

#include <cstddef>
#include <cstdlib>

// (gcc defines __SANITIZE_*__; clang does not, so the build's own definitions are checked too)
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__) ||       \
    defined(RIGIDTOUCH_SANITIZE) || defined(RIGIDTOUCH_SANITIZE_THREAD) || \
    defined(RIGIDTOUCH_FUZZING)
#define RIGIDTOUCH_MALLOC_COUNTING 0
#else
#define RIGIDTOUCH_MALLOC_COUNTING 1
#endif

namespace rigidtouch::test {

/// Whether allocations are counted in this build.
inline constexpr bool kMallocCounting = RIGIDTOUCH_MALLOC_COUNTING != 0;

namespace internal {
inline thread_local int malloc_guards = 0;        // live LimitMalloc objects on this thread
inline thread_local long malloc_allocations = 0;  // allocations while one was live
inline void CountAllocation() {
  if (malloc_guards > 0) ++malloc_allocations;
}
}  // namespace internal

/// Allocates 64 bytes and frees them, through the counted allocator (defined in limit_malloc.cc,
/// out of the caller's sight: a compiler may drop a malloc/free pair it can see, so a probe that
/// checks the counter works must not be written inline).
void ProbeAllocation();

/// Counts the allocations the calling thread makes while the guard lives (guards may nest; each
/// reports the count since it was made).
class LimitMalloc {
 public:
  LimitMalloc() : start_(internal::malloc_allocations) { ++internal::malloc_guards; }
  ~LimitMalloc() { --internal::malloc_guards; }
  LimitMalloc(const LimitMalloc&) = delete;
  LimitMalloc& operator=(const LimitMalloc&) = delete;
  /// Allocations since the guard was made.
  long allocations() const { return internal::malloc_allocations - start_; }

 private:
  long start_;
};

}  // namespace rigidtouch::test
