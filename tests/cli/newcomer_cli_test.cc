// What a newcomer reads on the terminal: a suggestion for a typo, a conversion error that names
// the flag and the type, one warning voice, rounded numbers, and one spectral figure for a tap
// in the table, the JSON and the figure.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <cmath>
#include <regex>
#include <string>

#include "cli_util.h"

namespace rigidtouch::test {
namespace {

TEST(NewcomerCliTest, ATypodFlagOrSubcommandGetsTheClosestValidOne) {
  CliResult r = RunCli("tap --rendrer train");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(
      r.err.rfind("rigidtouch: error: tap: unknown flag --rendrer; did you mean --renderer?", 0),
      0u)
      << r.err;
  EXPECT_NE(r.err.find("rigidtouch tap --help"), std::string::npos) << r.err;
  r = RunCli("study simulate --protocl x.json");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("study simulate: unknown flag --protocl; did you mean --protocol?"),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("rigidtouch study simulate --help"), std::string::npos) << r.err;
  r = RunCli("simulat --scene x.xml");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("unknown subcommand 'simulat' (did you mean 'simulate'?); valid: bench, "),
            std::string::npos)
      << r.err;
  // nothing close: no guess, the valid ones listed
  r = RunCli("tap --xyzzy 1");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("tap: unknown flag --xyzzy\n"), std::string::npos) << r.err;
}

TEST(NewcomerCliTest, AValueThatDoesNotConvertNamesTheFlagAndTheType) {
  const CliResult r = RunCli("tap --speed abc");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("rigidtouch: error: tap: --speed: 'abc' is not a number (approach speed "
                       "[m/s], in (0, 2])"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(r.err.find("Could not convert"), std::string::npos) << r.err;
}

// --renderer takes the name:material form --compare takes: the same material train
TEST(NewcomerCliTest, RendererTakesTheMaterialFormOfCompare) {
  const CliResult a = RunCli("tap --renderer train:wood --taps 1 --json");
  const CliResult b = RunCli("tap --renderer train --material wood --taps 1 --json");
  ASSERT_EQ(a.exit_code, 0) << a.err;
  ASSERT_EQ(b.exit_code, 0) << b.err;
  EXPECT_EQ(nlohmann::json::parse(a.out)["taps"], nlohmann::json::parse(b.out)["taps"]);
  EXPECT_EQ(nlohmann::json::parse(a.out)["material"], "wood");
  const CliResult both = RunCli("tap --renderer train:wood --material rubber --taps 1");
  EXPECT_EQ(both.exit_code, 2);
  EXPECT_NE(both.err.find("both name the material"), std::string::npos) << both.err;
  const CliResult penalty = RunCli("tap --renderer penalty:wood --taps 1");
  EXPECT_EQ(penalty.exit_code, 2);
  EXPECT_NE(penalty.err.find("a material goes with event or train"), std::string::npos)
      << penalty.err;
}

// a counted warning: the prefix, what it counts and how often, on stderr; never on stdout
TEST(NewcomerCliTest, CountedWarningsSpeakInTheOneVoiceOnStderr) {
  const CliResult r = RunCli("tap --renderer impulse --device touch --taps 1");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(std::regex_search(r.err, std::regex("rigidtouch: warning: the device's force limit "
                                                  "clipped the force in [0-9]+ ticks? "
                                                  "\\(force_clipped\\)\n")))
      << r.err;
  EXPECT_EQ(r.out.find("warning"), std::string::npos) << r.out;
}

// numbers rounded to their meaning: no exponent of rounding noise, no 16-digit rates
TEST(NewcomerCliTest, SimulateAndBenchPrintRoundedNumbers) {
  const std::string scene = std::string(RIGIDTOUCH_SCENES) + "/stack.xml";
  CliResult r = RunCli("simulate --scene " + scene + " --steps 50");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out.find("e-"), std::string::npos) << r.out;
  EXPECT_TRUE(std::regex_search(r.out, std::regex("position -?[0-9]+\\.[0-9]{6} "))) << r.out;
  r = RunCli("bench --scene " + scene + " --steps 50 --warmup 10 --quiet");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(std::regex_search(r.out, std::regex(": median [0-9.]+ us, p99 "))) << r.out;
  EXPECT_EQ(r.out.find(" ns"), std::string::npos) << r.out;
}

