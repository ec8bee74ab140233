// The tests in tests/bench/ need the benchmark build (MuJoCo and Bullet linked in by
// bench/CMakeLists.txt, which also defines RIGIDTOUCH_BENCH_ENABLED). In a build without
// -DRIGIDTOUCH_BUILD_BENCHMARKS=ON each file compiles to one skipped test instead.
#pragma once

#include <gtest/gtest.h>

/// Defines a test in `suite` that is skipped and says how to enable the real ones.
#define RIGIDTOUCH_BENCH_SKIPPED_TEST(suite)                                              \
  TEST(suite, NeedsBenchmarkBuild) {                                                      \
    GTEST_SKIP() << "configure with -DRIGIDTOUCH_BUILD_BENCHMARKS=ON to run these tests"; \
  }
