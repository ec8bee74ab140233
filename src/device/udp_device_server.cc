#include "rigidtouch/bridge.h"

#include <array>
#include <cerrno>
#include <cmath>
#include <memory>

#include "device/udp_link.h"
#include "device/udp_protocol.h"
#include "device/udp_socket.h"
#include "render/output.h"

namespace rigidtouch::device {
namespace {

constexpr std::string_view kUdpServerWhat = "udp device server";

UdpEndpoint ParseListen(const UdpDeviceServerOptions& options) {
  ValidatePacketLoss(options.test_loss, kUdpServerWhat);
  const UdpEndpoint listen = ParseUdpAddress(options.listen, "udp device server: listen");
  RequireLoopbackUnlessAllowed(listen, "udp device server: listen", options.allow_non_loopback);
  return listen;
}

UdpEndpoint ParsePeer(const UdpDeviceServerOptions& options) {
  if (options.peer.empty()) return UdpEndpoint{};
  const UdpEndpoint peer = ParseUdpAddress(options.peer, "udp device server: peer");
  if (peer.port == 0) {
    throw Error("udp device server: peer '" + options.peer + "' needs a port in [1, 65535]");
  }
  RequireLoopbackUnlessAllowed(peer, "udp device server: peer", options.allow_non_loopback);
  return peer;
}

}  // namespace

std::int64_t SessionTimeoutNs(const UdpDeviceServerOptions& options) {
  const double timeout_s = options.session_timeout_s;
  if (!(std::isfinite(timeout_s) && timeout_s >= options.watchdog_s && timeout_s <= 60.0)) {
    throw Error("udp device server: session_timeout_s = " + std::to_string(timeout_s) +
                " is outside [watchdog_s, 60] s");
  }
  return std::llround(timeout_s * 1e9);
}

struct UdpDeviceServer::Impl {
  Impl(Device& served, const UdpDeviceServerOptions& options)
      : device(served),
        watchdog_ns(WatchdogNs(options.watchdog_s, kUdpServerWhat)),
        session_timeout_ns(SessionTimeoutNs(options)),
        fixed_peer(!options.peer.empty()),
        allowed_peer(ParsePeer(options)),
        key(ResolveDeviceKey(options.key, options.key_file)),
        socket(ParseListen(options), "udp device server: listen"),
        loss(options.test_loss) {}

  void Step();
  void Release();
  void SendState();
  void DrainDatagrams(std::int64_t now_ns);
  void HandleHello(const PacketHeader& header, const UdpEndpoint& source, std::int64_t now_ns);
  void HandleCommand(const PacketHeader& header, const UdpEndpoint& source,
                     std::span<const std::uint8_t> datagram, std::int64_t now_ns);
  void SendReply();

