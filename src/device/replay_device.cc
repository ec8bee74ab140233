#include "device/replay_device.h"

#include <utility>

namespace rigidtouch::device {

ReplayDevice::ReplayDevice(std::vector<io::RecordSample> samples, const DeviceLimits& limits)
    : samples_(std::move(samples)), limits_(limits) {
  if (samples_.empty()) throw Error("replay: the record holds no tick");
}

const io::RecordSample& ReplayDevice::Current() const {
  return samples_[static_cast<std::size_t>(finished() ? size() - 1 : next_)];
}

DeviceState ReplayDevice::Read() {
  DeviceState s = Current().state;
  if (finished()) s.valid = false;
  return s;
}

void ReplayDevice::Write(const DeviceCommand& command) {
  commanded_force_N_ = command.force_N;
}

void ReplayDevice::EndPeriod(double period_s) {
  static_cast<void>(period_s);
  if (!finished()) ++next_;
}

void ReplayDevice::AnnotateTrace(TraceSample& sample) const {
  const io::RecordSample& r = Current();
  sample.tap = finished() ? -1 : r.tap;
  sample.hand_force_N = finished() ? Vec3::Zero() : r.hand_force_N;
}

}  // namespace rigidtouch::device
