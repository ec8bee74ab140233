// What the UDP bridge tests share: a home folder of their own (so the per-user key is never the
// real one), a key from `rigidtouch keygen`, and Intruder, a local process without the key.
#pragma once

#include <gtest/gtest.h>
#include <stdlib.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <iterator>
#include <mutex>
#include <span>
#include <string>
#include <thread>
#include <vector>

#include "cli/cli_util.h"
#include "device/udp_protocol.h"
#include "device/udp_socket.h"

namespace rigidtouch::test {

// points the per-user key lookup of this process and its children into `dir`
inline void IsolateHome(const std::filesystem::path& dir) {
  ::setenv("XDG_CONFIG_HOME", (dir / "xdg").c_str(), 1);
  ::setenv("HOME", (dir / "home").c_str(), 1);
}

// writes a fresh key with `rigidtouch keygen` and returns its path
inline std::string Keygen(const std::filesystem::path& dir) {
  const std::string key = (dir / "shared.key").string();
  const CliResult r = RunCli("keygen --out " + key);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  return key;
}

// A process on the host that does not hold the key: it floods its targets with what it can
// make (commands of 1000 N and states 5 m away under its own key, version 1 packets with a
// valid CRC and 1e300 values, hellos and hello-replies), and, when it holds the device's port,
// answers the renderer's hellos with forged replies and states and echoes its hellos back.
class Intruder {
 public:
  static constexpr double kMarker_m = 5.0;  // a position no honest device here reports

  explicit Intruder(int port = 0)
      : socket_(device::UdpEndpoint{0x7f000001u, static_cast<std::uint16_t>(port)}, "intruder") {
    key_.bytes.fill(0x42);  // not the shared key
  }
  ~Intruder() { Stop(); }

  void Start() {
    thread_ = std::thread([this] { Run(); });
  }
  void Stop() {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
  }
  void AddTarget(int port) {
    std::lock_guard<std::mutex> lock(mutex_);
    targets_.push_back(device::UdpEndpoint{0x7f000001u, static_cast<std::uint16_t>(port)});
  }
  std::uint64_t sent() const { return sent_; }
  int port() const { return socket_.local().port; }
  std::uint64_t hellos_heard() const { return hellos_heard_; }

 private:
  void Send(std::span<const std::uint8_t> bytes, const device::UdpEndpoint& to) {
    if (socket_.SendTo(bytes, to) == 0) ++sent_;
  }

  // what a version 1 sender puts on the wire: 16-byte header, zeroed CRC field, payload
  static std::vector<std::uint8_t> Version1(std::uint16_t type, std::size_t payload_bytes,
                                            double value) {
    std::vector<std::uint8_t> bytes(16 + payload_bytes, 0);
    const std::uint8_t header[] = {0x52,
                                   0x54,
                                   0x43,
                                   0x48,
                                   1,
                                   0,
                                   static_cast<std::uint8_t>(type),
                                   0,
                                   static_cast<std::uint8_t>(payload_bytes)};
    std::copy(std::begin(header), std::end(header), bytes.begin());
    const auto bits = std::bit_cast<std::uint64_t>(value);
    for (std::size_t at = 24; at + 8 <= bytes.size(); at += 8) {
      for (int i = 0; i < 8; ++i) bytes[at + i] = static_cast<std::uint8_t>(bits >> (8 * i));
    }
    return bytes;
  }

  void Flood(const device::UdpEndpoint& to, std::uint64_t client_nonce, std::uint64_t round) {
    using namespace device;
    DeviceCommand command;
    command.sequence = round;
    command.force_N = Vec3(1000.0, 0.0, 0.0);
    DeviceState state;
    state.sequence = round;
    state.position_m = Vec3(kMarker_m, kMarker_m, kMarker_m);
    const PacketHeader header{PacketType::kCommand, client_nonce, round, round};
    Send(EncodeCommand(command, header, key_), to);
    Send(EncodeState(state, header, key_), to);
    Send(EncodeHello(round, key_), to);
    Send(EncodeHelloReply(DeviceLimits{"", 1000.0, 0.0, 0.0}, client_nonce, round, key_), to);
    Send(Version1(2, 60, 1000.0), to);
    Send(Version1(1, 124, 1e300), to);
  }

  void Run() {
    std::array<std::uint8_t, device::kMaxDatagramBytes> buffer{};
    for (std::uint64_t round = 1; !stop_; ++round) {
      // as the stolen port: answer whoever says hello, with its own nonce
      device::Datagram datagram;
      // bounded, so a stop request is seen whatever arrives
      for (int taken = 0; taken < 64 && socket_.Receive(buffer, &datagram) == 0; ++taken) {
        if (datagram.source == socket_.local()) continue;
        device::PacketHeader header;
        const std::span<const std::uint8_t> bytes(buffer.data(), datagram.bytes);
        if (device::CheckFraming(bytes, device::PacketType::kHello, device::PacketType::kCommand,
                                 &header) == device::DecodeResult::kOk &&
            header.type == device::PacketType::kHello) {
          ++hellos_heard_;
          Send(bytes, datagram.source);  // the renderer's own hello, reflected
          Flood(datagram.source, header.client_nonce, round);
        }
      }
      std::vector<device::UdpEndpoint> targets;
      {
        std::lock_guard<std::mutex> lock(mutex_);
        targets = targets_;
      }
      for (const auto& target : targets) Flood(target, round, round);
      std::this_thread::sleep_for(std::chrono::microseconds(200));
    }
  }

  device::UdpSocket socket_;
  device::DeviceKey key_;
  std::atomic<bool> stop_{false};
  std::atomic<std::uint64_t> sent_{0};
  std::atomic<std::uint64_t> hellos_heard_{0};
  std::mutex mutex_;
  std::vector<device::UdpEndpoint> targets_;
  std::thread thread_;
};

}  // namespace rigidtouch::test
