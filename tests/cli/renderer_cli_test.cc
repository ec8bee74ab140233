// `--renderer event --material NAME|FILE.json` and `--passivity-control` end to end: used and
// reported, or refused with the reason.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "cli/cli_util.h"

namespace rigidtouch::test {
namespace {

using nlohmann::json;

TEST(RendererCliTest, EventRendererAndPassivityControlAreUsedAndReported) {
  const CliResult r = RunCli(
      "tap --renderer event --material aluminium --device omni --speed 0.5 --taps 1 "
      "--passivity-control --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json j = json::parse(r.out);
  EXPECT_EQ(j["renderer"], "event");
  EXPECT_EQ(j["material"], "aluminium");
  EXPECT_EQ(j["passivity_control"], true);
  EXPECT_EQ(j["impulses_per_window"], 0);
  // an active configuration without the controller (docs/renderers.md): it dissipates
  EXPECT_GT(j["taps"][0]["passivity_dissipated_J"].get<double>(), 0.0);
  EXPECT_LE(j["taps"][0]["energy_to_user_J"].get<double>(), 1e-9);
  const CliResult off =
      RunCli("tap --renderer event --material aluminium --device omni --speed 0.5 --taps 1 --json");
  ASSERT_EQ(off.exit_code, 0) << off.err;
  const json k = json::parse(off.out);
  EXPECT_EQ(k["passivity_control"], false);
  EXPECT_EQ(k["taps"][0]["passivity_dissipated_J"].get<double>(), 0.0);
  EXPECT_GT(k["taps"][0]["energy_to_user_J"].get<double>(), 0.0);
}

TEST(RendererCliTest, MaterialMistakesAreRefused) {
  const std::pair<std::string, std::string> cases[] = {
      {"tap --renderer event", "material is missing"},
      {"tap --renderer impulse --material wood", "used only by the event and train renderers"},
      {"tap --renderer train --material wood --frequency 50", "give one"},
      {"tap --renderer event --material glass", "'glass'"},
  };
  for (const auto& [args, says] : cases) {
    const CliResult r = RunCli(args + " --taps 1");
    EXPECT_EQ(r.exit_code, 2) << args;
    EXPECT_NE(r.err.find("rigidtouch: error:"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(says), std::string::npos) << args << ": " << r.err;
  }
}

}  // namespace
}  // namespace rigidtouch::test
