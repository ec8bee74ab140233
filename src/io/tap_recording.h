// Tap recordings for fitting a material (docs/materials.md): CSV files whose header names each
// column with its unit, read strictly. Every problem is an Error "FILE:LINE: what is wrong".
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace rigidtouch::io {

/// What the recorded signal measures: the handle's acceleration along the tap normal [m/s^2]
/// (column `acceleration_mps2`) or the contact force [N] (column `force_N`).
enum class TapQuantity { kAcceleration, kForce };

/// The unit of a quantity as the messages and material files write it: "m/s^2" or "N".
std::string_view TapQuantityUnit(TapQuantity quantity);

/// The column name of a quantity: "acceleration_mps2" or "force_N".
std::string_view TapQuantityColumn(TapQuantity quantity);

/// One tap's samples, in file order. Optional columns are empty when the file has none.
struct RecordedTap {
  int tap = 0;                 // the `tap` column's value (0 without that column)
  std::vector<double> time_s;  // strictly increasing
  std::vector<double> signal;  // m/s^2 or N (TapRecording::quantity)
  std::vector<double> velocity_mps;
  std::vector<double> position_m;
  std::vector<double> impact_speed_mps;
  std::vector<int> line;  // the file line of each sample (1-based; the header is line 1)
};

/// A recording: one file, one or more taps. Without a `tap` column the whole file is one tap;
/// with one, each run of rows with the same value is a tap (a value may not come back later).
struct TapRecording {
  std::string path;  // as given: errors name it
  TapQuantity quantity = TapQuantity::kAcceleration;
  std::vector<RecordedTap> taps;
};

/// The valid column names, in the order the docs list them.
const std::vector<std::string>& TapRecordingColumns();

/// Reads the CSV text of a recording named `path`. Line 1 is the header: comma-separated column
/// names from TapRecordingColumns, each at most once, with `time_s` and exactly one of
/// `acceleration_mps2` and `force_N`; at most one of `velocity_mps` and `position_m`. Lines
/// starting with '#' are comments and blank lines are skipped (both before the header too).
/// Every row has one finite number per column; time strictly increases within a tap; a tap has
/// at least two samples. Throws Error "PATH:LINE: ..." for the first problem.
TapRecording ParseTapRecording(std::string_view text, const std::string& path);

/// Reads the file at `path` (at most 256 MiB) with ParseTapRecording. Errors name the file.
TapRecording ReadTapRecording(const std::string& path);

}  // namespace rigidtouch::io
