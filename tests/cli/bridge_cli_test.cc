// End to end over loopback: `device-sim` and `serve` talk through the UDP bridge with 5% of the
// packets dropped; device-sim is killed mid-run, the watchdog zeroes the force, and a new
// device-sim brings the loop back (issue: real-time loop and network bridge). A third-party
// process without the key floods both ends, also from the device's stolen port, and nothing it
// sends reaches the device or the renderer. `rigidtouch keygen`. Also serve's text summary of an
// in-process run. Every test points XDG_CONFIG_HOME and HOME at its own folder, so the real home
// directory's key is never read or created.
#include <arpa/inet.h>
#include <fcntl.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <thread>
#include <vector>

#include "cli/cli_util.h"
#include "cli/intruder.h"
#include "device/udp_protocol.h"
#include "device/udp_socket.h"
#include "loop/test_poll.h"
#include "rigidtouch/bridge.h"
#include "rigidtouch/device.h"

namespace rigidtouch::test {
namespace {

using testing::PollUntil;

// the UDP ports process `pid` has bound: its socket inodes (/proc/PID/fd), then /proc/net/udp
std::set<int> UdpPortsOf(pid_t pid) {
  std::set<std::string> inodes;
  std::error_code error;
  for (const auto& entry :
       std::filesystem::directory_iterator("/proc/" + std::to_string(pid) + "/fd", error)) {
    const std::string target = std::filesystem::read_symlink(entry.path(), error).string();
    if (target.rfind("socket:[", 0) == 0) inodes.insert(target.substr(8, target.size() - 9));
  }
  std::set<int> ports;
  std::ifstream table("/proc/net/udp");
  std::string line;
  std::getline(table, line);  // column names
  while (std::getline(table, line)) {
    std::istringstream fields(line);
    std::string slot, local, remote, state, queues, timer, retransmits, uid, timeout, inode;
    fields >> slot >> local >> remote >> state >> queues >> timer >> retransmits >> uid >>
        timeout >> inode;
    if (inodes.count(inode) != 0)
      ports.insert(std::stoi(local.substr(local.find(':') + 1), nullptr, 16));
  }
  return ports;
}

// the largest |tool position| component in a trace CSV (direct coupling: the device's position)
double LargestToolCoordinate(const std::filesystem::path& trace) {
  std::ifstream in(trace);
  std::string line;
  std::getline(in, line);
  std::vector<int> columns;
  {
    std::istringstream names(line);
    std::string name;
    for (int c = 0; std::getline(names, name, ','); ++c) {
      if (name == "tool_x_m" || name == "tool_y_m" || name == "tool_z_m") columns.push_back(c);
    }
  }
  EXPECT_EQ(columns.size(), 3u) << line;
  double largest = 0.0;
  while (std::getline(in, line)) {
    std::istringstream cells(line);
    std::string cell;
    for (int c = 0; std::getline(cells, cell, ','); ++c) {
      if (std::find(columns.begin(), columns.end(), c) == columns.end()) continue;
      const double value = std::strtod(cell.c_str(), nullptr);
      largest = std::isfinite(value) ? std::max(largest, std::abs(value)) : HUGE_VAL;
    }
  }
  return largest;
}

long LinkCount(const nlohmann::json& link, const char* name) {
  return link.at(name).get<long>();
}

TEST(BridgeCliTest, LossyLinkWatchdogAndRecovery) {
  const auto dir = TempDir("bridge");
  IsolateHome(dir);  // zero configuration: both ends create or read the same per-user key
  const std::string addr = "udp://127.0.0.1:" + std::to_string(FreePort());
  const double watchdog_s = 0.05;
  // serve runs 4 s; device-sim 1 taps from 0 s, is killed at 2 s, device-sim 2 starts at 2.6 s
  const pid_t serve = Spawn("serve --device " + addr +
                                " --rate 1000 --duration 4 --test-drop 0.05 --startup-timeout 5" +
                                " --watchdog " + std::to_string(watchdog_s) + " --json",
                            (dir / "serve.json").string());
  const std::string sim_args = "device-sim --listen " + addr +
                               " --rate 1000 --taps 20 --speed 0.2 --test-drop 0.05 --duration 10";
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  const pid_t sim1 = Spawn(sim_args, (dir / "sim1.json").string());
  std::this_thread::sleep_for(std::chrono::milliseconds(1800));
  ::kill(sim1, SIGKILL);
  Wait(sim1);
  std::this_thread::sleep_for(std::chrono::milliseconds(600));
  const pid_t sim2 = Spawn(sim_args, (dir / "sim2.json").string());
  ASSERT_EQ(Wait(serve), 0);
  ::kill(sim2, SIGTERM);
  Wait(sim2);

  const auto j = nlohmann::json::parse(ReadAll(dir / "serve.json"));
  EXPECT_TRUE(j["finite"].get<bool>());     // no NaN ever reached the device
  EXPECT_GT(j["impulses"].get<long>(), 0);  // the taps were rendered
  const auto& link = j["device"]["link"];
  EXPECT_GT(link["test_dropped_incoming"].get<long>(), 0);  // the 5% loss was active
  EXPECT_GE(link["watchdog_trips"].get<long>(), 1);         // device-sim killed: watchdog fired
  EXPECT_GE(link["recoveries"].get<long>(), 1);             // and the new device-sim recovered
  EXPECT_GE(link["handshakes"].get<long>(), 2);             // one session with each device-sim
  EXPECT_EQ(link["unauthenticated"].get<long>(), 0);
  // the key was created on first use, private to the user
  struct stat info {};
  ASSERT_EQ(::stat((dir / "xdg" / "rigidtouch" / "device.key").c_str(), &info), 0);
  EXPECT_EQ(info.st_mode & 0777, 0600u);
  // while the device was gone (0.6 s) the loop output the safe zero force; the watchdog took
  // at most its configured time to notice, so at least 0.6 s - 0.05 s of zero-force ticks
  EXPECT_GE(j["safe_fallback_ticks"].get<long>(),
            static_cast<long>((0.6 - watchdog_s) * 1000 * 0.9));
  // and the loop kept its rate through all of it (4 s at 1 kHz, generous bound for a busy box)
  EXPECT_GE(j["loop"]["ticks"].get<long>(), 3000);
  std::filesystem::remove_all(dir);
}

TEST(BridgeCliTest, AddressInUseGivesAClearError) {
  const auto dir = TempDir("in_use");
  IsolateHome(dir);
  const int port = FreePort();
  const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  a.sin_port = htons(port);
  ASSERT_EQ(::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a), 0);
  const CliResult r =
      RunCli("device-sim --listen udp://127.0.0.1:" + std::to_string(port) + " --duration 0.1");
  ::close(fd);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find(std::to_string(port)), std::string::npos) << r.err;
  std::filesystem::remove_all(dir);
}

