// `serve` with an articulated scene (scenes/door.xml: a door on a z hinge resting closed against
// its stop at 0 rad): on the simulated device the hand pushes the panel's -y face, driving the door
// into its stop, with a train at the stop; over the UDP bridge `device-sim` taps the panel's top.
// On every path the tree is stepped in the loop (its joint is reported), every command is finite
// and within the Touch's 3.3 N, and the device port gives the user no energy; a session recorded
// on the door replays to the same record byte for byte.
#include <gtest/gtest.h>
#include <signal.h>

#include <chrono>
#include <cmath>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>

#include "cli/cli_util.h"

namespace rigidtouch::test {
namespace {

const std::string kDoor = std::string(RIGIDTOUCH_SOURCE_DIR) + "/scenes/door.xml";
// the panel's -y face at the tool's height, 0.6 m from the hinge; the hand pushes along +y. The
// door lies 1 to 1.2 m from the origin, beyond the default plausible radius of a device (1 m):
// the simulated hand's is widened to 0.5 m beyond the wall and the scene's tool
const std::string kPushPanel = " --wall-point 0.6 -0.02 1.0 --wall-normal 0 -1 0";

// the door's one joint, as serve reports it after the run
const nlohmann::json& Hinge(const nlohmann::json& j) {
  EXPECT_EQ(j["joints"].size(), 1u) << j.dump();
  EXPECT_EQ(j["joints"][0]["name"], "hinge");
  EXPECT_EQ(j["joints"][0]["type"], "hinge");
  return j["joints"][0];
}

void ExpectSafeCommands(const nlohmann::json& j) {
  ASSERT_TRUE(j["max_force_N"].is_number()) << j.dump();
  EXPECT_TRUE(j["finite"].get<bool>());
  EXPECT_EQ(j["non_finite_commands"].get<long>(), 0);
  EXPECT_LE(j["max_force_N"].get<double>(), 3.3);  // the Touch's limit
  EXPECT_GT(j["impulses"].get<long>(), 0);         // the tool met the panel
}

// Energy at the port: the simulated device integrates F_displayed . dx over every step of its
// own plant (SimulatedDevice::energy_to_user_J, exact for a force held over the step; device-sim
// reports its own); a passive rendering of taps that start and end out of contact keeps it <= 0.
// Measured -3.8e-3 J for one tap on the sim path and -1.0e-2 J for three over the bridge. The
// tolerance, 1e-4 J, is a margin under 1 % of what one active impulse would give the hand
// (m v^2 / 2 = 0.6 kg (0.2 m/s)^2 / 2 = 1.2e-2 J for the Touch and hand at the tap's speed).
constexpr double kEnergyTolerance_J = 1e-4;

TEST(ServeTreeCliTest, DoorStopTrainOnTheSimulatedDeviceGivesTheUserNoEnergy) {
  const CliResult r =
      RunCli("serve --scene " + kDoor + " --connect sim --taps 1 --joint-limit-renderer train" +
             kPushPanel + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  ExpectSafeCommands(j);
  EXPECT_LE(j["device"]["energy_to_user_J"].get<double>(), kEnergyTolerance_J) << j.dump();
  // the door was pushed into its stop and held there: its angle stays within 0.01 rad (0.6
  // degrees) of 0, and it is at its limit or within it after the hand left
  const auto& hinge = Hinge(j);
  EXPECT_LT(std::abs(hinge["position"].get<double>()), 0.01);
  EXPECT_LE(hinge["position"].get<double>(), 1e-3);
  EXPECT_TRUE(std::isfinite(hinge["velocity"].get<double>()));
}

TEST(ServeTreeCliTest, DoorSessionRecordedAndReplayedBitForBit) {
  const auto dir = TempDir("serve_tree_replay");
  const std::string rec = (dir / "door.csv").string(), again = (dir / "again.csv").string();
  const CliResult a = RunCli("serve --scene " + kDoor + " --connect sim --taps 1" + kPushPanel +
                             " --record " + rec + " --json");
  ASSERT_EQ(a.exit_code, 0) << a.err;
  const auto ja = nlohmann::json::parse(a.out);
  ExpectSafeCommands(ja);
  const CliResult b = RunCli("serve --scene " + kDoor + " --connect replay:" + rec +
                             " --replay-pace max --record " + again + " --json");
  ASSERT_EQ(b.exit_code, 0) << b.err;
  const auto jb = nlohmann::json::parse(b.out);
  EXPECT_EQ(jb["device"]["replayed_ticks"].get<long>(), ja["loop"]["ticks"].get<long>());
  EXPECT_EQ(jb["impulses"], ja["impulses"]);
  EXPECT_EQ(jb["joints"], ja["joints"]);  // the door ends where it ended, to the last bit
  EXPECT_TRUE(ReadAll(again) == ReadAll(rec));
  std::filesystem::remove_all(dir);
}

// device-sim taps straight down; the workspace offset puts its handle over the panel's top face
// (z = 1.9 m, where the tool's centre touches at device height 5 mm + 1.895 m), 0.6 m from the
// hinge
TEST(ServeTreeCliTest, DoorOverTheUdpBridge) {
  const auto dir = TempDir("serve_tree_udp");
  const std::string addr = "udp://127.0.0.1:" + std::to_string(FreePort());
  const pid_t serve = Spawn("serve --scene " + kDoor + " --connect " + addr +
                                " --workspace-offset 0.6 0 1.895 --rate 1000 --duration 1.6"
                                " --startup-timeout 5 --json",
                            (dir / "serve.json").string());
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  const pid_t sim = Spawn(
      "device-sim --listen " + addr + " --rate 1000 --taps 1 --speed 0.2 --duration 10 --json",
      (dir / "sim.json").string());
  ASSERT_EQ(Wait(serve), 0);
  ::kill(sim, SIGTERM);
  Wait(sim);
  const auto j = nlohmann::json::parse(ReadAll(dir / "serve.json"));
  ExpectSafeCommands(j);
  EXPECT_EQ(j["device"]["kind"], "udp");
  const auto& hinge = Hinge(j);
  // a vertical push on the panel's top does not turn the door (the hinge is vertical)
  EXPECT_LT(std::abs(hinge["position"].get<double>()), 1e-3);
  const auto s = nlohmann::json::parse(ReadAll(dir / "sim.json"));
  EXPECT_LE(s["energy_to_user_J"].get<double>(), kEnergyTolerance_J) << s.dump();
  std::filesystem::remove_all(dir);
}

// the simulated hand's aim on the bridge, and the bridge's workspace offset elsewhere, are refused
TEST(ServeTreeCliTest, AimAndOffsetFlagsOfAnotherDeviceAreRefused) {
  const std::string addr = "udp://127.0.0.1:" + std::to_string(FreePort());
  const CliResult aim =
      RunCli("serve --connect " + addr + " --wall-point 0 0 0 --wall-normal 0 0 1 --duration 0.01");
  EXPECT_EQ(aim.exit_code, 2) << aim.err;
  EXPECT_NE(aim.err.find("rigidtouch: error: serve: --wall-geom and --wall-point"),
            std::string::npos)
      << aim.err;
  const CliResult offset = RunCli("serve --connect sim --workspace-offset 0 0 1 --duration 0.01");
  EXPECT_EQ(offset.exit_code, 2) << offset.err;
  EXPECT_NE(offset.err.find("--workspace-offset applies to --connect udp://HOST:PORT only"),
            std::string::npos)
      << offset.err;
}

}  // namespace
}  // namespace rigidtouch::test
