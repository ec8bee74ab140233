// The tap experiment's table for people: a compact one on the terminal, the full one in the
// comparison's table file (the JSON has every figure per tap).
#pragma once

#include <string>

#include "analysis/tap_experiment.h"

namespace rigidtouch::cli {

/// Which columns a tap table shows.
enum class TapTable {
  kCompact,  ///< the terminal's: what the device displayed and how the transient repeats
  kFull,     ///< every metric (the comparison's table file)
};

/// The table's header: a Markdown header row and its separator, no newline at the end.
std::string TapTableHeader(TapTable table);

/// One renderer's row over the taps of `run`.
std::string TapTableRow(TapTable table, const std::string& name, const analysis::TapRun& run);

/// The note under a table: what the spectral figures are (both tables) and, for the compact one
/// whose header names no statistic, the statistics over the taps.
std::string TapTableNote(TapTable table, const analysis::TapRun& run);

/// A moving wall's joint over the taps (docs/articulated.md): the header row of its table (a
/// Markdown header and separator, no newline at the end).
std::string JointTableHeader();

/// One renderer's row of the joint table, with its newline; empty for a static wall or a link
/// without a hinge or slide.
std::string JointTableRow(const std::string& name, const analysis::TapRun& run);

}  // namespace rigidtouch::cli