// the review's attack on the device side: a process floods device-sim while no renderer is
// connected; every write to the device stays the zero force
TEST(BridgeCliTest, IntruderWithoutTheKeyNeverMovesTheDevice) {
  const auto dir = TempDir("intruder_device");
  IsolateHome(dir);
  const std::string key = Keygen(dir);
  const int port = FreePort();
  Intruder intruder;
  intruder.AddTarget(port);
  const pid_t sim = Spawn("device-sim --listen udp://127.0.0.1:" + std::to_string(port) +
                              " --key " + key + " --rate 1000 --duration 1.5 --json",
                          (dir / "sim.json").string());
  intruder.Start();
  ASSERT_EQ(Wait(sim), 0);
  intruder.Stop();
  const auto j = nlohmann::json::parse(ReadAll(dir / "sim.json"));
  const auto& link = j["link"];
  EXPECT_GT(intruder.sent(), 1000u);
  EXPECT_EQ(LinkCount(link, "accepted"), 0);
  EXPECT_EQ(LinkCount(link, "handshakes"), 0);
  EXPECT_EQ(LinkCount(link, "sent"), 0) << "no state of the hand went anywhere";
  // every period wrote the zero force, and so did the release at the stop; the simulated hand
  // received no energy
  EXPECT_EQ(LinkCount(link, "fallback_writes"), j["loop"]["ticks"].get<long>() + 1);
  EXPECT_EQ(j["energy_to_user_J"].get<double>(), 0.0);
  // and each datagram is accounted for as a drop
  EXPECT_GT(LinkCount(link, "unauthenticated"), 0);
  EXPECT_GT(link["malformed"]["wrong_version"].get<long>(), 0);
  EXPECT_GT(link["malformed"]["wrong_type"].get<long>(), 0);
  EXPECT_EQ(LinkCount(link, "unauthenticated") + link["malformed"]["total"].get<long>(),
            LinkCount(link, "received"));
  std::filesystem::remove_all(dir);
}

