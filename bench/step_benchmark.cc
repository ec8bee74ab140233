// Google Benchmark suite: every registered engine (rigidtouch once its adapter is registered,
// MuJoCo, Bullet) on every benchmark scene, then tables of the results and of the ratios.
//
// Extra flags (after Google Benchmark's own):
//   --rigidtouch_scenes=DIR   folder with tap.xml, stack.xml, pile.xml and the articulated
//                             door.xml, drawer.xml, lever.xml, arm.xml (default: the source tree)
//   --rigidtouch_scale=X      measure X (0 < X <= 1) of the specified steps, for smoke runs
//   --rigidtouch_interleave=N instead of Google Benchmark's runs, measure every engine of a scene
//                             in turns of N steps (strikes), the engines' order rotating: each
//                             engine then sees the same stretches of the machine's speed
//   --rigidtouch_large        also the large scenes pile400 and pile1000 (minutes: the peers
//                             take 5 ms to seconds per step there)
//   --rigidtouch_only=A,B     only the scenes named (both modes; e.g. pile400,pile1000)
//   --rigidtouch_engines=A,B  interleaved mode: only these engines (e.g. rigidtouch,bullet: MuJoCo
//                             2.2 cannot hold pile1000's or pile2000's contacts)
//   --rigidtouch_humanoid=PATH also the humanoid scene: MuJoCo's model/humanoid/humanoid.xml at
//                             PATH, lying on its back with the tool pushed onto its chest
//   --rigidtouch_peer_settings=stacking|defaults
//                             the peers' solver settings: those their documentation recommends
//                             for stacks (the default), or every setting at its default
// With --benchmark_repetitions=N --benchmark_enable_random_interleaving=true every scene and
// engine runs N times in random order and the tables pool the repetitions: each engine's steps
// then spread over the same stretch of a shared machine's changing speed, though at the scale of
// whole runs only.
#include <benchmark/benchmark.h>

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "bench/engine.h"
#include "bench/harness.h"
#include "bench/report.h"
#include "bench/scene.h"

namespace rigidtouch::bench {
namespace {

std::vector<RunResult>& Results() {
  static std::vector<RunResult> results;
  return results;
}

void ReportGateFailure(const RunResult& result) {
  std::fprintf(stderr,
               "\n!!!!!!!!!! QUALITY GATE FAILED: %s / %s -- its times are NOT comparable "
               "!!!!!!!!!!\n",
               result.scene.c_str(), result.engine.c_str());
  for (const std::string& failure : result.gates.failures) {
    std::fprintf(stderr, "!!!   %s\n", failure.c_str());
  }
  std::fprintf(stderr, "!!!   (measured anyway: median %.1f us, p99.9 %.1f us per step)\n\n",
               result.time.median_ns * 1e-3, result.time.p999_ns * 1e-3);
}

void RunScene(benchmark::State& state, const EngineEntry& entry, const Scene& scene) {
  const auto engine = entry.make();
  SceneRun run(*engine, scene);
  try {
    run.Prepare();
  } catch (const Error& error) {
    state.SkipWithError(error.what());
    return;
  }
  for (auto _ : state) {
    const std::int64_t duration_ns = run.MeasureOne();
    state.SetIterationTime(duration_ns > 0 ? static_cast<double>(duration_ns) * 1e-9 : 0.0);
  }
  const RunResult result = run.Finish();
  Results().push_back(result);
  state.counters["median_ns"] = result.time.median_ns;
  state.counters["p99_ns"] = result.time.p99_ns;
  state.counters["p99.9_ns"] = result.time.p999_ns;
  state.counters["max_ns"] = result.time.max_ns;
  state.counters["contacts"] = result.mean_contacts;
  state.counters["penetration_mm"] = result.gates.deepest_penetration_m * 1e3;
  state.counters["gate_failures"] = static_cast<double>(result.gates.failures.size());
  if (!result.gates.ok()) {
    ReportGateFailure(result);
    std::string message = "quality gate failed:";
    for (const std::string& failure : result.gates.failures) message += " " + failure + ";";
    state.SkipWithError(message.c_str());
  }
}

std::string FlagValue(int argc, char** argv, const std::string& flag) {
  const std::string prefix = "--" + flag + "=";
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg.rfind(prefix, 0) == 0) return arg.substr(prefix.size());
  }
  return "";
}

