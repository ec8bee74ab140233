// Trace files: one CSV row per haptic tick, a header row, SI units in the column names.
#pragma once

#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "rigidtouch/trace.h"

namespace rigidtouch::io {

/// Column names of a trace CSV, in file order: time_s; tool_{x,y,z}_m; tool_v{x,y,z}_mps;
/// penalty_f{x,y,z}_N; impulsive_f{x,y,z}_N; device_f{x,y,z}_N; hand_f{x,y,z}_N;
/// wall_n{x,y,z} (unit normal, no unit); penetration_m; tool_contacts; impulses;
/// kinetic_energy_before_J; kinetic_energy_after_J; clipped (0/1); tap; step.
std::span<const std::string_view> TraceColumns();

/// Writes `samples` to `path` atomically with WriteFileAtomically (io/output_file.h), so readers
/// never see a half-written trace and only a regular file is ever replaced. Numbers are written in
/// the shortest form that reads back to the same double. Throws rigidtouch::Error for a bad path
/// and io::OutputError for a failed write, naming the path and the reason, and then leaves no
/// file behind.
void WriteTraceCsv(const std::string& path, std::span<const TraceSample> samples);

/// Reads a trace written by WriteTraceCsv (columns may come in any order; extra columns are
/// ignored). Throws rigidtouch::Error naming the path, line and column on a missing file, a
/// missing column or a value that does not parse.
std::vector<TraceSample> ReadTraceCsv(const std::string& path);

}  // namespace rigidtouch::io