// both ends run and render taps while the intruder floods both of them (the renderer's port is
// found from /proc, as any local process could): the session survives, the renderer never
// takes the intruder's states, the device never takes its commands
TEST(BridgeCliTest, IntruderWithoutTheKeyReachesNeitherEndOfALiveSession) {
  const auto dir = TempDir("intruder_both");
  IsolateHome(dir);
  const std::string key = Keygen(dir);
  const std::string addr = "udp://127.0.0.1:" + std::to_string(FreePort());
  Intruder intruder;
  intruder.AddTarget(std::stoi(addr.substr(addr.rfind(':') + 1)));
  const pid_t sim = Spawn("device-sim --listen " + addr + " --key " + key +
                              " --rate 1000 --taps 20 --speed 0.2 --duration 3.5 --json",
                          (dir / "sim.json").string());
  intruder.Start();
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  const pid_t serve =
      Spawn("serve --device " + addr + " --key " + key +
                " --rate 1000 --duration 2.5 --json --trace " + (dir / "trace.csv").string(),
            (dir / "serve.json").string());
  std::set<int> serve_ports;
  // between fork and exec the child still holds this process's sockets, the intruder's too
  ASSERT_TRUE(PollUntil([&] {
    serve_ports = UdpPortsOf(serve);
    serve_ports.erase(intruder.port());
    return !serve_ports.empty();
  }));
  for (const int port : serve_ports) intruder.AddTarget(port);
  ASSERT_EQ(Wait(serve), 0);
  intruder.Stop();
  ::kill(sim, SIGTERM);
  Wait(sim);

  const auto served = nlohmann::json::parse(ReadAll(dir / "serve.json"));
  const auto& renderer = served["device"]["link"];
  EXPECT_GT(served["impulses"].get<long>(), 0) << "the taps were still rendered";
  EXPECT_GT(LinkCount(renderer, "accepted"), 1000);
  EXPECT_GE(LinkCount(renderer, "handshakes"), 1);  // more only if a slow (sanitizer) run tripped
  // the intruder reached the renderer's socket, but not from the device's address, to which the
  // renderer is pinned (the stolen-port test below covers datagrams from that address)
  EXPECT_GT(LinkCount(renderer, "wrong_source"), 1000);
  EXPECT_TRUE(served["finite"].get<bool>());
  // no state of the intruder's (5 m, 1e300) was ever the tool's position
  EXPECT_LT(LargestToolCoordinate(dir / "trace.csv"), 1.0);

  const auto sim_json = nlohmann::json::parse(ReadAll(dir / "sim.json"));
  const auto& device_link = sim_json["link"];
  EXPECT_EQ(LinkCount(device_link, "handshakes"), LinkCount(renderer, "handshakes"));
  EXPECT_EQ(LinkCount(device_link, "peer_changes"), 1) << "the session never left the renderer";
  EXPECT_GT(LinkCount(device_link, "unauthenticated"), 1000);
  // every command the device took was one the renderer sent
  EXPECT_LE(LinkCount(device_link, "accepted"), LinkCount(renderer, "sent"));
  std::filesystem::remove_all(dir);
}

