// Issue 51, end to end over loopback: a process without the key records a renderer's handshake
// and replays it after the session ended, while a new renderer connects (no session for the
// replayer, the renderer connects, the refusals are counted); and a renderer stopped with
// SIGSTOP for 0.3 s in contact answers no old state on resume.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <fstream>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <thread>
#include <vector>

#include "cli/cli_util.h"
#include "cli/intruder.h"
#include "device/udp_protocol.h"
#include "device/udp_socket.h"
#include "rigidtouch/bridge.h"
#include "rigidtouch/device.h"

namespace rigidtouch::test {
namespace {

using Bytes = std::vector<std::uint8_t>;

// A relay between serve and device-sim that holds no key: it forwards every datagram, records
// the first hello, confirming hello and hello-reply it sees, and, once told to, replays the
// recorded hello and confirmation to the device from a socket of its own (another address, as a
// process that only listened would) and the recorded hello-reply to the renderer every 100 ms.
class RecordingRelay {
 public:
  explicit RecordingRelay(int device_port)
      : relay_(device::UdpEndpoint{0x7f000001u, 0}, "relay"),
        replayer_(device::UdpEndpoint{0x7f000001u, 0}, "replayer"),
        device_{0x7f000001u, static_cast<std::uint16_t>(device_port)} {
    thread_ = std::thread([this] { Run(); });
  }
  ~RecordingRelay() {
    stop_ = true;
    thread_.join();
  }
  std::string address() const { return relay_.local().ToString(); }
  void StartReplaying() { replaying_ = true; }
  bool recorded() {
    std::lock_guard<std::mutex> lock(mutex_);
    return hello_.has_value() && reply_.has_value();  // version 2 sent no confirmation
  }
  std::uint64_t replays_sent() const { return replays_sent_; }
  // datagrams the device sent to the replayer's address: it must never stream to it
  std::uint64_t to_replayer() const { return to_replayer_; }
  // states forwarded to a renderer
  std::uint64_t states() const { return states_; }

 private:
  // classified from the header's bytes alone (type at offset 6, server nonce at 24), so the
  // relay records whatever version the two ends speak
  void Record(std::span<const std::uint8_t> bytes, bool from_device) {
    if (bytes.size() < device::kHeaderBytes + device::kMacBytes) return;
    const auto type = static_cast<device::PacketType>(bytes[6] | (bytes[7] << 8));
    bool server_nonce = false;
    for (std::size_t i = 24; i < 32; ++i) server_nonce = server_nonce || bytes[i] != 0;
    if (from_device && type == device::PacketType::kState) ++states_;
    std::lock_guard<std::mutex> lock(mutex_);
    std::optional<Bytes>* slot = nullptr;
    if (from_device && type == device::PacketType::kHelloReply) slot = &reply_;
    if (!from_device && type == device::PacketType::kHello)
      slot = server_nonce ? &confirm_ : &hello_;
    if (slot != nullptr && !slot->has_value()) *slot = Bytes(bytes.begin(), bytes.end());
  }

  void Replay() {
    std::lock_guard<std::mutex> lock(mutex_);
    if (hello_ && replayer_.SendTo(*hello_, device_) == 0) ++replays_sent_;
    if (confirm_ && replayer_.SendTo(*confirm_, device_) == 0) ++replays_sent_;
    if (reply_ && renderer_ && relay_.SendTo(*reply_, *renderer_) == 0) ++replays_sent_;
  }

  void Run() {
    std::array<std::uint8_t, device::kMaxDatagramBytes> buffer{};
    auto next_replay = std::chrono::steady_clock::now();
    while (!stop_) {
      device::Datagram datagram;
      for (int taken = 0; taken < 64 && relay_.Receive(buffer, &datagram) == 0; ++taken) {
        const std::span<const std::uint8_t> bytes(buffer.data(), datagram.bytes);
        const bool from_device = datagram.source == device_;
        Record(bytes, from_device);
        if (from_device) {
          if (renderer_) relay_.SendTo(bytes, *renderer_);
        } else {
          renderer_ = datagram.source;  // the newest renderer
          relay_.SendTo(bytes, device_);
        }
      }
      for (int taken = 0; taken < 64 && replayer_.Receive(buffer, &datagram) == 0; ++taken) {
        ++to_replayer_;
      }
      if (replaying_ && std::chrono::steady_clock::now() >= next_replay) {
        Replay();
        next_replay = std::chrono::steady_clock::now() + std::chrono::milliseconds(100);
      }
      std::this_thread::sleep_for(std::chrono::microseconds(100));
    }
  }

