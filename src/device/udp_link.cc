#include "device/udp_link.h"

#include <cmath>
#include <numeric>
#include <string>

#include "rigidtouch/types.h"

namespace rigidtouch::device {

std::uint64_t UdpCounters::MalformedTotal() const {
  return std::accumulate(malformed.begin(), malformed.end(), std::uint64_t{0});
}

void ValidatePacketLoss(const PacketLoss& loss, std::string_view what) {
  const auto check = [&](double fraction, std::string_view field) {
    if (!(fraction >= 0.0 && fraction <= 1.0)) {
      throw Error(std::string(what) + ": " + std::string(field) + " = " + std::to_string(fraction) +
                  " is outside [0, 1]");
    }
  };
  check(loss.incoming_fraction, "test_loss.incoming_fraction");
  check(loss.outgoing_fraction, "test_loss.outgoing_fraction");
}

void ValidateWatchdog(double watchdog_s, std::string_view what) {
  if (!(std::isfinite(watchdog_s) && watchdog_s > 0.0 && watchdog_s <= 10.0)) {
    throw Error(std::string(what) + ": watchdog_s = " + std::to_string(watchdog_s) +
                " is outside (0, 10] s");
  }
}

std::int64_t WatchdogNs(double watchdog_s, std::string_view what) {
  ValidateWatchdog(watchdog_s, what);
  return std::llround(watchdog_s * 1e9);
}

LossSimulator::LossSimulator(const PacketLoss& loss) : loss_(loss), generator_(loss.seed) {}

bool LossSimulator::Draw(double fraction) {
  // no draw at all without loss, so the common case costs nothing
  if (fraction <= 0.0) return false;
  return uniform_(generator_) < fraction;
}

void SendCounted(UdpSocket& socket, LossSimulator& loss, UdpCounters& counters,
                 std::span<const std::uint8_t> datagram, const UdpEndpoint& destination) noexcept {
  if (loss.DropOutgoing()) {
    ++counters.test_dropped_outgoing;
    return;
  }
  const int status = socket.SendTo(datagram, destination);
  if (status != 0) {
    ++counters.send_errors;
    counters.last_errno = status;
    return;
  }
  ++counters.sent;
}

}  // namespace rigidtouch::device
