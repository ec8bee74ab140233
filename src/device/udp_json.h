// JSON view of the UDP link counters, for `rigidtouch serve --json` and `device-sim --json`.
#pragma once

#include <nlohmann/json.hpp>

#include "device/udp_link.h"

namespace rigidtouch::device {

/// All fields of UdpCounters; "malformed" is an object keyed by DecodeResult name
/// ("too_short", "wrong_version", ...) plus "total".
nlohmann::json ToJson(const UdpCounters& counters);

}  // namespace rigidtouch::device
