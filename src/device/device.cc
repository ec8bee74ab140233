#include "rigidtouch/device.h"

#include <ctime>

namespace rigidtouch::device {

std::int64_t MonotonicNowNs() noexcept {
  timespec now{};
  clock_gettime(CLOCK_MONOTONIC, &now);
  return static_cast<std::int64_t>(now.tv_sec) * 1'000'000'000 + now.tv_nsec;
}

}  // namespace rigidtouch::device
