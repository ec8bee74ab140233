// Text tables of benchmark results: per engine, and the ratios rigidtouch / peer.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "bench/harness.h"

namespace rigidtouch::bench {

/// Merges the repetitions of each (scene, engine) run (Google Benchmark's
/// --benchmark_repetitions, best with --benchmark_enable_random_interleaving so that every
/// engine's repetitions spread over the same stretch of the machine's changing speed): the
/// durations are pooled and summarised again, the contact means weighted by steps, and the gate
/// failures united (each different sentence once). The merged runs come in `scenes` order, then
/// `engines` order; a pair that never ran is left out.
std::vector<RunResult> MergeRepetitions(const std::vector<RunResult>& results,
                                        const std::vector<std::string>& scenes,
                                        const std::vector<std::string>& engines);

/// Returns one row per run: scene, engine, median / p99 / p99.9 / max microseconds per step,
/// mean contact count and the gate verdict (with the failed gates spelled out below the table).
std::string FormatResultTable(const std::vector<RunResult>& results);

/// Returns, per scene, the ratio of the reference engine's median (and p99.9) step time to each
/// peer's: above 1 means the reference is slower. A cell reads "n/a" when either run is
/// missing and carries a "!" when either run failed a gate.
std::string FormatRatioTable(const std::vector<RunResult>& results, std::string_view reference,
                             const std::vector<std::string>& peers);

}  // namespace rigidtouch::bench
