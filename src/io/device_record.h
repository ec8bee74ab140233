// Device records (`--record LOG`): every tick's device state as the loop read it and the command it
// wrote, one CSV row per tick, so a session's hand motion can be replayed through any scene and
// renderer (device/replay_device.h; HAPI's PlaybackHapticsDevice). The format is documented in
// docs/device-protocol.md, "Recording and replay".
#pragma once

#include <cstdint>
#include <cstdio>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "rigidtouch/types.h"

namespace rigidtouch::io {

/// One tick of a record: what the device reported, what the loop commanded, and what only the
/// device knew (the scripted tap in progress and the simulated hand's force,
/// Device::AnnotateTrace).
struct RecordSample {
  std::int64_t tick = 0;             // the loop's tick index, from 0
  DeviceState state;                 // as the loop read it, `fresh` as the loop decided
  DeviceCommand command;             // as the loop wrote it, after its guards
  int tap = -1;                      // scripted tap in progress, -1 between taps or unknown
  Vec3 hand_force_N = Vec3::Zero();  // simulated hand's force on the handle (0 if unknown)
};

/// The first line of every record file, before the rate.
inline constexpr std::string_view kRecordMagic = "# rigidtouch device record v1";

/// Column names of a record, in file order (docs/device-protocol.md, "Recording and replay").
std::span<const std::string_view> RecordColumns();

/// Streams a record to a file from the writer thread: rows go to a temporary file in the target's
/// folder, renamed over the target by Commit(), so a session that fails leaves no partial record
/// and replaces nothing but a regular file. Numbers are written in the shortest form that reads
/// back to the same double, so a replay sees the recorded states bit for bit.
class RecordFileWriter {
 public:
  /// Checks `path` (Error naming it for a bad path), creates the temporary file and writes the
  /// header with the loop's rate [Hz].
  RecordFileWriter(const std::string& path, double rate_hz);
  /// Removes the temporary file unless Commit() succeeded.
  ~RecordFileWriter();
  RecordFileWriter(const RecordFileWriter&) = delete;
  RecordFileWriter& operator=(const RecordFileWriter&) = delete;

  /// Appends one row per sample. Throws OutputError naming the path on a failed write.
  void Append(std::span<const RecordSample> samples);
  /// Flushes, syncs and renames the file into place. Throws OutputError on failure.
  void Commit();

 private:
  void Fail(int error_number);

  std::string path_;
  std::string temp_path_;
  std::FILE* file_ = nullptr;
  std::string line_;  // scratch, reused for every row
  bool committed_ = false;
};

/// A record read back: the loop's rate and its samples in tick order.
struct Record {
  double rate_hz = 0.0;
  std::vector<RecordSample> samples;
};

/// Reads a record written by RecordFileWriter. Throws Error naming the path, the line and the
/// column for a missing file, a wrong first line, a missing column or a value that does not parse
/// (a flag other than 0/1, ticks not counting up by one). Non-finite numbers are read as written:
/// they are what the device reported, and the loop treats such a state as invalid.
Record ReadRecord(const std::string& path);

}  // namespace rigidtouch::io
