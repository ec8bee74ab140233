// The Python example device server (examples/vendor_bridge/fake_device.py) against rigidtouch:
// `serve` renders on it under the stricter of its announced force limit and the preset's; a
// renderer holding the key that sends 1000 N (and non-finite forces) gets the device's limit
// displayed, not its command; a local process without the key moves nothing.
#include <gtest/gtest.h>
#include <signal.h>

#include <chrono>
#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>

#include "cli/cli_util.h"
#include "cli/intruder.h"
#include "device/udp_device.h"
#include "loop/test_poll.h"

namespace rigidtouch::test {
namespace {

constexpr double kDeviceLimit_N = 2.0;  // below the Touch preset's 3.3 N

// runs fake_device.py on `port` with the shared key, its limit kDeviceLimit_N, for `seconds`
pid_t SpawnFakeDevice(int port, const std::string& key, double seconds,
                      const std::filesystem::path& out) {
  const std::string script =
      std::string(RIGIDTOUCH_SOURCE_DIR) + "/examples/vendor_bridge/fake_device.py";
  return SpawnCommand("python3 " + script + " --listen udp://127.0.0.1:" + std::to_string(port) +
                          " --key " + key + " --max-force " + std::to_string(kDeviceLimit_N) +
                          " --rate 1000 --duration " + std::to_string(seconds) + " --json",
                      out.string());
}

nlohmann::json Summary(const std::filesystem::path& out) {
  const std::string text = ReadAll(out);
  EXPECT_FALSE(text.empty()) << "fake_device.py printed nothing (is python3 installed?)";
  return text.empty() ? nlohmann::json::object() : nlohmann::json::parse(text);
}

TEST(FakeDeviceTest, ServeRendersWithinTheLimitTheDeviceAnnounces) {
  const auto dir = TempDir("fake_device_serve");
  IsolateHome(dir);
  const std::string key = Keygen(dir);
  const int port = FreePort();
  const pid_t device = SpawnFakeDevice(port, key, 4.0, dir / "device.json");
  const pid_t serve =
      Spawn("serve --device udp://127.0.0.1:" + std::to_string(port) + " --key " + key +
                " --preset touch --rate 1000 --duration 2.5" + " --startup-timeout 5 --json",
            (dir / "serve.json").string());
  ASSERT_EQ(Wait(serve), 0);
  ASSERT_EQ(Wait(device), 0);

  const auto served = nlohmann::json::parse(ReadAll(dir / "serve.json"));
  EXPECT_EQ(served["force_limit_N"].get<double>(), kDeviceLimit_N) << "the stricter: the device's";
  EXPECT_GE(served["device"]["link"]["handshakes"].get<long>(), 1);
  EXPECT_GT(served["device"]["link"]["accepted"].get<long>(), 1000);
  EXPECT_TRUE(served["finite"].get<bool>());
  EXPECT_LE(served["max_force_N"].get<double>(), kDeviceLimit_N);
  // the simulated hand pushes down into the wall: it was felt, and clipped at the limit
  EXPECT_GT(served["max_force_N"].get<double>(), 0.5 * kDeviceLimit_N);

  const nlohmann::json shown = Summary(dir / "device.json");
  EXPECT_GE(shown["sessions"].get<long>(), 1);
  EXPECT_GT(shown["commands"].get<long>(), 1000);
  EXPECT_LE(shown["max_displayed_force_N"].get<double>(), kDeviceLimit_N * (1 + 1e-12));
  EXPECT_GT(shown["max_displayed_force_N"].get<double>(), 0.5 * kDeviceLimit_N);
  std::filesystem::remove_all(dir);
}

// a renderer with the key but without limits (a bug, or a user's own client): 1000 N commands
// are displayed at the device's limit, non-finite ones are dropped
TEST(FakeDeviceTest, ClampsWhatAnAuthenticatedRendererSends) {
  const auto dir = TempDir("fake_device_clamp");
  IsolateHome(dir);
  const std::string key = Keygen(dir);
  const int port = FreePort();
  const pid_t device = SpawnFakeDevice(port, key, 2.0, dir / "device.json");
  device::UdpDeviceOptions options;
  options.server = "udp://127.0.0.1:" + std::to_string(port);
  options.key_file = key;
  device::UdpDevice renderer(options);
  ASSERT_TRUE(testing::PollUntil([&] {
    renderer.Read();
    return renderer.has_session();
  })) << "no session with fake_device.py";
  EXPECT_EQ(renderer.announced_limits().max_force_N, kDeviceLimit_N);
  DeviceCommand command;
  for (int k = 0; k < 300; ++k) {
    renderer.Read();
    command.sequence = static_cast<std::uint64_t>(k) + 1;
    command.force_N = Vec3(0.0, 600.0, 800.0);  // 1000 N
    if (k % 3 == 2) command.force_N.x() = std::numeric_limits<double>::quiet_NaN();
    renderer.Write(command);
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  ASSERT_EQ(Wait(device), 0);
  const nlohmann::json shown = Summary(dir / "device.json");
  EXPECT_GT(shown["commands"].get<long>(), 100);
  EXPECT_GE(shown["dropped"].get<long>(), 50) << "the non-finite commands";
  EXPECT_NEAR(shown["max_displayed_force_N"].get<double>(), kDeviceLimit_N, 1e-9);
  std::filesystem::remove_all(dir);
}

// the review's attack on the Python device: without the key nothing starts a session and the
// device displays nothing
TEST(FakeDeviceTest, IntruderWithoutTheKeyNeverMovesIt) {
  const auto dir = TempDir("fake_device_intruder");
  IsolateHome(dir);
  const std::string key = Keygen(dir);
  const int port = FreePort();
  Intruder intruder;
  intruder.AddTarget(port);
  const pid_t device = SpawnFakeDevice(port, key, 1.5, dir / "device.json");
  intruder.Start();
  ASSERT_EQ(Wait(device), 0);
  intruder.Stop();
  const nlohmann::json shown = Summary(dir / "device.json");
  EXPECT_GT(intruder.sent(), 1000u);
  EXPECT_EQ(shown["sessions"].get<long>(), 0);
  EXPECT_EQ(shown["commands"].get<long>(), 0);
  EXPECT_EQ(shown["max_displayed_force_N"].get<double>(), 0.0);
  EXPECT_GT(shown["dropped"].get<long>(), 500);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace rigidtouch::test