  device::UdpSocket relay_;
  device::UdpSocket replayer_;
  device::UdpEndpoint device_;
  std::optional<device::UdpEndpoint> renderer_;  // relay thread only
  std::mutex mutex_;
  std::optional<Bytes> hello_, confirm_, reply_;
  std::atomic<bool> stop_{false};
  std::atomic<bool> replaying_{false};
  std::atomic<std::uint64_t> replays_sent_{0};
  std::atomic<std::uint64_t> to_replayer_{0};
  std::atomic<std::uint64_t> states_{0};
  std::thread thread_;
};

long Count(const nlohmann::json& link, const char* name) {
  return link.contains(name) ? link.at(name).get<long>() : -1;
}

TEST(BridgeCliTest, ReplayedHandshakesOpenNoSessionAndTheRendererConnects) {
  const auto dir = TempDir("replayed_hello");
  IsolateHome(dir);
  const std::string key = Keygen(dir);
  const int port = FreePort();
  const pid_t sim = Spawn("device-sim --listen udp://127.0.0.1:" + std::to_string(port) +
                              " --key " + key + " --rate 1000 --duration 8 --json",
                          (dir / "sim.json").string());
  RecordingRelay relay(port);
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  // a genuine session through the relay, which records its handshake
  const CliResult first = RunCli("serve --device " + relay.address() + " --key " + key +
                                 " --rate 1000 --duration 0.5 --startup-timeout 3");
  ASSERT_EQ(first.exit_code, 0) << first.err;
  ASSERT_TRUE(relay.recorded());
  // its session ends at the device (session timeout 0.5 s); then the replays start
  std::this_thread::sleep_for(std::chrono::milliseconds(800));
  relay.StartReplaying();
  std::this_thread::sleep_for(std::chrono::milliseconds(600));
  EXPECT_EQ(relay.to_replayer(), 0u) << "the device answered or streamed to the replayer";
  // a new renderer connects while the replays go on (its hello-replies replayed to it too)
  const pid_t serve = Spawn("serve --device " + relay.address() + " --key " + key +
                                " --rate 1000 --duration 1 --startup-timeout 2 --json",
                            (dir / "serve.json").string());
  EXPECT_EQ(Wait(serve), 0) << "the renderer was refused";
  EXPECT_EQ(relay.to_replayer(), 0u);
  ::kill(sim, SIGTERM);
  EXPECT_EQ(Wait(sim), 0);
  EXPECT_GT(relay.replays_sent(), 20u);

  const auto served = nlohmann::json::parse(ReadAll(dir / "serve.json"));
  const auto& renderer = served["device"]["link"];
  EXPECT_EQ(Count(renderer, "handshakes"), 1);
  EXPECT_GT(Count(renderer, "accepted"), 500);
  EXPECT_GE(Count(renderer, "replayed_handshakes"), 5) << "the recorded reply was refused";
  const auto device_link = nlohmann::json::parse(ReadAll(dir / "sim.json"))["link"];
  EXPECT_EQ(Count(device_link, "handshakes"), 2) << "one session per serve, none for replays";
  // refused as seen before while no session was live (0.6 s: 6 rounds of a hello and a
  // confirmation), then as another address's while the new renderer's session was
  EXPECT_GE(Count(device_link, "replayed_handshakes"), 10);
  EXPECT_GE(Count(device_link, "replayed_handshakes") + Count(device_link, "hellos_refused"), 20);
  std::filesystem::remove_all(dir);
}

// A handle that ignores the force (an infinitely stiff hand): from 8 mm above the wall's
// surface plane it moves down at 0.2 m/s to 1 mm into it and stays there, in contact.
class PressingHandle final : public device::Device {
 public:
  DeviceState Read() override {
    DeviceState s;
    s.sequence = ++reads_;
    s.time_s = static_cast<double>(reads_) / 1000.0;
    const double z = std::max(0.004, 0.008 - 0.2 * static_cast<double>(moving_) / 1000.0);
    s.position_m = Vec3(0.0, 0.0, z);
    s.velocity_mps = Vec3(0.0, 0.0, z > 0.004 ? -0.2 : 0.0);
    if (approaching) ++moving_;
    return s;
  }
  void Write(const DeviceCommand& command) override { last = command; }
  const DeviceLimits& limits() const override { return limits_; }

  bool approaching = false;
  DeviceCommand last;