// the review's second attack: the intruder binds the device's port before the device starts.
// The renderer talks to it (its hellos reach the intruder) but accepts nothing it sends: it never
// gets a session, so it gives up after its startup timeout with status 5 and no force rendered;
// device-sim refuses to start with a clear message
TEST(BridgeCliTest, StolenDevicePortYieldsNothingToTheRenderer) {
  const auto dir = TempDir("stolen_port");
  IsolateHome(dir);
  const std::string key = Keygen(dir);
  const int port = FreePort();
  Intruder intruder(port);
  intruder.Start();
  const std::string addr = "udp://127.0.0.1:" + std::to_string(port);
  const pid_t serve =
      Spawn("serve --device " + addr + " --key " + key +
                " --rate 1000 --duration 1.5 --startup-timeout 1.2 --json --trace " +
                (dir / "trace.csv").string(),
            (dir / "serve.json").string());
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  const CliResult sim = RunCli("device-sim --listen " + addr + " --key " + key + " --duration 1");
  EXPECT_NE(sim.exit_code, 0);
  EXPECT_NE(sim.err.find(std::to_string(port)), std::string::npos) << sim.err;
  EXPECT_NE(sim.err.find("in use"), std::string::npos) << sim.err;
  // no session with the intruder, however much it sent: no first state, so no run at all
  EXPECT_EQ(Wait(serve), 5);
  intruder.Stop();

  EXPECT_GT(intruder.hellos_heard(), 10u) << "the renderer kept asking the stolen port";
  EXPECT_TRUE(ReadAll(dir / "serve.json").empty()) << "serve rendered a session";
  EXPECT_FALSE(std::filesystem::exists(dir / "trace.csv"));
  std::filesystem::remove_all(dir);
}

// A handle that ignores the force it is given (an infinitely stiff hand): it rests at
// kStart_m until `Approach`, then moves down at kSpeed_mps, one new reading per Read.
class StiffHandle final : public device::Device {
 public:
  static constexpr double kStart_m = 0.008;  // the tool centre touches the wall at 0.005
  static constexpr double kSpeed_mps = 0.2;
  static constexpr double kRateHz = 1000.0;

  DeviceState Read() override {
    DeviceState s;
    s.sequence = ++sequence_;
    s.time_s = static_cast<double>(sequence_) / kRateHz;
    s.position_m = Vec3(0.0, 0.0, kStart_m - kSpeed_mps * moving_reads_ / kRateHz);
    s.velocity_mps = Vec3(0.0, 0.0, approaching_ ? -kSpeed_mps : 0.0);
    if (approaching_) ++moving_reads_;
    return s;
  }
  void Write(const DeviceCommand&) override {}
  const DeviceLimits& limits() const override { return limits_; }

  void Approach() { approaching_ = true; }
  double z() const { return kStart_m - kSpeed_mps * moving_reads_ / kRateHz; }

 private:
  std::uint64_t sequence_ = 0;
  long moving_reads_ = 0;
  bool approaching_ = false;
  DeviceLimits limits_;  // no limit of its own: serve's preset decides
};

// Forks a device process: a UdpDeviceServer at 1 kHz over StiffHandle. Once serve holds a
// session the handle approaches the wall; `contact_reads` readings after it touched, the process
// kills itself with SIGKILL (the state stream stops mid-contact, as when a bridge crashes).
pid_t SpawnDeviceKilledInContact(const std::string& listen, const std::string& key,
                                 int contact_reads) {
  const pid_t pid = ::fork();
  if (pid != 0) return pid;
  StiffHandle handle;
  device::UdpDeviceServerOptions options;
  options.listen = listen;
  options.key_file = key;
  device::UdpDeviceServer server(handle, options);
  auto next = std::chrono::steady_clock::now();
  int touching = 0;
  for (int k = 0; k < 20000; ++k) {  // at most 20 s
    server.Step();
    if (server.has_peer()) handle.Approach();
    if (handle.z() < 0.005 && ++touching > contact_reads) ::raise(SIGKILL);
    next += std::chrono::milliseconds(1);
    std::this_thread::sleep_until(next);
  }
  ::_exit(1);  // serve never connected
}

// the columns of a trace CSV by name
std::map<std::string, std::vector<double>> ReadTraceColumns(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  std::vector<std::string> names;
  {
    std::istringstream header(line);
    for (std::string name; std::getline(header, name, ',');) names.push_back(name);
  }
  std::map<std::string, std::vector<double>> columns;
  while (std::getline(in, line)) {
    std::istringstream cells(line);
    std::string cell;
    for (std::size_t c = 0; c < names.size() && std::getline(cells, cell, ','); ++c) {
      columns[names[c]].push_back(std::strtod(cell.c_str(), nullptr));
    }
  }
  return columns;
}