// the first word of cell `column` (1: the renderer) of the table row that starts with `row`
std::string Cell(const std::string& table, const std::string& row, int column) {
  const std::size_t at = table.find("| " + row + " |");
  if (at == std::string::npos) return "(no row " + row + ")";
  std::size_t begin = at;
  for (int c = 1; c < column; ++c) begin = table.find('|', begin + 1);
  const std::size_t end = table.find('|', begin + 1);
  std::string cell = table.substr(begin + 1, end - begin - 1);
  cell.erase(0, cell.find_first_not_of(' '));
  return cell.substr(0, cell.find(' '));
}

// One spectral figure: the 50 Hz train's transient repeats at 50 Hz and the 250 Hz train's at
// 250 Hz in the JSON, and the table file and the terminal's table say what the JSON's taps say,
// over one stated window, on `device`. A train the tool stops within two impulses (the ideal
// device's 50 Hz wall), or whose pulses a bounce puts out of step (the Falcon's), does not repeat
// within the window: "none", never a harmonic. On the Touch both trains repeat.
void ExpectTrainsRepeatAtTheirRate(const std::string& device) {
  SCOPED_TRACE(device);
  const std::string walls[] = {"wall 1: train 250 Hz", "wall 2: train 50 Hz"};
  const double rates[] = {250.0, 50.0};
  const auto dir = TempDir("walls_" + device);
  const std::string args = "tap --compare wall1,wall2 --taps 1 --device " + device +
                           " --quiet --out-dir " + dir.string();
  const CliResult json = RunCli(args + " --json");
  ASSERT_EQ(json.exit_code, 0) << json.err;
  const auto j = nlohmann::json::parse(json.out);
  const std::string file = ReadAll(dir / "compare.md");
  EXPECT_NE(file.find("over 100 ms from contact onset (10.0 Hz"), std::string::npos) << file;
  for (int w = 0; w < 2; ++w) {
    const auto& tap = j["renderers"][w]["taps"][0];
    EXPECT_NEAR(tap["spectrum_window_s"].get<double>(), 0.1, 1e-9);
    const double rate = tap["transient_repetition_hz"].get<double>();
    // the rate is the sample rate over a lag, the sample rate from the trace's rounded times
    const bool nominal = std::abs(rate - rates[w]) < 1e-6 * rates[w];
    EXPECT_TRUE(nominal || rate == 0.0) << walls[w] << " " << rate;
    const std::string cell = rate == 0.0 ? "none" : (w == 0 ? "250.0" : "50.0");
    EXPECT_EQ(Cell(file, walls[w], 12), cell) << file;
  }
  if (device != "touch") return;
  // the Touch keeps three or more pulses of each train: the rates themselves
  EXPECT_NEAR(j["renderers"][1]["taps"][0]["transient_repetition_hz"].get<double>(), 50.0, 1e-6);
  const CliResult text = RunCli(args);
  ASSERT_EQ(text.exit_code, 0) << text.err;
  EXPECT_EQ(Cell(text.out, walls[0], 7), "250.0") << text.out;
  EXPECT_EQ(Cell(text.out, walls[1], 7), "50.0") << text.out;
  EXPECT_NE(text.out.find("over 100 ms from contact onset (10.0 Hz"), std::string::npos)
      << text.out;
}

// the Touch, whose trains repeat at their rates, and the Falcon, whose 50 Hz train a bounce puts
// out of step ("none")
TEST(NewcomerCliTest, TrainsRepeatAtTheirRateInTableJsonAndTableFile) {
  for (const char* device : {"touch", "falcon"}) ExpectTrainsRepeatAtTheirRate(device);
}

// every preset device (12 taps through the CLI: 42 s under AddressSanitizer)
TEST(NewcomerCliTest, SlowTrainsRepeatAtTheirRateOnEveryPresetDevice) {
  for (const char* device : {"touch", "omni", "falcon", "omega3", "generic", "ideal"}) {
    ExpectTrainsRepeatAtTheirRate(device);
  }
}

}  // namespace
}  // namespace rigidtouch::test