// every engine on every scene in turns of `block` measurements (MeasureInterleaved); an engine
// whose scene does not load is reported and left out
std::vector<RunResult> RunInterleaved(const std::vector<Scene>& scenes, int block,
                                      const std::string& only_engines) {
  std::vector<RunResult> results;
  for (const Scene& scene : scenes) {
    std::vector<std::unique_ptr<Engine>> engines;
    std::vector<std::unique_ptr<SceneRun>> runs;
    std::vector<SceneRun*> prepared;
    for (const EngineEntry& entry : Engines()) {
      if (!only_engines.empty() &&
          ("," + only_engines + ",").find("," + entry.name + ",") == std::string::npos) {
        continue;
      }
      engines.push_back(entry.make());
      runs.push_back(std::make_unique<SceneRun>(*engines.back(), scene));
      try {
        runs.back()->Prepare();
        prepared.push_back(runs.back().get());
      } catch (const Error& error) {
        std::cerr << "error: " << scene.name << " / " << entry.name << ": " << error.what() << "\n";
      }
    }
    MeasureInterleaved(prepared, scene.measured_steps, block);
    for (SceneRun* run : prepared) {
      results.push_back(run->Finish());
      if (!results.back().gates.ok()) ReportGateFailure(results.back());
    }
  }
  return results;
}

// removes our flags so Google Benchmark does not reject them
void DropFlags(int& argc, char** argv) {
  int kept = 1;
  for (int i = 1; i < argc; ++i) {
    if (std::string(argv[i]).rfind("--rigidtouch_", 0) != 0) argv[kept++] = argv[i];
  }
  argc = kept;
}

}  // namespace
}  // namespace rigidtouch::bench