// The review's third finding, end to end: the device process dies (SIGKILL) in the middle of an
// impulse train. From the last fresh state to the watchdog, serve sends no impulse and no force
// larger than the one it sent for the last fresh state; then the zero force. (Before the stale
// policy the train kept firing on the frozen approach velocity: 9.7 N grew to 16.9 N.)
TEST(BridgeCliTest, DeviceKilledDuringContactGetsNoNewImpulseAndNoGrowingForce) {
  const auto dir = TempDir("killed_in_contact");
  IsolateHome(dir);
  const std::string key = Keygen(dir);
  const std::string addr = "udp://127.0.0.1:" + std::to_string(FreePort());
  const pid_t device = SpawnDeviceKilledInContact(addr, key, /*contact_reads=*/40);
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  // omega.3 (12 N): a stiffness of 500 N/m keeps the penalty (8 mm deep at most: 4 N) and the
  // train's impulses unclipped;
  // 250 Hz train: an impulse every 4 ticks of the 100 ms window
  const pid_t serve = Spawn("serve --device " + addr + " --key " + key +
                                " --preset omega3 --stiffness 500 --renderer train"
                                " --frequency 250 --t-collision 0.1 --rate 1000 --duration 1"
                                " --watchdog 0.05 --startup-timeout 5 --json --trace " +
                                (dir / "trace.csv").string(),
                            (dir / "serve.json").string());
  const int serve_status = Wait(serve);
  int device_status = 0;
  ::waitpid(device, &device_status, 0);
  ASSERT_EQ(serve_status, 0);
  ASSERT_TRUE(WIFSIGNALED(device_status) && WTERMSIG(device_status) == SIGKILL)
      << "the device process did not reach the wall";

  const auto j = nlohmann::json::parse(ReadAll(dir / "serve.json"));
  EXPECT_GE(j["device"]["link"]["watchdog_trips"].get<long>(), 1);
  EXPECT_TRUE(j["finite"].get<bool>());
  auto t = ReadTraceColumns(dir / "trace.csv");
  const std::vector<double>& z = t["tool_z_m"];
  const std::vector<double>& impulses = t["impulses"];
  ASSERT_GT(z.size(), 100u);
  std::vector<double> force(z.size());
  for (std::size_t k = 0; k < z.size(); ++k) {
    force[k] = std::hypot(t["device_fx_N"][k], t["device_fy_N"][k], t["device_fz_N"][k]);
  }
  // the trace holds the tool after the tick's integration, so the handle's position that tick
  // (direct coupling) is z - v h; the handle moves 0.2 mm every reading, so the last fresh state
  // is the last tick at which that position changed before the watchdog's zero force (from
  // then on the tool is held at rest where it was)
  const std::vector<double>& vz = t["tool_vz_mps"];
  const std::vector<double>& depth = t["penetration_m"];
  const auto touched = std::find_if(depth.begin(), depth.end(), [](double d) { return d > 0.0; });
  ASSERT_NE(touched, depth.end()) << "never touched the wall";
  std::size_t watchdog = static_cast<std::size_t>(touched - depth.begin());
  while (watchdog < z.size() && force[watchdog] > 0.0) ++watchdog;
  ASSERT_LT(watchdog, z.size()) << "the force never went to zero";
  std::size_t last_fresh = 0;
  for (std::size_t k = 1; k < watchdog; ++k) {
    const double handle = z[k] - vz[k] * 1e-3, before = z[k - 1] - vz[k - 1] * 1e-3;
    if (std::abs(handle - before) > 1e-7) last_fresh = k;
  }
  ASSERT_LT(z[last_fresh] - vz[last_fresh] * 1e-3, 0.005) << "killed in contact";
  double train_impulses = 0.0;
  for (std::size_t k = 0; k <= last_fresh; ++k) train_impulses += impulses[k];
  // 40 ms of contact is ten impulses at 250 Hz; a loaded machine's late ticks see fewer states
  ASSERT_GE(train_impulses, 2.0) << "a train was running when the device died";
  ASSERT_GT(force[last_fresh], 0.5);
  ASSERT_LT(force[last_fresh], 12.0) << "unclipped, so a growing force would show";
  long stale_ticks = 0, zero_ticks = 0;
  for (std::size_t k = last_fresh + 1; k < z.size(); ++k) {
    EXPECT_EQ(impulses[k], 0.0) << "tick " << k << " after the last fresh state " << last_fresh;
    EXPECT_LE(force[k], force[last_fresh]) << "tick " << k;
    if (force[k] > 0.0) ++stale_ticks;
    if (force[k] == 0.0) ++zero_ticks;
  }
  // the force is held, not dropped, until the watchdog (50 ms) ends it with the zero force
  EXPECT_GE(stale_ticks, 10);
  EXPECT_LE(stale_ticks, 200);  // a loaded machine may run late ticks back to back
  EXPECT_GT(zero_ticks, 300);   // the rest of the 1 s run, fewer on a loaded machine
  EXPECT_GE(j["held_force_ticks"].get<long>() + j["stale_device_ticks"].get<long>(), 10);
  std::filesystem::remove_all(dir);
}

