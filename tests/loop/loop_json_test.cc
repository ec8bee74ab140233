#include "loop/loop_json.h"

#include <gtest/gtest.h>

namespace rigidtouch::loop {
namespace {

TEST(LoopJson, StatsKeysCarryUnitsAndValues) {
  LoopStats stats;
  stats.rate_hz = 1000.0;
  stats.achieved_rate_hz = 999.5;
  stats.ticks = 1234;
  stats.overruns = 3;
  stats.period_error_p99_s = 2.5e-5;
  stats.warnings = {"could not set SCHED_FIFO priority 80: Operation not permitted"};
  const nlohmann::json json = ToJson(stats);
  EXPECT_EQ(json.at("rate_hz").get<double>(), 1000.0);
  EXPECT_EQ(json.at("achieved_rate_hz").get<double>(), 999.5);
  EXPECT_EQ(json.at("ticks").get<std::int64_t>(), 1234);
  EXPECT_EQ(json.at("overruns").get<std::int64_t>(), 3);
  EXPECT_EQ(json.at("period_error_p99_s").get<double>(), 2.5e-5);
  for (const char* key : {"period_error_p50_s", "period_error_p999_s", "period_error_max_s",
                          "skipped_periods", "wakeup_latency_max_s", "memory_locked",
                          "realtime_priority_active", "stop_requested", "elapsed_s"}) {
    EXPECT_TRUE(json.contains(key)) << key;
  }
  ASSERT_EQ(json.at("warnings").size(), 1u);
  EXPECT_EQ(json.at("warnings")[0].get<std::string>(), stats.warnings[0]);
}

TEST(LoopJson, TraceQueueStats) {
  TraceQueueStats stats;
  stats.pushed = 10;
  stats.dropped = 2;
  stats.written = 8;
  stats.capacity = 64;
  const nlohmann::json json = ToJson(stats);
  EXPECT_EQ(json.at("pushed").get<std::uint64_t>(), 10u);
  EXPECT_EQ(json.at("dropped").get<std::uint64_t>(), 2u);
  EXPECT_EQ(json.at("written").get<std::uint64_t>(), 8u);
  EXPECT_EQ(json.at("capacity").get<std::uint64_t>(), 64u);
}

}  // namespace
}  // namespace rigidtouch::loop
