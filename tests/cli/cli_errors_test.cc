// The typo finder behind "did you mean" (apps/rigidtouch/cli_errors.h).
#include "rigidtouch/cli_errors.h"

#include <gtest/gtest.h>

namespace rigidtouch::cli {
namespace {

TEST(CliErrorsTest, EditDistanceClosedForms) {
  EXPECT_EQ(EditDistance("", ""), 0);
  EXPECT_EQ(EditDistance("abc", ""), 3);
  EXPECT_EQ(EditDistance("--rendrer", "--renderer"), 1);  // one insertion
  EXPECT_EQ(EditDistance("kitten", "sitting"), 3);
  EXPECT_EQ(EditDistance("simulat", "simulate"), 1);
}

TEST(CliErrorsTest, ClosestOnlyForATypo) {
  const std::vector<std::string> flags = {"--renderer", "--restitution", "--rate", "--taps"};
  EXPECT_EQ(Closest("--rendrer", flags), "--renderer");
  EXPECT_EQ(Closest("--tap", flags), "--taps");
  EXPECT_EQ(Closest("--xyzzy", flags), "");
  // a short word is not a typo of anything two edits away
  EXPECT_EQ(Closest("ab", {"cd"}), "");
}

}  // namespace
}  // namespace rigidtouch::cli