int main(int argc, char** argv) {
  using namespace rigidtouch::bench;
  std::string scenes_dir = FlagValue(argc, argv, "rigidtouch_scenes");
  if (scenes_dir.empty()) scenes_dir = DefaultScenesDir();
  const std::string scale_text = FlagValue(argc, argv, "rigidtouch_scale");
  const std::string interleave_text = FlagValue(argc, argv, "rigidtouch_interleave");
  bool large = false;
  for (int i = 1; i < argc; ++i) large |= std::string(argv[i]) == "--rigidtouch_large";
  const std::string only = FlagValue(argc, argv, "rigidtouch_only");
  const std::string only_engines = FlagValue(argc, argv, "rigidtouch_engines");
  const std::string peer_settings_text = FlagValue(argc, argv, "rigidtouch_peer_settings");
  std::string humanoid_path;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--rigidtouch_humanoid" || arg.rfind("--rigidtouch_humanoid=", 0) == 0) {
      humanoid_path = FlagValue(argc, argv, "rigidtouch_humanoid");
      if (humanoid_path.empty()) {
        std::cerr << "error: --rigidtouch_humanoid needs the path of MuJoCo's "
                     "model/humanoid/humanoid.xml: --rigidtouch_humanoid=PATH\n";
        return 2;
      }
    }
  }
  DropFlags(argc, argv);
  int interleave = 0;
  if (!interleave_text.empty()) {
    interleave = std::atoi(interleave_text.c_str());
    if (interleave < 1) {
      std::cerr << "error: --rigidtouch_interleave must be a whole number of steps >= 1, got '"
                << interleave_text << "'\n";
      return 2;
    }
  }

  static std::vector<Scene> scenes;
  try {
    const double scale = scale_text.empty() ? 1.0 : std::atof(scale_text.c_str());
    const PeerSettings peer_settings = peer_settings_text.empty()
                                           ? PeerSettings::kStacking
                                           : ParsePeerSettings(peer_settings_text);
    scenes = BenchmarkScenes(scenes_dir, scale);
    for (Scene& scene : ArticulatedBenchmarkScenes(scenes_dir, scale)) scenes.push_back(scene);
    if (!humanoid_path.empty()) {
      const std::string dir = (std::filesystem::temp_directory_path() /
                               ("rigidtouch_bench_humanoid_" + std::to_string(getpid())))
                                  .string();
      scenes.push_back(HumanoidBenchmarkScene(
          WriteHumanoidWrapper(humanoid_path, dir, "rigidtouch_humanoid"), scale));
    }
    if (large || !only.empty()) {
      for (Scene& scene : LargeBenchmarkScenes(scenes_dir, scale)) scenes.push_back(scene);
    }
    if (!only.empty()) {
      const std::string list = "," + only + ",";
      std::vector<Scene> kept;
      for (const Scene& scene : scenes) {
        if (list.find("," + scene.name + ",") != std::string::npos) kept.push_back(scene);
      }
      if (kept.empty()) {
        std::cerr << "error: --rigidtouch_only=" << only << " names no benchmark scene\n";
        return 2;
      }
      scenes = kept;
    }
    for (Scene& scene : scenes) scene.peer_settings = peer_settings;
  } catch (const rigidtouch::Error& error) {
    std::cerr << "error: " << error.what() << "\n";
    return 2;
  }
  for (const Scene& scene : scenes) {
    for (const EngineEntry& entry : Engines()) {
      benchmark::RegisterBenchmark(
          (scene.name + "/" + entry.name).c_str(),
          [&entry, &scene](benchmark::State& state) { RunScene(state, entry, scene); })
          ->UseManualTime()
          ->Iterations(scene.measured_steps)
          ->Unit(benchmark::kMicrosecond);
    }
  }
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  if (interleave > 0) {
    std::cout << "interleaved: every engine of a scene in turns of " << interleave
              << " measured steps (strikes)\n";
    Results() = RunInterleaved(scenes, interleave, only_engines);
  } else {
    benchmark::RunSpecifiedBenchmarks();
  }
  benchmark::Shutdown();

  std::vector<std::string> scene_names, engine_names, peers;
  for (const Scene& scene : scenes) scene_names.push_back(scene.name);
  for (const EngineEntry& entry : Engines()) {
    engine_names.push_back(entry.name);
    if (entry.name != kReferenceEngine) peers.push_back(entry.name);
  }
  // repetitions (--benchmark_repetitions) of one scene and engine are pooled
  const std::vector<RunResult> results = MergeRepetitions(Results(), scene_names, engine_names);
  std::cout << "\n" << FormatResultTable(results) << "\n";
  std::cout << FormatRatioTable(results, kReferenceEngine, peers);
  bool has_reference = false;
  for (const EngineEntry& entry : Engines()) has_reference |= entry.name == kReferenceEngine;
  if (!has_reference) {
    std::cout << "(no engine named '" << kReferenceEngine
              << "' is registered yet: its column stays n/a)\n";
  }
  if (peers.size() >= 2) std::cout << "\n" << FormatRatioTable(results, peers[1], {peers[0]});
  // the machine's own tail at each of the reference engine's step times
  std::cout << "\nmachine noise floor: a constant-work kernel timed like a step, calibrated to "
            << kReferenceEngine << "'s median, as many samples as the scene's steps\n";
  std::printf("%-13s %-14s %-14s %-24s %-24s\n", "scene", "median_us", "kernel_us",
              "kernel p99.9/median", "engine p99.9/median");
  for (const RunResult& r : results) {
    if (r.engine != kReferenceEngine || r.time.count == 0) continue;
    const TimeSummary probe = ConstantWorkProbe(r.time.median_ns, static_cast<int>(r.time.count));
    std::printf("%-13s %-14.1f %-14.1f %-24.1f %-24.1f\n", r.scene.c_str(), r.time.median_ns * 1e-3,
                probe.median_ns * 1e-3, probe.p999_ns / probe.median_ns,
                r.time.p999_ns / r.time.median_ns);
  }
  std::cout << "\nconfiguration:\n";
  std::vector<std::string> printed;
  for (const RunResult& result : results) {
    bool seen = false;
    for (const std::string& line : printed) seen |= line == result.configuration;
    if (!seen) {
      printed.push_back(result.configuration);
      std::cout << "  " << result.engine << ": " << result.configuration << "\n";
    }
  }
  return 0;
}
