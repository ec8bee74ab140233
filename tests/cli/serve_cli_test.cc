// `serve` end to end against device limits: over the UDP bridge with `device-sim` (Touch preset,
// 3.3 N) no command exceeds the preset's force and clipping is reported; a stiffness the device
// cannot display is refused; no answering device is an error with its own exit status.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "cli/cli_util.h"

namespace rigidtouch::test {
namespace {

// the Touch (3.3 N, 400 N/m) on its stiffest wall: taps at 0.2 m/s stop with impulses of
// m v / h, far above 3.3 N, so the limit must clip, and nothing sent may exceed it
TEST(ServeCliTest, UdpPathKeepsEveryCommandWithinThePresetsForce) {
  const auto dir = TempDir("serve_limits");
  const std::string addr = "udp://127.0.0.1:" + std::to_string(FreePort());
  const pid_t serve = Spawn("serve --device " + addr +
                                " --preset touch --stiffness 400 --rate 1000 --duration 2.5"
                                " --startup-timeout 5 --json",
                            (dir / "serve.json").string());
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  const pid_t sim = Spawn("device-sim --listen " + addr +
                              " --preset touch --rate 1000 --taps 20 --speed 0.2 --duration 10",
                          (dir / "sim.json").string());
  ASSERT_EQ(Wait(serve), 0);
  ::kill(sim, SIGTERM);
  Wait(sim);

  const auto j = nlohmann::json::parse(ReadAll(dir / "serve.json"));
  ASSERT_TRUE(j["max_force_N"].is_number()) << j.dump();  // never null
  EXPECT_LE(j["max_force_N"].get<double>(), 3.3);
  EXPECT_GT(j["max_force_N"].get<double>(), 3.0);  // the wall was reached
  EXPECT_GT(j["clipped_ticks"].get<long>(), 0);
  EXPECT_GT(j["warnings"]["force_clipped"].get<long>(), 0);
  EXPECT_GT(j["impulses"].get<long>(), 0);
  EXPECT_TRUE(j["finite"].get<bool>());
  EXPECT_EQ(j["limits"]["max_force_N"].get<double>(), 3.3);
  EXPECT_EQ(j["force_limit_N"].get<double>(), 3.3);
  EXPECT_EQ(j["contact"]["stiffness_N_per_m"].get<double>(), 400.0);
  std::filesystem::remove_all(dir);
}

// stiffness by flag or config above the preset's, on either device path, is refused before
// anything runs, naming the parameter and the limit (exit status 2)
TEST(ServeCliTest, StiffnessAboveTheDevicesIsRefused) {
  const std::string config = (TempDir("serve_config") / "stiff.json").string();
  std::ofstream(config) << R"({"contact": {"stiffness_N_per_m": 1e308}})";
  const std::string addr = "udp://127.0.0.1:" + std::to_string(FreePort());
  for (const std::string& args : {"serve --device " + addr + " --stiffness 1e300",
                                  "serve --device " + addr + " --config " + config,
                                  std::string("serve --device sim --stiffness 1e300"),
                                  "serve --device " + addr + " --preset touch --damping 50"}) {
    const CliResult r = RunCli(args + " --json");
    EXPECT_EQ(r.exit_code, 2) << args;
    EXPECT_TRUE(r.out.empty()) << r.out;
    const bool damping = args.find("--damping") != std::string::npos;
    EXPECT_NE(r.err.find(damping ? "damping_Ns_per_m = 50" : "stiffness_N_per_m = 1e+30"),
              std::string::npos)
        << r.err;
    EXPECT_NE(r.err.find(damping ? "max_damping_Ns_per_m = 4 " : "max_stiffness_N_per_m = 400"),
              std::string::npos)
        << r.err;
  }
}

// the bridge's flags with the in-process simulated device, and the simulated hand's with the
// bridge, were accepted and unused (even out of range: --test-drop 2, --watchdog -1)
TEST(ServeCliTest, FlagsOfAnotherDeviceAreRefused) {
  for (const std::string flag :
       {"--key /nonexistent/k.key", "--watchdog -1", "--test-drop 2", "--startup-timeout 5"}) {
    const CliResult r = RunCli("serve --device sim --duration 0.01 " + flag);
    EXPECT_EQ(r.exit_code, 2) << flag << "\n" << r.err;
    const std::string name = flag.substr(0, flag.find(' '));
    EXPECT_NE(r.err.find("rigidtouch: error: serve: " + name +
                         " applies to --connect udp://HOST:PORT only"),
              std::string::npos)
        << r.err;
  }
  const std::string addr = "udp://127.0.0.1:" + std::to_string(FreePort());
  const CliResult taps = RunCli("serve --connect " + addr + " --taps 2 --duration 0.01");
  EXPECT_EQ(taps.exit_code, 2) << taps.err;
  EXPECT_NE(taps.err.find("a device through the bridge is moved by its own hand"),
            std::string::npos)
      << taps.err;
}

// no device server: a clear message after the startup timeout, exit status 5, not 0
TEST(ServeCliTest, NoAnsweringDeviceFailsAfterTheStartupTimeout) {
  const std::string addr = "udp://127.0.0.1:" + std::to_string(FreePort());
  const auto t0 = std::chrono::steady_clock::now();
  const CliResult r = RunCli("serve --device " + addr + " --startup-timeout 0.3 --json");
  const double took_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_EQ(r.exit_code, 5) << r.err;
  EXPECT_TRUE(r.out.empty()) << r.out;
  EXPECT_NE(r.err.find("no state from the device at " + addr), std::string::npos) << r.err;
  EXPECT_GE(took_s, 0.3);
  EXPECT_LT(took_s, 5.0);
}

// an acceleration material on a device of another mass: serve converts it on both device paths
// (simulated, and the bridge, whose note comes before the session looks for the device) and says
// so once with the rendered amplitude (docs/materials.md, "From acceleration to force")
TEST(ServeCliTest, AnAccelerationMaterialIsConvertedForTheDevice) {
  const auto dir = TempDir("serve_material");
  const std::string material = (dir / "accel.json").string();
  const std::string device = (dir / "heavy.json").string();
  std::ofstream(material) << nlohmann::json{
      {"name", "accel"},
      {"amplitude_Ns_per_m", 15.0},
      {"decay_per_s", 60},
      {"frequency_hz", 100},
      {"amplitude_quantity", "acceleration"},
      {"amplitude_mps2_per_mps", 25.0},
      {"effective_mass_kg", 0.6}}.dump();
  std::ofstream(device) << nlohmann::json{{"name", "heavy"},
                                          {"max_force_N", 0},
                                          {"max_stiffness_N_per_m", 0},
                                          {"max_damping_Ns_per_m", 0},
                                          {"apparent_mass_kg", 0.646},
                                          {"encoder_resolution_m", 1e-6},
                                          {"velocity_filter_hz", 100},
                                          {"delay_ticks", 0}}
                               .dump();
  const std::string flags =
      " --device " + device + " --renderer event --material " + material + " --json";
  const std::string note =
      "rigidtouch: note: material 'accel' was fitted as an acceleration with effective mass "
      "0.6 kg; on heavy (effective mass 1.2 kg) its amplitude is 25 (m/s^2)/(m/s) x 1.2 kg = 30 "
      "N/(m/s)";
  const CliResult sim = RunCli("serve --connect sim --taps 1 --duration 1" + flags);
  EXPECT_EQ(sim.exit_code, 0) << sim.err;
  EXPECT_NE(sim.err.find(note), std::string::npos) << sim.err;
  const std::string addr = "udp://127.0.0.1:" + std::to_string(FreePort());
  const CliResult bridge = RunCli("serve --connect " + addr + " --startup-timeout 0.3" + flags);
  EXPECT_EQ(bridge.exit_code, 5) << bridge.err;
  EXPECT_NE(bridge.err.find(note), std::string::npos) << bridge.err;
  EXPECT_EQ(bridge.err.find(note), bridge.err.rfind(note)) << bridge.err;
}

// an output path that cannot be written is refused before the session, not after it
TEST(ServeCliTest, UnwritableTracePathIsRefusedBeforeTheSession) {
  const auto t0 = std::chrono::steady_clock::now();
  const CliResult r =
      RunCli("serve --device sim --duration 30 --trace /nonexistent-folder/t.csv --json");
  const double took_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("/nonexistent-folder/t.csv"), std::string::npos) << r.err;
  EXPECT_LT(took_s, 5.0);  // the 30 s session never ran
}

// the plausibility limits a config file sets are used by serve, and its flags override them one
// by one (the flags' defaults used to override the config silently)
TEST(ServeCliTest, PlausibilityLimitsFromTheConfigAndTheFlags) {
  const std::filesystem::path dir = TempDir("plausible");
  const std::string config = (dir / "c.json").string();
  std::ofstream(config) << R"({"device": {"plausible_radius_m": 0.4, "plausible_speed_mps": 3}})";
  const std::string serve =
      "serve --device sim --rate 1000 --duration 0.2 --taps 1 --json --config " + config;
  for (const auto& [flags, radius] :
       std::vector<std::pair<std::string, double>>{{"", 0.4}, {" --max-device-radius 0.6", 0.6}}) {
    const CliResult r = RunCli(serve + flags);
    ASSERT_EQ(r.exit_code, 0) << flags << "\n" << r.err;
    const auto j = nlohmann::json::parse(r.out);
    EXPECT_EQ(j["limits"]["plausible_radius_m"].get<double>(), radius) << flags;
    EXPECT_EQ(j["limits"]["plausible_speed_mps"].get<double>(), 3.0) << flags;
  }
  std::filesystem::remove_all(dir);
}

// the connection a config file names (device.connect) is serve's; --connect overrides it; a value
// that is no connection is refused naming the file and the field
TEST(ServeCliTest, ConnectionFromTheConfigAndTheFlag) {
  const std::filesystem::path dir = TempDir("connect");
  const std::string config = (dir / "c.json").string();
  const std::string addr = "udp://127.0.0.1:" + std::to_string(FreePort());
  std::ofstream(config) << R"({"device": {"connect": ")" << addr << R"("}})";
  const std::string serve = "serve --rate 1000 --duration 0.2 --json --config " + config;
  // nothing answers at the config's address: the bridge was tried
  const CliResult bridged = RunCli(serve + " --startup-timeout 0.3");
  EXPECT_EQ(bridged.exit_code, 5) << bridged.err;
  EXPECT_NE(bridged.err.find("no state from the device at " + addr), std::string::npos)
      << bridged.err;
  const CliResult sim = RunCli(serve + " --connect sim --taps 1");
  EXPECT_EQ(sim.exit_code, 0) << sim.err;
  for (const char* bad : {"tcp://127.0.0.1:9", "udp://", "touch"}) {
    std::ofstream(config) << R"({"device": {"connect": ")" << bad << R"("}})";
    const CliResult r = RunCli(serve);
    EXPECT_EQ(r.exit_code, 2) << bad << "\n" << r.err;
    EXPECT_NE(r.err.find(config + ": device.connect"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(bad), std::string::npos) << r.err;
  }
  // tap, simulate and bench connect to no device: the field is refused, not ignored
  std::ofstream(config) << R"({"device": {"connect": "sim"}})";
  const CliResult tap = RunCli("tap --taps 1 --json --config " + config);
  EXPECT_EQ(tap.exit_code, 2) << tap.err;
  EXPECT_NE(tap.err.find("device.connect"), std::string::npos) << tap.err;
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace rigidtouch::test
