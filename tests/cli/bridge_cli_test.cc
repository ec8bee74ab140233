// End to end over loopback: `device-sim` and `serve` talk through the UDP bridge with 5% of the
// packets dropped; device-sim is killed mid-run, the watchdog zeroes the force, and a new
// device-sim brings the loop back (issue: real-time loop and network bridge). Also serve's text
// summary of an in-process run.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <thread>

#include "cli/cli_util.h"

namespace rigidtouch::test {
namespace {

// a UDP port that was free a moment ago on 127.0.0.1
int FreePort() {
  const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  a.sin_port = 0;
  ::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a);
  socklen_t n = sizeof a;
  ::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &n);
  ::close(fd);
  return ntohs(a.sin_port);
}

// starts `rigidtouch ARGS` with stdout to `out`; returns its pid
pid_t Spawn(const std::string& args, const std::string& out) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    const std::string cmd = std::string("exec ") + RIGIDTOUCH_CLI + " " + args + " >" + out;
    ::execl("/bin/sh", "sh", "-c", cmd.c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  return pid;
}

int Wait(pid_t pid) {
  int status = 0;
  ::waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

TEST(BridgeCliTest, LossyLinkWatchdogAndRecovery) {
  const auto dir = TempDir("bridge");
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
  // while the device was gone (0.6 s) the loop output the safe zero force; the watchdog took
  // at most its configured time to notice, so at least 0.6 s - 0.05 s of zero-force ticks
  EXPECT_GE(j["safe_fallback_ticks"].get<long>(),
            static_cast<long>((0.6 - watchdog_s) * 1000 * 0.9));
  // and the loop kept its rate through all of it (4 s at 1 kHz, generous bound for a busy box)
  EXPECT_GE(j["loop"]["ticks"].get<long>(), 3000);
  std::filesystem::remove_all(dir);
}

TEST(BridgeCliTest, AddressInUseGivesAClearError) {
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
