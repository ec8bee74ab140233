#include "device/udp_link.h"

#include <gtest/gtest.h>

#include <string>

#include "rigidtouch/types.h"

namespace rigidtouch::device {
namespace {

TEST(UdpLink, LossSimulatorDropsTheRequestedFractionReproducibly) {
  const PacketLoss loss{0.05, 0.5, 7};
  LossSimulator a(loss);
  LossSimulator b(loss);
  constexpr int kDraws = 100000;
  int incoming = 0;
  int outgoing = 0;
  for (int i = 0; i < kDraws; ++i) {
    const bool in = a.DropIncoming();
    const bool out = a.DropOutgoing();
    EXPECT_EQ(in, b.DropIncoming());  // same seed, same decisions
    EXPECT_EQ(out, b.DropOutgoing());
    incoming += in ? 1 : 0;
    outgoing += out ? 1 : 0;
  }
  // binomial: sd = sqrt(n p (1 - p)) = 69 and 158 draws; 5 sd bounds
  EXPECT_NEAR(incoming, 0.05 * kDraws, 5 * 69);
  EXPECT_NEAR(outgoing, 0.5 * kDraws, 5 * 158);
}

TEST(UdpLink, NoLossNeverDropsAndFullLossAlwaysDrops) {
  LossSimulator none(PacketLoss{});
  LossSimulator all(PacketLoss{1.0, 1.0, 1});
  for (int i = 0; i < 1000; ++i) {
    EXPECT_FALSE(none.DropIncoming());
    EXPECT_FALSE(none.DropOutgoing());
    EXPECT_TRUE(all.DropIncoming());
    EXPECT_TRUE(all.DropOutgoing());
  }
}

TEST(UdpLink, ValidationNamesTheField) {
  try {
    ValidatePacketLoss(PacketLoss{0.0, -0.1, 1}, "udp device server");
    FAIL();
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("test_loss.outgoing_fraction"), std::string::npos);
    EXPECT_NE(std::string(error.what()).find("[0, 1]"), std::string::npos);
  }
  EXPECT_THROW(ValidateWatchdog(0.0, "x"), Error);
  EXPECT_THROW(ValidateWatchdog(11.0, "x"), Error);
  EXPECT_THROW(ValidateWatchdog(std::nan(""), "x"), Error);
  EXPECT_NO_THROW(ValidateWatchdog(0.02, "x"));
}

TEST(UdpLink, MalformedTotalSumsEveryReason) {
  UdpCounters counters;
  counters.malformed[static_cast<std::size_t>(DecodeResult::kTooShort)] = 3;
  counters.malformed[static_cast<std::size_t>(DecodeResult::kWrongVersion)] = 4;
  EXPECT_EQ(counters.MalformedTotal(), 7u);
  EXPECT_EQ(counters.Malformed(DecodeResult::kWrongVersion), 4u);
}

}  // namespace
}  // namespace rigidtouch::device
