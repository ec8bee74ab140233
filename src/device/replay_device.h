// A device that replays a recorded session's handle motion (`--device replay:LOG`): each period it
// reports the next recorded state, whatever the scene and renderer, so renderers can be compared
// on identical motion (HAPI's PlaybackHapticsDevice). Commands are not fed back: the recorded hand
// moved the handle as it did, the replayed renderer only decides what would have been displayed.
#pragma once

#include <cstdint>
#include <vector>

#include "io/device_record.h"
#include "rigidtouch/device.h"

namespace rigidtouch::device {

/// Replays io::Record samples, one per period. Read, Write and EndPeriod never allocate or throw.
class ReplayDevice : public Device {
 public:
  /// Takes the recorded samples (at least one; Error otherwise) and the limits to report.
  ReplayDevice(std::vector<io::RecordSample> samples, const DeviceLimits& limits);

  /// The recorded state of the current period. After the last one: that state marked invalid,
  /// so a loop running past the record outputs zero force.
  DeviceState Read() override;
  /// Keeps the command (commanded_force_N) and counts it; the recorded motion does not change.
  void Write(const DeviceCommand& command) override;
  const DeviceLimits& limits() const override { return limits_; }
  /// Moves on to the next recorded sample.
  void EndPeriod(double period_s) override;
  /// The recorded tap index and hand force of the current period.
  void AnnotateTrace(TraceSample& sample) const override;

  /// Number of recorded periods.
  std::int64_t size() const { return static_cast<std::int64_t>(samples_.size()); }
  /// Periods replayed so far.
  std::int64_t position() const { return next_; }
  /// True once every recorded period has been replayed.
  bool finished() const { return next_ >= size(); }
  /// The loop stops once the record is replayed.
  bool Ended() const override { return finished(); }
  /// The force of the last Write [N].
  const Vec3& commanded_force_N() const { return commanded_force_N_; }
  /// The first recorded state (where the handle started).
  const DeviceState& first_state() const { return samples_.front().state; }

 private:
  const io::RecordSample& Current() const;

  std::vector<io::RecordSample> samples_;
  DeviceLimits limits_;
  std::int64_t next_ = 0;
  Vec3 commanded_force_N_ = Vec3::Zero();
};

}  // namespace rigidtouch::device
