#include "device/udp_json.h"

#include <gtest/gtest.h>

namespace rigidtouch::device {
namespace {

TEST(UdpJson, CountersWithMalformedByReason) {
  UdpCounters counters;
  counters.received = 10;
  counters.accepted = 6;
  counters.watchdog_trips = 1;
  counters.malformed[static_cast<std::size_t>(DecodeResult::kNonFinite)] = 2;
  counters.malformed[static_cast<std::size_t>(DecodeResult::kTooShort)] = 1;
  const nlohmann::json json = ToJson(counters);
  EXPECT_EQ(json.at("received").get<std::uint64_t>(), 10u);
  EXPECT_EQ(json.at("accepted").get<std::uint64_t>(), 6u);
  EXPECT_EQ(json.at("watchdog_trips").get<std::uint64_t>(), 1u);
  EXPECT_EQ(json.at("malformed").at("non_finite").get<std::uint64_t>(), 2u);
  EXPECT_EQ(json.at("malformed").at("too_short").get<std::uint64_t>(), 1u);
  EXPECT_EQ(json.at("malformed").at("total").get<std::uint64_t>(), 3u);
  EXPECT_FALSE(json.at("malformed").contains("ok"));
  EXPECT_EQ(json.at("malformed").size(), kDecodeResultCount);  // 8 reasons + total
}

TEST(UdpJson, SessionAndAuthenticationCounters) {
  UdpCounters counters;
  counters.unauthenticated = 5;
  counters.replayed = 4;
  counters.no_session = 3;
  counters.handshakes = 2;
  counters.hellos_refused = 6;
  counters.session_timeouts = 1;
  counters.clamped_commands = 7;
  const nlohmann::json json = ToJson(counters);
  EXPECT_EQ(json.at("unauthenticated").get<std::uint64_t>(), 5u);
  EXPECT_EQ(json.at("replayed").get<std::uint64_t>(), 4u);
  EXPECT_EQ(json.at("no_session").get<std::uint64_t>(), 3u);
  EXPECT_EQ(json.at("handshakes").get<std::uint64_t>(), 2u);
  EXPECT_EQ(json.at("hellos_refused").get<std::uint64_t>(), 6u);
  EXPECT_EQ(json.at("session_timeouts").get<std::uint64_t>(), 1u);
  EXPECT_EQ(json.at("clamped_commands").get<std::uint64_t>(), 7u);
  EXPECT_EQ(json.at("malformed").at("total").get<std::uint64_t>(), 0u);
}

}  // namespace
}  // namespace rigidtouch::device
