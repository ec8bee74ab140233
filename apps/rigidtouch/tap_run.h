// `rigidtouch tap` in process, for the Python bindings: the subcommand's own flags, settings
// resolution (flag > config > device preset > default) and checks, with the run returned
// instead of printed, so a sweep point means exactly what the same flags mean to the CLI.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "analysis/tap_experiment.h"

namespace rigidtouch::cli {

/// A tap run and the JSON object `rigidtouch tap --json` prints for it.
struct TapOutcome {
  analysis::TapRun run;
  nlohmann::json result;
};

/// Runs `rigidtouch tap ARGS...` (the flags without the subcommand name). Throws Error on a
/// malformed flag or a bad value, naming it as the CLI does; --compare-walls, --trace, --plot
/// and --json are refused. A run whose state went non-finite is returned, not thrown: its
/// result's "non_finite_state" says so.
TapOutcome RunTapFlags(const std::vector<std::string>& args);

/// The model and simulated hand and device `rigidtouch tap ARGS...` would run (PrepareTap), for
/// a loop driven from elsewhere. Throws Error as RunTapFlags.
analysis::TapSetup PrepareTapFlags(const std::vector<std::string>& args);

/// The long names of tap's flags, without the dashes (for a sweep's spec to be checked before it
/// runs).
std::vector<std::string> TapFlagNames();

}  // namespace rigidtouch::cli