  Device& device;
  std::int64_t watchdog_ns = 0;
  std::int64_t session_timeout_ns = 0;
  bool fixed_peer = false;
  UdpEndpoint allowed_peer;  // the only client address when fixed_peer
  DeviceKey key;
  UdpSocket socket;
  LossSimulator loss;
  UdpCounters counters;
  // the session: pinned to the client's address and both nonces
  bool session = false;
  bool had_peer = false;
  UdpEndpoint peer;
  std::uint64_t client_nonce = 0;
  std::uint64_t server_nonce = 0;
  std::uint64_t sent_counter = 0;
  std::uint64_t received_counter = 0;
  std::int64_t last_peer_ns = 0;  // newest authenticated hello or command from the peer
  std::uint64_t sequence = 0;     // the server numbers states itself: strictly increasing
  DeviceCommand command;          // newest accepted command, already clamped
  bool has_command = false;
  bool tripped = false;
  std::int64_t last_fresh_ns = 0;
  std::array<std::uint8_t, kMaxDatagramBytes> buffer{};
};

UdpDeviceServer::UdpDeviceServer(Device& device, const UdpDeviceServerOptions& options)
    : impl_(std::make_unique<Impl>(device, options)) {}
UdpDeviceServer::~UdpDeviceServer() = default;
UdpDeviceServer::UdpDeviceServer(UdpDeviceServer&&) noexcept = default;
UdpDeviceServer& UdpDeviceServer::operator=(UdpDeviceServer&&) noexcept = default;

void UdpDeviceServer::Step() {
  impl_->Step();
}
void UdpDeviceServer::Release() {
  impl_->Release();
}
const UdpCounters& UdpDeviceServer::counters() const {
  return impl_->counters;
}
bool UdpDeviceServer::watchdog_tripped() const {
  return impl_->tripped;
}
const UdpEndpoint& UdpDeviceServer::local_endpoint() const {
  return impl_->socket.local();
}
bool UdpDeviceServer::has_peer() const {
  return impl_->session;
}
const UdpEndpoint& UdpDeviceServer::peer() const {
  return impl_->peer;
}
std::uint64_t UdpDeviceServer::last_sequence() const {
  return impl_->sequence;
}

void UdpDeviceServer::Impl::Step() {
  const std::int64_t now_ns = MonotonicNowNs();
  if (session && now_ns - last_peer_ns > session_timeout_ns) {
    // the peer is gone; another client holding the key may now start a session
    session = false;
    ++counters.session_timeouts;
  }
  // Device order: Read, (renderer computes), Write
  SendState();
  DrainDatagrams(now_ns);
  if (has_command && !tripped && now_ns - last_fresh_ns > watchdog_ns) {
    tripped = true;
    ++counters.watchdog_trips;
  }
  if (session && has_command && !tripped) {
    device.Write(command);
    return;
  }
  DeviceCommand zero;
  zero.sequence = sequence;
  zero.safe_fallback = true;
  device.Write(zero);
  ++counters.fallback_writes;
}

void UdpDeviceServer::Impl::Release() {
  // the command is dropped: Step writes zero until the renderer sends a new one
  has_command = false;
  DeviceCommand zero;
  zero.sequence = sequence;
  zero.safe_fallback = true;
  device.Write(zero);
  ++counters.fallback_writes;
}

void UdpDeviceServer::Impl::SendState() {
  DeviceState state = device.Read();
  // an invalid reading is not sent: the client's watchdog covers a device that stops reporting
  if (!state.valid) {
    ++counters.invalid_device_states;
    return;
  }
  if (!session) return;
  state.sequence = ++sequence;
  const PacketHeader header{PacketType::kState, client_nonce, server_nonce, ++sent_counter};
  const StatePacket packet = EncodeState(state, header, key);
  SendCounted(socket, loss, counters, packet, peer);
}

void UdpDeviceServer::Impl::SendReply() {
  const HelloReplyPacket packet =
      EncodeHelloReply(device.limits(), client_nonce, server_nonce, key);
  SendCounted(socket, loss, counters, packet, peer);
}

void UdpDeviceServer::Impl::DrainDatagrams(std::int64_t now_ns) {
  const LinkInbox inbox{socket, buffer, loss, counters, key};
  DrainAuthenticated(inbox, fixed_peer ? &allowed_peer : nullptr, PacketType::kHello,
                     PacketType::kCommand,
                     [&](const PacketHeader& header, std::span<const std::uint8_t> bytes,
                         const UdpEndpoint& source) {
                       if (header.type == PacketType::kHello) {
                         HandleHello(header, source, now_ns);
                       } else {
                         HandleCommand(header, source, bytes, now_ns);
                       }
                     });
}

void UdpDeviceServer::Impl::HandleHello(const PacketHeader& header, const UdpEndpoint& source,
                                        std::int64_t now_ns) {
  if (header.client_nonce == 0) {
    ++counters.no_session;
    return;
  }
  if (session && source != peer) {
    // one renderer at a time: a live session is never taken over
    ++counters.hellos_refused;
    return;
  }
  if (session && header.client_nonce == client_nonce) {
    // the same hello again: our reply was lost; answer it the same way
    last_peer_ns = now_ns;
    SendReply();
    return;
  }
  if (!had_peer || source != peer) ++counters.peer_changes;
  // a new session: fresh nonce, counters and sequencing from scratch, zero force until its
  // first command
  session = true;
  had_peer = true;
  peer = source;
  client_nonce = header.client_nonce;
  server_nonce = RandomNonce();
  sent_counter = 0;
  received_counter = 0;
  sequence = 0;
  has_command = false;
  tripped = false;
  last_peer_ns = now_ns;
  ++counters.handshakes;
  SendReply();
}

void UdpDeviceServer::Impl::HandleCommand(const PacketHeader& header, const UdpEndpoint& source,
                                          std::span<const std::uint8_t> datagram,
                                          std::int64_t now_ns) {
  if (!session || header.client_nonce != client_nonce || header.server_nonce != server_nonce) {
    ++counters.no_session;
    return;
  }
  if (source != peer) {
    ++counters.wrong_source;
    return;
  }
  if (header.counter <= received_counter) {
    ++counters.replayed;
    return;
  }
  DeviceCommand decoded;
  const DecodeResult result = DecodeCommandPayload(datagram, &decoded);
  if (result != DecodeResult::kOk) {
    ++counters.malformed[static_cast<std::size_t>(result)];
    return;
  }
  received_counter = header.counter;
  last_peer_ns = now_ns;
  if (has_command && !tripped && decoded.sequence < command.sequence) {
    ++counters.stale;
    return;
  }
  // the bridge knows the hardware's limit; the renderer's own clipping is not relied on. The
  // renderer's own clip (overflow-safe, rounded down to the limit, the torque scaled with the
  // force): a plain scale by limit / norm can land one rounding above the limit
  const bool torque_clipped = render::LimitTorque(device.limits().max_torque_Nm, decoded.torque_Nm);
  if (render::LimitForce(device.limits().max_force_N, decoded.force_N, decoded.torque_Nm) ||
      torque_clipped) {
    decoded.clipped = true;
    ++counters.clamped_commands;
  }
  // an equal sequence replaces the command: a renderer ticking faster than the device answers
  // one state several times, and the later answer is the newer one
  command = decoded;
  has_command = true;
  ++counters.accepted;
  last_fresh_ns = now_ns;
  if (tripped) {
    tripped = false;
    ++counters.recoveries;
  }
}

}  // namespace rigidtouch::device
