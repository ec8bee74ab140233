// Text tables of benchmark results: per engine, and the ratios rigidtouch / peer.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "bench/harness.h"

namespace rigidtouch::bench {

/// Returns one row per run: scene, engine, median / p99 / p99.9 / max microseconds per step,
/// mean contact count and the gate verdict (with the failed gates spelled out below the table).
std::string FormatResultTable(const std::vector<RunResult>& results);

/// Returns, per scene, the ratio of the reference engine's median (and p99.9) step time to each
/// peer's: above 1 means the reference is slower. A cell reads "n/a" when either run is
/// missing and carries a "!" when either run failed a gate.
std::string FormatRatioTable(const std::vector<RunResult>& results, std::string_view reference,
                             const std::vector<std::string>& peers);

}  // namespace rigidtouch::bench
