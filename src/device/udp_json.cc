#include "device/udp_json.h"

#include <string>

namespace rigidtouch::device {

nlohmann::json ToJson(const UdpCounters& counters) {
  nlohmann::json malformed = nlohmann::json::object();
  // index 0 is kOk, which is never a reason for dropping a datagram
  for (std::size_t i = 1; i < kDecodeResultCount; ++i) {
    malformed[std::string(ToString(static_cast<DecodeResult>(i)))] = counters.malformed[i];
  }
  malformed["total"] = counters.MalformedTotal();
  return nlohmann::json{
      {"received", counters.received},
      {"accepted", counters.accepted},
      {"stale", counters.stale},
      {"duplicate", counters.duplicate},
      {"wrong_source", counters.wrong_source},
      {"unauthenticated", counters.unauthenticated},
      {"replayed", counters.replayed},
      {"no_session", counters.no_session},
      {"handshakes", counters.handshakes},
      {"hellos_refused", counters.hellos_refused},
      {"replayed_handshakes", counters.replayed_handshakes},
      {"expired", counters.expired},
      {"session_timeouts", counters.session_timeouts},
      {"clamped_commands", counters.clamped_commands},
      {"malformed", malformed},
      {"watchdog_trips", counters.watchdog_trips},
      {"recoveries", counters.recoveries},
      {"sent", counters.sent},
      {"send_errors", counters.send_errors},
      {"receive_errors", counters.receive_errors},
      {"test_dropped_incoming", counters.test_dropped_incoming},
      {"test_dropped_outgoing", counters.test_dropped_outgoing},
      {"fallback_writes", counters.fallback_writes},
      {"invalid_device_states", counters.invalid_device_states},
      {"peer_changes", counters.peer_changes},
      {"last_errno", counters.last_errno},
  };
}

}  // namespace rigidtouch::device
