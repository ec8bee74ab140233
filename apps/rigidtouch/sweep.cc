// `rigidtouch sweep`: sweeps of the tap experiment on Dask. The runner is the Python module's
// (python3 -m rigidtouch.sweeps), so the command line and `rigidtouch.sweep(...)` are one code
// path; this subcommand finds the module next to the executable and hands over to it.
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <optional>
#include <string>
#include <vector>

#include "command.h"
#include "rigidtouch/types.h"

#ifndef RIGIDTOUCH_PYTHON
#define RIGIDTOUCH_PYTHON "python3"  // the module was not configured: the one on PATH
#endif

namespace rigidtouch::cli {
namespace {

struct SweepFlags {
  std::string spec;
  std::string out;
  std::string scheduler;
  std::optional<int> workers;
  std::optional<int> batch;
  bool json = false;
  bool quiet = false;
};

// folders holding the package rigidtouch/: the build tree's python/ beside the executable, the
// installed lib/python3/dist-packages of its prefix
std::vector<std::string> PackageDirs() {
  std::vector<std::string> dirs;
  std::error_code ec;
  const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (ec) return dirs;
  for (const std::filesystem::path& dir :
       {exe.parent_path() / "python",
        exe.parent_path().parent_path() / "lib/python3/dist-packages"}) {
    if (std::filesystem::exists(dir / "rigidtouch" / "__init__.py", ec)) dirs.push_back(dir);
  }
  return dirs;
}

void RunSweep(const SweepFlags& f) {
  std::string path;
  for (const std::string& dir : PackageDirs()) path += (path.empty() ? "" : ":") + dir;
  if (const char* old = std::getenv("PYTHONPATH"); old != nullptr && *old != '\0') {
    path += (path.empty() ? "" : ":") + std::string(old);
  }
  if (path.empty()) {
    throw Error(
        "sweep needs the Python module rigidtouch, found neither beside this executable nor on "
        "PYTHONPATH: configure with -DRIGIDTOUCH_BUILD_PYTHON=ON and build (or install) it");
  }
  setenv("PYTHONPATH", path.c_str(), 1);
  // the interpreter the module was built for, unless RIGIDTOUCH_PYTHON names another
  const char* env = std::getenv("RIGIDTOUCH_PYTHON");
  const std::string python = env != nullptr && *env != '\0' ? env : RIGIDTOUCH_PYTHON;
  std::vector<std::string> args = {python,  "-m", "rigidtouch.sweeps", "--spec", f.spec,
                                   "--out", f.out};
  if (!f.scheduler.empty()) args.insert(args.end(), {"--scheduler", f.scheduler});
  if (f.workers) args.insert(args.end(), {"--workers", std::to_string(*f.workers)});
  if (f.batch) args.insert(args.end(), {"--batch", std::to_string(*f.batch)});
  if (f.json) args.push_back("--json");
  if (f.quiet) args.push_back("--quiet");
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  std::cout.flush();
  execvp(python.c_str(), argv.data());
  throw Error("cannot run " + python + " for the sweep: " + std::strerror(errno));
}

void RegisterSweep(CLI::App& root) {
  auto f = std::make_shared<SweepFlags>();
  CLI::App* app = root.add_subcommand(
      "sweep",
      "sweep the tap experiment over a grid of parameters on Dask (local worker processes or a "
      "cluster); results appended per point, so a rerun resumes (docs/python.md)");
  app->add_option("--spec", f->spec, "sweep spec (JSON): base flags and a grid of tap flags")
      ->required();
  app->add_option("--out", f->out, "results file (JSON lines), appended per point")->required();
  auto* scheduler =
      app->add_option("--scheduler", f->scheduler, "an existing Dask scheduler, tcp://HOST:8786");
  app->add_option("--workers", f->workers, "local worker processes (default: one per core)")
      ->check(CLI::Range(1, 1024))
      ->excludes(scheduler);
  app->add_option("--batch", f->batch, "points per Dask task (default: about 8 tasks per worker)")
      ->check(CLI::Range(1, 100000));
  app->add_flag("--json", f->json, "print one JSON object");
  AddQuietFlag(*app, f->quiet);
  app->callback([f] { RunSweep(*f); });
}

const CommandRegistrar sweep_registrar("sweep", &RegisterSweep);

}  // namespace
}  // namespace rigidtouch::cli
