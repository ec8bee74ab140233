// `rigidtouch study run|simulate|analyze|predict`: perception-study sessions for people, virtual
// cohorts of simulated participants, analysis of logs, and the observer model's predictions.
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "base/text.h"
#include "device/device_spec.h"
#include "io/output_file.h"
#include "rigidtouch/command.h"
#include "rigidtouch/types.h"
#include "scene_flags.h"
#include "study/analysis.h"
#include "study/log.h"
#include "study/observer.h"
#include "study/protocol.h"
#include "study/session.h"
#include "study/simulate.h"
#include "study/stimulus.h"

#ifndef RIGIDTOUCH_VERSION
#define RIGIDTOUCH_VERSION "unknown"
#endif

namespace rigidtouch::cli {

namespace {

using nlohmann::json;
namespace st = rigidtouch::study;

constexpr char kSoftwareVersion[] = RIGIDTOUCH_VERSION;

struct RunOptions {
  std::string protocol;
  std::string participant;
  std::string log;
  bool resume = false;
  std::uint64_t seed = 0;
  CLI::Option* seed_option = nullptr;
  std::string presenter = "device";
  std::string scene;
  std::optional<std::string> device;   // the device: a preset or a JSON spec (or old: connection)
  std::optional<std::string> connect;  // udp://HOST:PORT, or sim for a dry run
  std::optional<std::string> preset;   // old spelling of --device NAME
  std::string key_file;
  bool json = false;
};

struct SimulateOptions {
  std::string protocol;
  int participants = 0;
  std::uint64_t seed = 0;
  std::string log_dir;
  bool resume = false;
  std::string observer;
  std::string scene;
  std::string device;
  bool json = false;
  bool quiet = false;
};

struct AnalyzeOptions {
  std::vector<std::string> logs;
  bool json = false;
};

struct PredictOptions {
  std::string protocol;
  std::string observer;
  std::uint64_t seed = 1;
  int taps = 20;
  int participants = 9;
  int cohorts = 1000;
  std::string scene;
  std::string device;
  bool json = false;
  bool quiet = false;
};

std::string StatusName(st::SessionStatus status) {
  switch (status) {
    case st::SessionStatus::kComplete:
      return "complete";
    case st::SessionStatus::kAlreadyComplete:
      return "already_complete";
    case st::SessionStatus::kStopped:
      return "stopped";
  }
  return "unknown";
}

st::ObserverParams LoadObserver(const std::string& path) {
  return path.empty() ? st::ObserverParams{} : st::LoadObserverParams(path);
}

// simulated taps on `scene` with the `device` preset (empty: the defaults)
std::unique_ptr<st::StimulusSource> TapSource(const std::string& scene, const std::string& device) {
  st::TapSourceOptions options;
  options.scene = scene;
  options.device = device;
  return st::MakeTapStimulusSource(options);
}

// the text presenter renders nothing: a device flag given with it would be silently unused
void RefuseDeviceFlagsForText(const RunOptions& o) {
  const std::pair<const char*, bool> flags[] = {{"--scene", !o.scene.empty()},
                                                {"--device", o.device.has_value()},
                                                {"--connect", o.connect.has_value()},
                                                {"--preset", o.preset.has_value()},
                                                {"--key", !o.key_file.empty()}};
  for (const auto& [flag, given] : flags) {
    if (given) {
      throw Error(std::string(flag) +
                  " has no effect with --presenter text (a dry run that renders nothing); "
                  "remove it, or use --presenter device");
    }
  }
}

void RunStudy(const RunOptions& o) {
  if (o.presenter == "text") RefuseDeviceFlagsForText(o);
  const st::Protocol protocol = st::LoadProtocol(o.protocol);
  // with --json, stdout carries only the final JSON object
  std::ostream& screen = o.json ? std::cerr : std::cout;
  std::unique_ptr<st::WallPresenter> presenter;
  if (o.presenter == "text") {
    presenter = std::make_unique<st::TextPresenter>(screen);
    screen << "Dry run with the text presenter: it names the rendered wall, so do not use it with "
              "a participant.\n";
  } else {
    const DeviceChoice choice = ResolveDevice(o.device, o.connect, o.preset);
    presenter = st::MakeDeviceWallPresenter(
        st::PresenterOptions{o.scene, choice.connect, choice.spec_text, o.key_file});
  }
  st::SessionConfig config;
  config.participant = o.participant;
  if (o.seed_option != nullptr && o.seed_option->count() > 0) config.seed = o.seed;
  config.resume = o.resume;
  config.software_version = kSoftwareVersion;
  config.mode = "person";
  config.start_extra["presenter"] = presenter->Describe();
  config.start_extra["dry_run"] = presenter->dry_run();
  st::TerminalResponder responder(std::cin, screen);
  const st::SessionOutcome outcome =
      st::RunLoggedSession(protocol, config, o.log, *presenter, responder);
  if (o.json) {
    json j = {{"status", StatusName(outcome.status)},
              {"participant", o.participant},
              {"seed", outcome.seed},
              {"resumed", outcome.resumed},
              {"answers_before", outcome.answers_before},
              {"answers_recorded", outcome.answers_recorded},
              {"answers_total", outcome.answers_total},
              {"next_step", outcome.next_step},
              {"torn_tail_bytes_dropped", outcome.torn_tail_bytes}};
    std::cout << j.dump() << "\n";
  } else if (outcome.torn_tail_bytes > 0) {
    std::cout << "(a torn last line of " << outcome.torn_tail_bytes
              << " bytes from an interrupted write was removed from the log)\n";
  }
}

void Simulate(const SimulateOptions& o) {
  const st::Protocol protocol = st::LoadProtocol(o.protocol);
  st::CohortConfig config;
  config.participants = o.participants;
  config.seed = o.seed;
  config.resume = o.resume;
  config.observer = LoadObserver(o.observer);
  config.software_version = kSoftwareVersion;
  if (!o.log_dir.empty()) {
    io::CheckOutputDir(o.log_dir, "log directory (--log-dir)");
    std::error_code error;
    std::filesystem::create_directories(o.log_dir, error);
    if (error)
      throw Error(o.log_dir + ": cannot create the log directory (" + error.message() + ")");
    config.log_dir = o.log_dir;
  }
  const std::unique_ptr<st::StimulusSource> source = TapSource(o.scene, o.device);
  const std::unique_ptr<Progress> progress = StartProgress("study simulate", o.quiet);
  config.progress = progress.get();
  const std::vector<st::ParticipantRun> runs = st::SimulateCohort(protocol, *source, config);
  progress->Finish();
  const bool stopped = static_cast<int>(runs.size()) < o.participants ||
                       (!runs.empty() && runs.back().outcome.status == st::SessionStatus::kStopped);
  if (stopped) {
    int complete = 0;
    for (const auto& run : runs) complete += run.outcome.status != st::SessionStatus::kStopped;
    progress->ThrowIfStopped(
        "participant " + std::to_string(runs.size()) + " of " + std::to_string(o.participants),
        config.log_dir.empty()
            ? "the answers were kept in memory only (no --log-dir): nothing to resume"
            : std::to_string(complete) + " participant(s) complete; every answer given is in " +
                  config.log_dir + ": run again with --resume to continue");
  }
  std::vector<st::LogInput> logs;
  for (const auto& run : runs) {
    logs.push_back({run.log_path.empty() ? run.id : run.log_path, run.records});
  }
  const st::StudyReport report = st::AnalyzeLogs(logs);
  if (o.json) {
    json j = st::ReportToJson(report);
    j["simulation"] = {{"participants", o.participants},
                       {"seed", o.seed},
                       {"observer", config.observer.ToJson()},
                       {"stimulus_source", source->Describe()},
                       {"logs_written", !config.log_dir.empty()}};
    std::cout << j.dump() << "\n";
  } else {
    std::cout << "Simulated " << o.participants << " participant(s) with seed " << o.seed << " ("
              << source->Describe() << ")\n"
              << st::ReportToText(report);
  }
}

void Analyze(const AnalyzeOptions& o) {
  std::vector<st::LogInput> logs;
  for (const std::string& path : o.logs) {
    st::LogContents contents = st::ReadLog(path);  // read-only: a torn tail is ignored
    if (contents.records.empty()) throw Error(path + ": no such log or empty log");
    logs.push_back({path, std::move(contents.records)});
  }
  const st::StudyReport report = st::AnalyzeLogs(logs);
  if (o.json) {
    std::cout << st::ReportToJson(report).dump() << "\n";
  } else {
    std::cout << st::ReportToText(report);
  }
}

json ShareJson(const st::CohortShare& share) {
  return {{"expected", share.expected}, {"interval_90", {share.low, share.high}}};
}

void Predict(const PredictOptions& o) {
  const st::Protocol protocol = st::LoadProtocol(o.protocol);
  const st::ObserverParams observer = LoadObserver(o.observer);
  const std::unique_ptr<st::StimulusSource> source = TapSource(o.scene, o.device);
  st::PredictionConfig config;
  config.seed = o.seed;
  config.sample_taps = o.taps;
  config.participants = o.participants;
  config.cohorts = o.cohorts;
  const std::unique_ptr<Progress> progress = StartProgress("study predict", o.quiet);
  config.progress = progress.get();
  const auto predictions = st::PredictProtocol(protocol, *source, observer, config);
  progress->Finish();
  if (o.json) {
    json tests = json::array();
    for (const auto& p : predictions) {
      tests.push_back({{"name", p.name},
                       {"distance_jnd", p.distance_jnd},
                       {"predicted_percent_correct",
                        std::isnan(p.percent_correct) ? json(nullptr) : json(p.percent_correct)},
                       {"chance_percent", p.chance_percent},
                       {"mean_percepts_jnd", p.mean_percepts},
                       {"label_interference", p.label_interference},
                       {"cohort_percent_correct", ShareJson(p.cohort_percent_correct)},
                       {"share_at_least_90", ShareJson(p.at_least_90)},
                       {"share_at_most_50", ShareJson(p.at_most_50)},
                       {"cohorts_below_previous_test", std::isnan(p.cohorts_below_previous)
                                                           ? json(nullptr)
                                                           : json(p.cohorts_below_previous)}});
    }
    std::cout << json{{"tests", tests},
                      {"observer", observer.ToJson()},
                      {"stimulus_source", source->Describe()},
                      {"sample_taps", o.taps},
                      {"participants", o.participants},
                      {"cohorts", o.cohorts},
                      {"seed", o.seed}}
                     .dump()
              << "\n";
  } else {
    std::cout << "Observer model, " << o.taps << " sampled taps per wall (" << source->Describe()
              << "); " << o.cohorts << " simulated cohorts of " << o.participants
              << " (intervals: 5th-95th percentile over cohorts)\n";
    auto percent = [](double share) { return text::Percent(share); };
    // percent-correct values are percentages already: to 0.1
    auto pc = [](double percent_value) { return text::Fixed(percent_value, 1); };
    auto jnd = [](double d) { return text::Significant(d, 3); };
    for (const auto& p : predictions) {
      if (p.mean_percepts.size() == 2) {
        std::cout << "  " << p.name << ": walls " << jnd(p.distance_jnd)
                  << " JND apart; nominal observer " << pc(p.percent_correct) << "% correct\n";
      } else {
        std::cout << "  " << p.name << ": " << p.mean_percepts.size() << " walls, the nearest two "
                  << jnd(p.distance_jnd) << " JND apart; chance " << pc(p.chance_percent)
                  << "% (no nominal closed form for more than two walls: see the cohorts)\n";
      }
      if (o.cohorts == 0) continue;
      const st::CohortShare& m = p.cohort_percent_correct;
      std::cout << "    cohort mean " << pc(m.expected) << "% correct [" << pc(m.low) << ", "
                << pc(m.high) << "]; participants at >= 90%: " << percent(p.at_least_90.expected)
                << " [" << percent(p.at_least_90.low) << ", " << percent(p.at_least_90.high)
                << "]; at <= 50%: " << percent(p.at_most_50.expected) << " ["
                << percent(p.at_most_50.low) << ", " << percent(p.at_most_50.high) << "]\n";
      if (!std::isnan(p.cohorts_below_previous)) {
        std::cout << "    cohorts whose mean is below the previous test's: "
                  << percent(p.cohorts_below_previous) << "\n";
      }
    }
  }
}

void AddStudyCommand(CLI::App& root) {
  CLI::App* study = root.add_subcommand(
      "study", "Perception studies: run sessions, simulate cohorts, analyse logs");
  study->require_subcommand(1);

  auto run_options = std::make_shared<RunOptions>();
  CLI::App* run = study->add_subcommand(
      "run",
      "Run (or resume) one participant's session at the terminal; answers are read one "
      "per line from stdin, end of input stops cleanly");
  run->add_option("--protocol", run_options->protocol, "Protocol JSON file")->required();
  run->add_option("--participant", run_options->participant, "Participant ID ([A-Za-z0-9._-])")
      ->required();
  run->add_option("--log", run_options->log, "Session log (JSON lines), created if missing")
      ->required();
  run->add_flag("--resume", run_options->resume, "Continue the session recorded in --log");
  run_options->seed_option =
      run->add_option("--seed", run_options->seed,
                      "Session seed, 0 to 2^64 - 1 (default: the protocol's, else random; "
                      "recorded in the log)")
          ->transform(SeedRange());
  run->add_option("--presenter", run_options->presenter,
                  "device: render on the device; text: dry run that prints the wall")
      ->check(CLI::IsMember({"device", "text"}))
      ->capture_default_str();
  run->add_option("--scene", run_options->scene, "Scene for the device presenter");
  run->add_option("--device", run_options->device,
                  "the device: a preset or a JSON device spec (" + device::DeviceSpecHelp() +
                      ", default touch); its limits apply (force, stiffness, damping)");
  run->add_option("--connect", run_options->connect,
                  "device presenter: udp://HOST:PORT (a device through the bridge), or sim (a "
                  "dry run on the in-process simulated device, logged as one); required (the "
                  "old spelling --device udp://...|sim is read the same)");
  run->add_option("--preset", run_options->preset, "old spelling of --device NAME");
  run->add_option("--key", run_options->key_file,
                  "bridge key file (rigidtouch keygen); default: the per-user key");
  run->add_flag("--json", run_options->json,
                "Prompts on stderr, one JSON summary object on stdout");
  run->callback([run_options] { RunStudy(*run_options); });

  auto sim_options = std::make_shared<SimulateOptions>();
  CLI::App* simulate = study->add_subcommand(
      "simulate", "Run a virtual cohort of simulated participants and analyse it");
  simulate->add_option("--protocol", sim_options->protocol, "Protocol JSON file")->required();
  simulate->add_option("--participants", sim_options->participants, "Cohort size")
      ->required()
      ->check(CLI::Range(1, 1000000));
  simulate->add_option("--seed", sim_options->seed, "Cohort seed, 0 to 2^64 - 1")
      ->required()
      ->transform(SeedRange());
  simulate->add_option("--log-dir", sim_options->log_dir,
                       "Write one log per participant here (created if missing)");
  simulate->add_flag("--resume", sim_options->resume, "Continue the logs in --log-dir");
  simulate->add_option("--observer", sim_options->observer,
                       "JSON file overriding observer parameters (docs/study.md)");
  simulate->add_option("--scene", sim_options->scene, "Scene for the tap experiment");
  simulate->add_option("--device", sim_options->device,
                       "Device for the tap experiment: " + device::DeviceSpecHelp());
  simulate->add_flag("--json", sim_options->json, "Print one JSON object");
  AddQuietFlag(*simulate, sim_options->quiet);
  simulate->callback([sim_options] { Simulate(*sim_options); });

  auto analyze_options = std::make_shared<AnalyzeOptions>();
  CLI::App* analyze = study->add_subcommand("analyze", "Analyse session logs of one protocol");
  analyze->add_option("logs", analyze_options->logs, "Session logs")->required();
  analyze->add_flag("--json", analyze_options->json, "Print one JSON object");
  analyze->callback([analyze_options] { Analyze(*analyze_options); });

  auto predict_options = std::make_shared<PredictOptions>();
  CLI::App* predict = study->add_subcommand(
      "predict",
      "Predicted percent correct for each test: the nominal observer, and simulated cohorts "
      "(shares of participants at >= 90% and <= 50%)");
  predict->add_option("--protocol", predict_options->protocol, "Protocol JSON file")->required();
  predict->add_option("--observer", predict_options->observer, "Observer parameter JSON file");
  predict->add_option("--seed", predict_options->seed, "Seed of the sampled taps, 0 to 2^64 - 1")
      ->capture_default_str()
      ->transform(SeedRange());
  predict->add_option("--taps", predict_options->taps, "Sampled taps per wall")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  predict
      ->add_option("--participants", predict_options->participants,
                   "Cohort size the intervals refer to (the method's study had 9)")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  predict
      ->add_option("--cohorts", predict_options->cohorts,
                   "Simulated cohorts for the shares and intervals (0: nominal observer only)")
      ->check(CLI::Range(0, 100000))
      ->capture_default_str();
  predict->add_option("--scene", predict_options->scene, "Scene for the tap experiment");
  predict->add_option("--device", predict_options->device,
                      "Device for the tap experiment: " + device::DeviceSpecHelp());
  predict->add_flag("--json", predict_options->json, "Print one JSON object");
  AddQuietFlag(*predict, predict_options->quiet);
  predict->callback([predict_options] { Predict(*predict_options); });
}

const CommandRegistrar study_registrar("study", &AddStudyCommand);

}  // namespace

}  // namespace rigidtouch::cli