 private:
  std::uint64_t reads_ = 0;
  long moving_ = 0;
  DeviceLimits limits_;
};

// Forks a device process at 1 kHz over PressingHandle that times, on its own clock, how old the
// state each new command answers is (from the Step that sent the state to the Step that applies
// the command). It finds the renderer's stall (no command for over 0.2 s) and writes to `out`:
// the stall, the largest force before it, and, for the commands of the 0.3 s after it, their
// count and the oldest state one answered.
pid_t SpawnTimingDevice(const std::string& listen, const std::string& key, const std::string& out) {
  const pid_t pid = ::fork();
  if (pid != 0) return pid;
  using Clock = std::chrono::steady_clock;
  PressingHandle handle;
  device::UdpDeviceServerOptions options;
  options.listen = listen;
  options.key_file = key;
  device::UdpDeviceServer server(handle, options);
  std::map<std::uint64_t, Clock::time_point> sent_at;  // this session's states
  std::uint64_t session = 0, accepted = 0;
  Clock::time_point last_command{}, resumed{};
  double stall_s = 0.0, oldest_s = 0.0, force_before_N = 0.0;
  long answered = 0, unknown = 0;
  auto next = Clock::now();
  for (int k = 0; k < 15000; ++k) {
    server.Step();
    const auto now = Clock::now();
    if (server.has_peer()) handle.approaching = true;
    if (server.counters().handshakes != session) {
      session = server.counters().handshakes;
      sent_at.clear();
    }
    if (server.has_peer()) sent_at.emplace(server.last_sequence(), now);
    if (server.counters().accepted != accepted && !handle.last.safe_fallback) {
      // the command applied this Step is a new one
      if (resumed == Clock::time_point{} && last_command != Clock::time_point{} &&
          now - last_command > std::chrono::milliseconds(200)) {
        resumed = now;
        stall_s = std::chrono::duration<double>(now - last_command).count();
      }
      last_command = now;
      if (resumed == Clock::time_point{}) {
        force_before_N = std::max(force_before_N, handle.last.force_N.norm());
      } else if (now - resumed < std::chrono::milliseconds(300)) {
        const auto state = sent_at.find(handle.last.sequence);
        if (state == sent_at.end()) {
          ++unknown;
        } else {
          ++answered;
          oldest_s = std::max(oldest_s, std::chrono::duration<double>(now - state->second).count());
        }
      }
    }
    accepted = server.counters().accepted;
    if (resumed != Clock::time_point{} && now - resumed > std::chrono::milliseconds(400)) break;
    next += std::chrono::milliseconds(1);
    std::this_thread::sleep_until(next);
  }
  server.Release();
  std::ofstream(out) << stall_s << " " << force_before_N << " " << answered << " " << unknown << " "
                     << oldest_s << "\n";
  ::_exit(0);
}

// serve stopped (SIGSTOP) for 0.3 s while pressing into the wall: on resume no command answers
// a state older than one period (1 ms) plus max_state_age_s (10 ms), with 4 ms for the device's
// own 1 ms Step and a loaded machine (before: the first commands answered states 47 to 237 ms old)
TEST(BridgeCliTest, AStoppedRendererAnswersNoOldStateOnResume) {
  const auto dir = TempDir("stopped_renderer");
  IsolateHome(dir);
  const std::string key = Keygen(dir);
  const std::string addr = "udp://127.0.0.1:" + std::to_string(FreePort());
  const std::string timing = (dir / "timing.txt").string();
  const pid_t device = SpawnTimingDevice(addr, key, timing);
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  const pid_t serve = Spawn("serve --device " + addr + " --key " + key +
                                " --rate 1000 --duration 2 --startup-timeout 5 --json",
                            (dir / "serve.json").string());
  std::this_thread::sleep_for(std::chrono::milliseconds(900));
  ASSERT_EQ(::kill(serve, SIGSTOP), 0);
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  ASSERT_EQ(::kill(serve, SIGCONT), 0);
  EXPECT_EQ(Wait(serve), 0);
  int status = 0;
  ::waitpid(device, &status, 0);
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
  std::ifstream in(timing);
  double stall_s = 0.0, force_before_N = 0.0, oldest_s = 1.0;
  long answered = 0, unknown = 0;
  ASSERT_TRUE(in >> stall_s >> force_before_N >> answered >> unknown >> oldest_s);
  EXPECT_GE(stall_s, 0.25);
  EXPECT_GT(force_before_N, 0.1) << "not in contact when stopped";
  EXPECT_GT(answered, 100) << "the renderer did not resume rendering";
  EXPECT_EQ(unknown, 0);
  EXPECT_LE(oldest_s, 0.001 + 0.010 + 0.004);
  const auto served = nlohmann::json::parse(ReadAll(dir / "serve.json"));
  EXPECT_GT(served["device"]["link"]["expired"].get<long>(), 0) << "the backlog was rendered";
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace rigidtouch::test
