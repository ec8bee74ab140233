// `rigidtouch bench`: nanoseconds per step of a scene (2000 warm-up steps, then N measured).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <iostream>

#include "command.h"
#include "render/workspace.h"
#include "scene_flags.h"

namespace rigidtouch::cli {
namespace {

struct BenchFlags {
  SceneFlags scene;
  long steps = 5000;
  long warmup = 2000;
  std::vector<double> tool_force{0.0, 0.0, -2.0};
  bool json = false;
};

double Percentile(const std::vector<double>& sorted, double q) {
  // nearest rank
  const std::size_t k = static_cast<std::size_t>(std::ceil(q * sorted.size()));
  return sorted[std::min(sorted.size() - 1, k == 0 ? 0 : k - 1)];
}

void Run(const BenchFlags& f) {
  if (f.steps < 1) throw Error("--steps must be >= 1");
  const Model model = LoadModel(f.scene.scene, ToLoadOptions(f.scene));
  PrintLoadWarnings(model);
  Data data = MakeData(model);
  TickInput input;
  input.tool_wrench.force_N = Vec3(f.tool_force[0], f.tool_force[1], f.tool_force[2]);
  for (long s = 0; s < f.warmup; ++s) Tick(model, data, input);
  const dynamics::GroupSolveCounts before = data.workspace->velocity.Counts();
  std::vector<double> ns(static_cast<std::size_t>(f.steps));
  int max_contacts = 0;
  long impulses = 0;
  double deepest = 0.0;
  for (long s = 0; s < f.steps; ++s) {
    const auto t0 = std::chrono::steady_clock::now();
    Tick(model, data, input);
    const auto t1 = std::chrono::steady_clock::now();
    ns[s] = std::chrono::duration<double, std::nano>(t1 - t0).count();
    max_contacts = std::max(max_contacts, data.ncontact);
    impulses += data.nimpulse;
    for (int c = 0; c < data.ncontact; ++c) deepest = std::max(deepest, data.contacts[c].depth_m);
  }
  const dynamics::GroupSolveCounts solves = data.workspace->velocity.Counts() - before;
  bool finite = true;
  for (const BodyState& b : data.bodies) finite = finite && b.x_W.allFinite();
  std::sort(ns.begin(), ns.end());
  const nlohmann::json result = {
      {"scene", model.source},
      {"steps", f.steps},
      {"warmup_steps", f.warmup},
      {"median_ns", Percentile(ns, 0.5)},
      {"p99_ns", Percentile(ns, 0.99)},
      {"p999_ns", Percentile(ns, 0.999)},
      {"max_ns", ns.back()},
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
  if (f.json) {
    std::cout << result.dump() << "\n";
    return;
  }
  std::cout << model.source << ": median " << result["median_ns"] << " ns, p99 " << result["p99_ns"]
            << ", p99.9 " << result["p999_ns"] << ", max " << result["max_ns"] << " ns per step; "
            << data.ncontact << " contacts\n";
}

void Register(CLI::App& root) {
  auto f = std::make_shared<BenchFlags>();
  CLI::App* app = root.add_subcommand("bench", "time the steps of a scene");
  AddSceneFlags(app, f->scene);
  AddThreadsFlag(app, f->scene);
  app->add_option("--steps", f->steps, "measured steps")->capture_default_str();
  app->add_option("--warmup", f->warmup, "warm-up steps")->capture_default_str();
  app->add_option("--tool-force", f->tool_force, "constant tool force FX FY FZ [N]")->expected(3);
  app->add_flag("--json", f->json, "print one JSON object");
  // an error about a parameter the user wrote says where it was written
  app->callback([f] { WithOrigins(ResolveSettings(f->scene), [&] { Run(*f); }); });
}

const CommandRegistrar registrar(&Register);

}  // namespace
}  // namespace rigidtouch::cli