TEST(KeygenCliTest, WritesAPrivateKeyAndNeverOverwritesUnlessForced) {
  const auto dir = TempDir("keygen");
  IsolateHome(dir);
  const std::filesystem::path key = dir / "keys" / "device.key";
  CliResult r = RunCli("keygen --out " + key.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  struct stat info {};
  ASSERT_EQ(::stat(key.c_str(), &info), 0);
  EXPECT_EQ(info.st_mode & 0777, 0600u);
  const std::string first = ReadAll(key);
  EXPECT_EQ(first.size(), 65u);
  EXPECT_EQ(r.out.find(first.substr(0, 64)), std::string::npos) << "the key is never printed";

  r = RunCli("keygen --out " + key.string());
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("already exists"), std::string::npos) << r.err;
  EXPECT_EQ(ReadAll(key), first);
  r = RunCli("keygen --out " + key.string() + " --force");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(ReadAll(key), first);

  // a key others may read is refused, naming the fix
  ::chmod(key.c_str(), 0644);
  r = RunCli("device-sim --listen udp://127.0.0.1:0 --key " + key.string() + " --duration 0.1");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("chmod 600"), std::string::npos) << r.err;

  // without --out: the per-user default, here under the test's XDG_CONFIG_HOME
  r = RunCli("keygen --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(nlohmann::json::parse(r.out)["key_file"].get<std::string>(),
            (dir / "xdg" / "rigidtouch" / "device.key").string());
  std::filesystem::remove_all(dir);
}

// the text summary of a short in-process run: every deadline is a tick or a skipped period
// (300 of them at 1 kHz for 0.3 s), the period errors are in microseconds and ordered
TEST(ServeCliTest, TextSummaryCountsEveryDeadlineInMicroseconds) {
  const CliResult r = RunCli("serve --device sim --rate 1000 --duration 0.3 --taps 1");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // std::regex is avoided: GCC 12 warns inside <regex> at -O3 (maybe-uninitialized)
  const std::size_t at = r.out.find("ticks ");
  ASSERT_NE(at, std::string::npos) << r.out;
  long long ticks = 0, overruns = 0, skipped = 0;
  double rate = 0.0, asked = 0.0, period_us[4] = {};
  int consumed = -1;
  const int n =
      std::sscanf(r.out.c_str() + at,
                  "ticks %lld at %lf Hz (asked %lf), overruns %lld, skipped periods %lld, "
                  "period error p50 / p99 / p99.9 / max %lf / %lf / %lf / %lf us%n",
                  &ticks, &rate, &asked, &overruns, &skipped, &period_us[0], &period_us[1],
                  &period_us[2], &period_us[3], &consumed);
  ASSERT_EQ(n, 9) << r.out;
  ASSERT_GT(consumed, 0) << r.out;  // the line ends in "us"
  EXPECT_EQ(asked, 1000.0);
  EXPECT_EQ(ticks + skipped, 300) << r.out;
  EXPECT_GE(overruns, 0);
  EXPECT_GT(rate, 0.0);
  EXPECT_LE(rate, 1000.1);
  double last = 0.0;
  for (double p : period_us) {
    EXPECT_GE(p, last) << r.out;
    last = p;
  }
  EXPECT_LT(last, 3e5) << r.out;  // the largest period error is shorter than the run
}

}  // namespace
}  // namespace rigidtouch::test
