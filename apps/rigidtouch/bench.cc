// `rigidtouch bench`: nanoseconds per step of a scene (2000 warm-up steps, then N measured).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <iostream>

#include "base/text.h"
#include "command.h"
#include "engine/workspace.h"
#include "loop/reference_job.h"
#include "scene_flags.h"

namespace rigidtouch::cli {
namespace {

struct BenchFlags {
  SceneFlags scene;
  long steps = 5000;
  long warmup = 2000;
  std::vector<double> tool_force{0.0, 0.0, -2.0};
  bool tool_force_given = false;  // --tool-force on the command line (its default is not)
  bool json = false;
  bool reference = false;
  bool quiet = false;
};

// --reference: the last warm-up steps whose median sizes the fixed job, and the job's first guess
// and largest size in units (a unit is some tens of nanoseconds; the cap is about a second)
constexpr long kReferenceWarmup = 200;
constexpr long kReferenceFirstUnits = 1000;
constexpr long kReferenceMaxUnits = 10'000'000;
constexpr int kCalibrationRuns = 21;
constexpr long kProgressSteps = 1024;  // steps between two looks at the progress

double Percentile(const std::vector<double>& sorted, double q) {
  // nearest rank
  const std::size_t k = static_cast<std::size_t>(std::ceil(q * sorted.size()));
  return sorted[std::min(sorted.size() - 1, k == 0 ? 0 : k - 1)];
}

// median, p99, p99.9 (nearest rank) and max of sorted durations
nlohmann::json Summary(const std::vector<double>& sorted) {
  return {{"median_ns", Percentile(sorted, 0.5)},
          {"p99_ns", Percentile(sorted, 0.99)},
          {"p999_ns", Percentile(sorted, 0.999)},
          {"max_ns", sorted.back()}};
}

// the reference's JSON: the job's size, its summary, and the steps' percentiles over the job's
nlohmann::json ReferenceJson(long units, const std::vector<double>& job_sorted,
                             const nlohmann::json& steps) {
  nlohmann::json r = Summary(job_sorted);
  r["units"] = units;
  for (const char* key : {"median_ns", "p99_ns", "p999_ns", "max_ns"}) {
    r["step_over_job"][key] = steps[key].get<double>() / r[key].get<double>();
  }
  // each one's tail over its own median: comparable even where the two medians differ
  for (const auto& [name, x] :
       {std::pair<const char*, const nlohmann::json*>{"steps", &steps}, {"job", &r}}) {
    const double median = (*x)["median_ns"].get<double>();
    r["tail_over_median"][name] = {{"p99", (*x)["p99_ns"].get<double>() / median},
                                   {"p999", (*x)["p999_ns"].get<double>() / median}};
  }
  return r;
}

// between steps, outside the timed part: every kProgressSteps steps a look at the clock and at
// the stop request
void LookAtProgress(Progress& progress, long done, long total, const char* phase) {
  if (done % kProgressSteps != 0) return;
  const std::string where =
      std::string(phase) + " step " + std::to_string(done) + " of " + std::to_string(total);
  progress.ThrowIfStopped(where, "nothing was measured");
  if (progress.Due()) progress.Report(static_cast<double>(done) / total, where);
}

// bench's lines for people: microseconds to 3-4 digits (the JSON keeps the nanoseconds)
void PrintBench(const nlohmann::json& result, const std::string& source, long units,
                bool reference) {
  const auto us = [](const nlohmann::json& ns) {
    return text::Significant(1e-3 * ns.get<double>());
  };
  std::cout << source << ": median " << us(result["median_ns"]) << " us, p99 "
            << us(result["p99_ns"]) << ", p99.9 " << us(result["p999_ns"]) << ", max "
            << us(result["max_ns"]) << " us per step; " << result["contacts"] << " contacts\n";
  if (reference) {
    const nlohmann::json& r = result["reference"];
    const nlohmann::json& q = r["step_over_job"];
    std::cout << "fixed job of " << units << " units after each step: median " << us(r["median_ns"])
              << " us, p99 " << us(r["p99_ns"]) << ", p99.9 " << us(r["p999_ns"]) << ", max "
              << us(r["max_ns"]) << " us\n"
              << std::fixed << std::setprecision(2) << "step over job: median "
              << q["median_ns"].get<double>() << ", p99 " << q["p99_ns"].get<double>() << ", p99.9 "
              << q["p999_ns"].get<double>() << ", max " << q["max_ns"].get<double>()
              << "; p99.9 over median: steps "
              << r["tail_over_median"]["steps"]["p999"].get<double>() << ", job "
              << r["tail_over_median"]["job"]["p999"].get<double>() << "\n";
  }
}

void RunBench(const BenchFlags& f) {
  if (f.steps < 1) throw Error("--steps must be >= 1, got " + std::to_string(f.steps));
  if (f.warmup < 0) throw Error("--warmup must be >= 0, got " + std::to_string(f.warmup));
  const Vec3 tool_force = ToolForce(f.tool_force);
  if (f.reference && f.warmup < kReferenceWarmup) {
    throw Error("--reference needs --warmup >= " + std::to_string(kReferenceWarmup) + " (got " +
                std::to_string(f.warmup) +
                "): the fixed job is sized to the median of the last 200 warm-up steps");
  }
  const Settings settings = ResolveSettings(f.scene);
  RefuseUnusedRender(settings, {settings.load.render.renderer});
  RefuseDeviceSettings(settings, "bench");
  const Model model = LoadModel(f.scene.scene, settings.load);
  PrintLoadWarnings(model);
  Data data = MakeData(model);
  TickInput input;
  // --tool none: no tool to push (the default force would only move the held placeholder), and a
  // force the user gave is refused rather than dropped
  if (!model.has_tool && f.tool_force_given) {
    throw Error("--tool-force needs a tool; the scene is loaded with --tool none");
  }
  input.tool_wrench.force_N = model.has_tool ? tool_force : Vec3::Zero();
  // the last warm-up steps are timed when the reference job is sized from them
  std::vector<double> warm_ns;
  const std::unique_ptr<Progress> progress = StartProgress("bench", f.quiet);
  const long total = f.warmup + f.steps;
  auto look = [&progress, total](long done, const char* phase) {
    LookAtProgress(*progress, done, total, phase);
  };

  for (long s = 0; s < f.warmup; ++s) {
    look(s, "warm-up");
    const auto t0 = std::chrono::steady_clock::now();
    Tick(model, data, input);
    if (f.reference && s >= f.warmup - kReferenceWarmup) {
      warm_ns.push_back(
          std::chrono::duration<double, std::nano>(std::chrono::steady_clock::now() - t0).count());
    }
  }
  loop::ReferenceJob job;
  long units = 0;
  if (f.reference) {
    std::sort(warm_ns.begin(), warm_ns.end());
    units = loop::CalibrateUnits(Percentile(warm_ns, 0.5), kReferenceFirstUnits, kReferenceMaxUnits,
                                 [&job](long u) { return job.MedianNs(u, kCalibrationRuns); });
  }
  std::vector<double> job_ns(f.reference ? static_cast<std::size_t>(f.steps) : 0);
  const dynamics::GroupSolveCounts before = data.workspace->velocity.Counts();
  std::vector<double> ns(static_cast<std::size_t>(f.steps));
  int max_contacts = 0;
  long impulses = 0;
  double deepest = 0.0;
  for (long s = 0; s < f.steps; ++s) {
    look(f.warmup + s, "measured");
    const auto t0 = std::chrono::steady_clock::now();
    Tick(model, data, input);
    const auto t1 = std::chrono::steady_clock::now();
    ns[s] = std::chrono::duration<double, std::nano>(t1 - t0).count();
    // the job right after each step, so that both meet the machine in the same state
    if (f.reference) job_ns[s] = static_cast<double>(job.TimedRunNs(units));
    max_contacts = std::max(max_contacts, data.ncontact);
    impulses += data.nimpulse;
    for (int c = 0; c < data.ncontact; ++c) deepest = std::max(deepest, data.contacts[c].depth_m);
  }
  progress->Finish();
  const dynamics::GroupSolveCounts solves = data.workspace->velocity.Counts() - before;
  bool finite = true;
  for (const BodyState& b : data.bodies) finite = finite && b.x_W.allFinite();
  std::sort(ns.begin(), ns.end());
  const nlohmann::json steps = Summary(ns);
  nlohmann::json result = {{"scene", model.source},
                           {"steps", f.steps},
                           {"warmup_steps", f.warmup},
                           {"median_ns", steps["median_ns"]},
                           {"p99_ns", steps["p99_ns"]},
                           {"p999_ns", steps["p999_ns"]},
                           {"max_ns", steps["max_ns"]},
                           {"contacts", data.ncontact},
                           {"max_contacts", max_contacts},
                           {"impulses", impulses},
                           {"deepest_penetration_m", deepest},
                           {"finite", finite},
                           {"threads", model.threads},
                           {"worker_jobs_taken_back",
                            data.workspace->worker ? data.workspace->worker->jobs_taken_back() : 0},
                           {"group_solves",
                            {{"factorisations", solves.factorisations},
                             {"lagged", solves.lagged_solves},
                             {"lagged_failures", solves.lagged_failures},
                             {"refinements", solves.refinement_steps},
                             {"unkept_factors", solves.unkept}}},
                           {"warnings", WarningsJson(data)}};
  if (f.reference) {
    std::sort(job_ns.begin(), job_ns.end());
    result["reference"] = ReferenceJson(units, job_ns, steps);
    result["reference"]["checksum"] = job.chain();
  }
  if (f.json) {
    std::cout << result.dump() << "\n";
    return;
  }
  PrintBench(result, model.source, units, f.reference);
}

void RegisterBench(CLI::App& root) {
  auto f = std::make_shared<BenchFlags>();
  CLI::App* app = root.add_subcommand("bench", "time the steps of a scene");
  AddSceneFlags(app, f->scene);
  AddThreadsFlag(app, f->scene);
  app->add_option("--steps", f->steps, "measured steps")->capture_default_str();
  app->add_option("--warmup", f->warmup, "warm-up steps")->capture_default_str();
  app->add_option("--tool-force", f->tool_force, "constant tool force FX FY FZ [N]")->expected(3);
  app->add_flag("--json", f->json, "print one JSON object");
  AddQuietFlag(*app, f->quiet);
  app->add_flag("--reference", f->reference,
                "after each step, time a fixed job sized to the median of the last 200 warm-up "
                "steps: the tail the machine adds to work that never varies "
                "(docs/performance.md)");
  // an error about a parameter the user wrote says where it was written
  app->callback([f, app] {
    f->tool_force_given = app->count("--tool-force") > 0;
    WithOrigins(ResolveSettings(f->scene), [&] { RunBench(*f); });
  });
}

const CommandRegistrar bench_registrar("bench", &RegisterBench);

}  // namespace
}  // namespace rigidtouch::cli
