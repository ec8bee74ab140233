// Progress of long work: silent for the first 2 s, then a line at most every 2 s (a bar redrawn
// in place on a terminal), the time left estimated from the rate since the first report, nothing
// with --quiet, and a stop request turned into Interrupted with 128 + signal for the CLI.
#include "base/progress.h"

#include <gtest/gtest.h>

#include <atomic>
#include <sstream>
#include <string>
#include <vector>

namespace rigidtouch {
namespace {

double fake_now_s = 0.0;
double FakeClock() {
  return fake_now_s;
}

std::vector<std::string> Lines(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) out.push_back(line);
  return out;
}

TEST(ProgressTest, SilentAtFirstThenALineAtMostEveryTwoSeconds) {
  fake_now_s = 50.0;
  std::ostringstream out;
  Progress p(out, "study simulate", Progress::Options{}, nullptr, nullptr, &FakeClock);
  // a report every 0.25 s for 9 s
  for (int k = 0; k <= 36; ++k) {
    fake_now_s = 50.0 + 0.25 * k;
    if (p.Due()) p.Report(k / 36.0, "participant 1 of 1");
    p.Report(k / 36.0, "participant 1 of 1");  // Report checks Due itself too
  }
  const std::vector<std::string> lines = Lines(out.str());
  // due at 2, 4, 6 and 8 s
  ASSERT_EQ(lines.size(), 4u) << out.str();
  EXPECT_EQ(p.printed(), 4);
  for (const std::string& line : lines) {
    EXPECT_EQ(line.rfind("rigidtouch: progress: study simulate: ", 0), 0u) << line;
  }
  // at 2 s: 8/36 done since the first report at 0 s: 28/36 left at the same rate is 7 s
  EXPECT_EQ(lines[0],
            "rigidtouch: progress: study simulate: 22% (participant 1 of 1), 2.0 s elapsed, "
            "about 7.0 s left");
}

TEST(ProgressTest, TheTimeLeftCountsFromTheFirstReportNotFromWorkDoneBefore) {
  fake_now_s = 0.0;
  std::ostringstream out;
  Progress p(out, "task", Progress::Options{}, nullptr, nullptr, &FakeClock);
  fake_now_s = 1.0;
  p.Report(0.5, "");  // a resumed run starts half done
  fake_now_s = 3.0;
  p.Report(0.6, "");  // 0.1 in 2 s: 0.4 left takes 8 s
  EXPECT_EQ(out.str(), "rigidtouch: progress: task: 60%, 3.0 s elapsed, about 8.0 s left\n");
  // before any progress since the first report there is no rate
  EXPECT_EQ(p.Text(0.5, "", 1.0), "50%, 1.0 s elapsed, estimating the time left");
  p.Restart("task: next phase");
  fake_now_s = 5.0;
  p.Report(0.0, "x");
  EXPECT_NE(out.str().find("task: next phase: 0% (x), 5.0 s elapsed, estimating the time left"),
            std::string::npos)
      << out.str();
}

TEST(ProgressTest, ATerminalGetsOneBarRedrawnInPlaceAndEndedOnce) {
  fake_now_s = 0.0;
  std::ostringstream out;
  Progress::Options o;
  o.terminal = true;
  {
    Progress p(out, "bench", o, nullptr, nullptr, &FakeClock);
    fake_now_s = 2.0;
    p.Report(0.25, "");
    fake_now_s = 2.05;  // within a tenth of a second: not redrawn
    p.Report(0.3, "");
    fake_now_s = 2.2;
    p.Report(0.5, "");
    EXPECT_EQ(p.printed(), 2);
  }  // the destructor ends the line
  const std::string s = out.str();
  EXPECT_EQ(s.find("\n"), s.size() - 1) << s;
  EXPECT_NE(s.find("\r\033[Kbench [######..................] 25%"), std::string::npos) << s;
  EXPECT_NE(s.find("\r\033[Kbench [############............] 50%"), std::string::npos) << s;
}

TEST(ProgressTest, QuietPrintsNothingButStillStops) {
  fake_now_s = 0.0;
  std::ostringstream out;
  Progress::Options o;
  o.enabled = false;
  std::atomic<bool> stop{false};
  std::atomic<int> signal{0};
  Progress p(out, "study predict", o, &stop, &signal, &FakeClock);
  for (int k = 0; k < 100; ++k) {
    fake_now_s = k;
    p.Report(k / 100.0, "cohort");
  }
  EXPECT_EQ(out.str(), "");
  EXPECT_NO_THROW(p.ThrowIfStopped("cohort 3 of 9", "nothing was written"));
  signal = 15;
  stop = true;
  try {
    p.ThrowIfStopped("cohort 3 of 9", "nothing was written");
    FAIL() << "no Interrupted";
  } catch (const Interrupted& e) {
    EXPECT_EQ(e.signal(), 15);
    EXPECT_STREQ(e.what(), "study predict stopped at cohort 3 of 9; nothing was written");
  }
  signal = 0;  // a flag set without a recorded signal: Ctrl-C's
  EXPECT_EQ(p.StopSignal(), 2);
}

TEST(ProgressTest, DurationsForPeople) {
  EXPECT_EQ(FormatDuration(0.44), "0.4 s");
  EXPECT_EQ(FormatDuration(12.2), "12 s");
  EXPECT_EQ(FormatDuration(185.0), "3 min 05 s");
  EXPECT_EQ(FormatDuration(2 * 3600.0 + 7 * 60.0), "2 h 07 min");
  EXPECT_EQ(FormatDuration(-1.0), "0.0 s");
}

}  // namespace
}  // namespace rigidtouch
