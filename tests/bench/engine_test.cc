#include "bench_test_config.h"

#ifdef RIGIDTOUCH_BENCH_ENABLED

#include <algorithm>

#include "bench/engine.h"

namespace rigidtouch::bench {
namespace {

TEST(Engine, PeersAreRegisteredInAStableOrder) {
  const std::vector<EngineEntry>& engines = Engines();
  std::vector<std::string> names;
  for (const EngineEntry& entry : engines) names.push_back(entry.name);
  const auto mujoco = std::find(names.begin(), names.end(), "mujoco");
  const auto bullet = std::find(names.begin(), names.end(), "bullet");
  ASSERT_NE(mujoco, names.end());
  ASSERT_NE(bullet, names.end());
  EXPECT_LT(bullet, mujoco);  // peers by name
  const auto reference = std::find(names.begin(), names.end(), kReferenceEngine);
  if (reference != names.end()) {
    EXPECT_EQ(reference, names.begin());
  }
}

TEST(Engine, FactoriesMakeEnginesOfTheirName) {
  for (const EngineEntry& entry : Engines()) {
    const std::unique_ptr<Engine> engine = entry.make();
    ASSERT_NE(engine, nullptr);
    EXPECT_EQ(engine->Name(), entry.name);
  }
}

}  // namespace
}  // namespace rigidtouch::bench

#else
RIGIDTOUCH_BENCH_SKIPPED_TEST(Engine)
#endif
