// Tap recordings (io/tap_recording.h): the columns and units read, and each bad recording refused
// with "FILE:LINE: reason".
#include "io/tap_recording.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "rigidtouch/types.h"

namespace rigidtouch::io {
namespace {

std::string RecordingError(const std::string& text) {
  try {
    ParseTapRecording(text, "rec.csv");
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(TapRecordingTest, ReadsColumnsAndTaps) {
  const TapRecording r = ParseTapRecording(
      "# a comment\n"
      "time_s, force_N, position_m, tap\n"
      "0.000, 0.0, 0.010, 3\n"
      "0.001, 0.5, 0.009, 3\n"
      "\n"
      "0.000, 0.1, 0.010, 4\n"
      "0.001, 0.2, 0.009, 4\n",
      "rec.csv");
  EXPECT_EQ(r.quantity, TapQuantity::kForce);
  ASSERT_EQ(r.taps.size(), 2u);
  EXPECT_EQ(r.taps[0].tap, 3);
  EXPECT_EQ(r.taps[1].tap, 4);
  EXPECT_EQ(r.taps[1].line, (std::vector<int>{6, 7}));
  EXPECT_EQ(r.taps[0].position_m, (std::vector<double>{0.010, 0.009}));
  EXPECT_TRUE(r.taps[0].velocity_mps.empty());
}

// each bad recording: the file, the line, and what is wrong
TEST(TapRecordingTest, BadRecordingsNameTheFileAndLine) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"", "rec.csv:1: empty recording"},
      {"# only a comment\n\n", "rec.csv:1: empty recording"},
      {"0.0,1.0\n0.001,2.0\n", "rec.csv:1: no header"},
      {"time_s,acceleration_g,velocity_mps\n0,1,0\n",
       "rec.csv:1: column \"acceleration_g\" has a "
       "unit rigidtouch does not read"},
      {"time_ms,force_N\n0,1\n", "rec.csv:1: column \"time_ms\" has a unit"},
      {"time_s,force_N,colour\n", "rec.csv:1: unknown column \"colour\""},
      {"time_s,velocity_mps\n0,1\n", "rec.csv:1: give exactly one signal column"},
      {"time_s,force_N,acceleration_mps2\n", "rec.csv:1: give exactly one signal column"},
      {"time_s,force_N,force_N\n", "rec.csv:1: column \"force_N\" is given twice"},
      {"time_s,force_N\n0,1\n0.002,1\n0.001,1\n", "rec.csv:4: time_s 0.001 is not after"},
      {"time_s,force_N\n0,1\n0.001,nan\n", "rec.csv:3: column force_N: nan is not a finite"},
      {"time_s,force_N\n0,1\n0.001,x\n", "rec.csv:3: column force_N: \"x\" is not a number"},
      {"time_s,force_N\n0,1\n0.001\n", "rec.csv:3: has 1 values; the header names 2 columns"},
      {"time_s,force_N\n0,1\n", "rec.csv:2: tap 0 has one sample"},
      {"time_s,force_N\n", "rec.csv:1: no samples after the header"},
      {"time_s,force_N,tap\n0,1,0\n0.001,1,0\n0,1,1\n0.001,1,1\n0.002,1,0\n",
       "rec.csv:6: tap 0 comes back"},
      {"time_s,force_N,tap\n0,1,0.5\n", "rec.csv:2: column tap: 0.5 is not an integer"},
  };
  for (const auto& [text, expected] : cases) {
    const std::string e = RecordingError(text);
    EXPECT_NE(e.find(expected), std::string::npos) << "got: " << e << "\nwanted: " << expected;
  }
}

TEST(TapRecordingTest, AMissingFileNamesIt) {
  try {
    ReadTapRecording("no/such/recording.csv");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("no/such/recording.csv:1: cannot open"),
              std::string::npos);
  }
}

}  // namespace
}  // namespace rigidtouch::io
