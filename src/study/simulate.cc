#include "study/simulate.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <string_view>

#include "rigidtouch/types.h"
#include "study/log.h"
#include "study/plan.h"
#include "study/random.h"

namespace rigidtouch::study {

namespace {
constexpr std::uint64_t kParticipantStream = 31;
constexpr std::uint64_t kPredictionStream = 32;
constexpr std::uint64_t kCohortStream = 33;
}  // namespace

std::string SimulatedParticipantId(int index, int participants) {
  std::size_t digits = 3;
  for (int n = participants; n >= 1000; n /= 10) ++digits;
  std::string number = std::to_string(index + 1);
  if (number.size() < digits) number.insert(0, digits - number.size(), '0');
  return "sim-" + number;
}

std::uint64_t SimulatedParticipantSeed(std::uint64_t cohort_seed, int index) {
  return DeriveSeed(cohort_seed, {kParticipantStream, static_cast<std::uint64_t>(index)});
}

SessionConfig SimulatedSessionConfig(const std::string& id, std::uint64_t seed,
                                     std::uint64_t cohort_seed, int index,
                                     const ObserverParams& observer, const StimulusSource& source,
                                     const std::string& software_version, bool resume) {
  SessionConfig config;
  config.participant = id;
  config.seed = seed;
  config.resume = resume;
  config.software_version = software_version;
  config.mode = "simulated";
  config.start_extra["observer"] = observer.ToJson();
  config.start_extra["stimulus_source"] = source.Describe();
  config.start_extra["cohort_seed"] = cohort_seed;
  config.start_extra["participant_index"] = index;
  config.resume_checked_fields = {"observer", "stimulus_source", "cohort_seed",
                                  "participant_index"};
  return config;
}

namespace {

// a simulated participant seen by the cohort's progress: each answer reports how far the cohort
// is, and a stop request ends the session before its next answer (the log stays resumable)
class WatchedParticipant final : public WallPresenter, public Responder {
 public:
  WatchedParticipant(SimulatedParticipant& participant, Progress* progress, int index,
                     int participants, int steps)
      : participant_(participant),
        progress_(progress),
        index_(index),
        participants_(participants),
        steps_(steps) {}
  void Present(const Condition& condition, int taps) override {
    participant_.Present(condition, taps);
  }
  std::string Describe() const override { return participant_.Describe(); }
  bool dry_run() const override { return participant_.dry_run(); }
  void Show(std::string_view text) override { participant_.Show(text); }
  std::optional<int> Ask(const Protocol& protocol, const Step& step) override {
    if (progress_ == nullptr) return participant_.Ask(protocol, step);
    if (progress_->StopRequested()) {
      stopped_ = true;
      return std::nullopt;
    }
    if (progress_->Due()) {
      const double within = static_cast<double>(step.index + 1) / std::max(1, steps_);
      progress_->Report(
          (index_ + within) / participants_,
          "participant " + std::to_string(index_ + 1) + " of " + std::to_string(participants_));
    }
    return participant_.Ask(protocol, step);
  }
  std::string StopReason() const override {
    return stopped_ ? "interrupted by a signal" : participant_.StopReason();
  }

 private:
  SimulatedParticipant& participant_;
  Progress* progress_;
  int index_, participants_, steps_;
  bool stopped_ = false;
};

}  // namespace

std::vector<ParticipantRun> SimulateCohort(const Protocol& protocol, StimulusSource& source,
                                           const CohortConfig& config) {
  if (config.participants < 1) {
    throw Error("participants: " + std::to_string(config.participants) + "; valid: >= 1");
  }
  std::vector<ParticipantRun> runs;
  runs.reserve(config.participants);
  // every participant's plan has the same steps, in another order
  const int steps = static_cast<int>(MakePlan(protocol, config.seed).size());
  for (int i = 0; i < config.participants; ++i) {
    if (config.progress != nullptr && config.progress->StopRequested()) break;
    ParticipantRun run;
    run.id = SimulatedParticipantId(i, config.participants);
    run.seed = SimulatedParticipantSeed(config.seed, i);
    const SessionConfig session =
        SimulatedSessionConfig(run.id, run.seed, config.seed, i, config.observer, source,
                               config.software_version, config.resume);
    SimulatedParticipant participant(protocol, config.observer, source, run.seed);
    WatchedParticipant watched(participant, config.progress, i, config.participants, steps);
    if (config.log_dir.empty()) {
      MemorySink sink;
      run.outcome = RunSession(protocol, session, {}, run.id, sink, watched, watched);
      run.records = std::move(sink.records);
    } else {
      run.log_path = config.log_dir + "/" + run.id + ".jsonl";
      run.outcome = RunLoggedSession(protocol, session, run.log_path, watched, watched);
      run.records = ReadLog(run.log_path).records;
    }
    const bool stopped = run.outcome.status == SessionStatus::kStopped;
    runs.push_back(std::move(run));
    if (stopped) break;
  }
  return runs;
}

namespace {

// Replays taps rendered once per condition: tap `seed` draws one of them uniformly. Lets the
// prediction run thousands of simulated participants on the engine's percepts without rendering
// every tap again.
class SampledTapSource final : public StimulusSource {
 public:
  SampledTapSource(StimulusSource& inner, std::uint64_t seed, int taps, Progress* progress,
                   int pools_expected)
      : inner_(inner),
        seed_(seed),
        taps_(taps),
        progress_(progress),
        pools_expected_(std::max(1, pools_expected)) {}

  // the taps of `condition` (rendered on first use): seeds depend on its configuration only
  const std::vector<TapPercept>& TapsOf(const Condition& condition) {
    const std::uint64_t config_hash = Fnv1a64(condition.ToJson().dump());
    auto found = pools_.find(config_hash);
    if (found != pools_.end()) return found->second;
    const std::uint64_t stream = DeriveSeed(seed_, {kPredictionStream, config_hash});
    std::vector<TapPercept> taps;
    for (int j = 0; j < taps_; ++j) {
      if (progress_ != nullptr) {
        const std::string where =
            "wall " + std::to_string(pools_.size() + 1) + " of " + std::to_string(pools_expected_);
        progress_->ThrowIfStopped(where, "nothing was written");
        if (progress_->Due()) {
          progress_->Report((pools_.size() + static_cast<double>(j) / taps_) / pools_expected_,
                            where);
        }
      }
      taps.push_back(
          inner_.RenderTap(condition, DeriveSeed(stream, {static_cast<std::uint64_t>(j)})));
    }
    return pools_.emplace(config_hash, std::move(taps)).first->second;
  }

  TapPercept RenderTap(const Condition& condition, std::uint64_t tap_seed) override {
    const std::vector<TapPercept>& taps = TapsOf(condition);
    Rng rng(tap_seed);
    return taps[rng.Below(taps.size())];
  }

  std::string Describe() const override {
    return std::to_string(taps_) + " sampled taps per wall of " + inner_.Describe();
  }

 private:
  StimulusSource& inner_;
  std::uint64_t seed_;
  int taps_;
  Progress* progress_;
  int pools_expected_;
  std::map<std::uint64_t, std::vector<TapPercept>> pools_;
};

// p-quantile of sorted values (nearest rank)
double Quantile(const std::vector<double>& sorted, double p) {
  const auto n = static_cast<double>(sorted.size());
  const auto k = static_cast<std::size_t>(std::clamp(std::ceil(p * n) - 1.0, 0.0, n - 1.0));
  return sorted[k];
}

CohortShare Summarise(std::vector<double> per_cohort, double expected) {
  std::sort(per_cohort.begin(), per_cohort.end());
  return {expected, Quantile(per_cohort, 0.05), Quantile(per_cohort, 0.95)};
}

}  // namespace

namespace {

// the nominal observer's prediction of each test at the walls' mean percepts
std::vector<TestPrediction> NominalPredictions(const Protocol& protocol, SampledTapSource& sampled,
                                               const ObserverParams& observer) {
  std::vector<TestPrediction> predictions;
  for (std::size_t index = 0; index < protocol.tests.size(); ++index) {
    const StudyTest& test = protocol.tests[index];
    const std::size_t k = test.conditions.size();
    std::vector<PerceptVector> means(k, PerceptVector{});
    for (std::size_t c = 0; c < k; ++c) {
      // equal configurations get the same taps, so two labels for one wall are predicted at
      // exactly chance
      const std::vector<TapPercept>& taps = sampled.TapsOf(protocol.conditions[test.conditions[c]]);
      for (const TapPercept& tap : taps) {
        const PerceptVector v = ToPerceptVector(observer, tap);
        for (int i = 0; i < kPerceptDimensions; ++i) means[c][i] += v[i] / taps.size();
      }
    }
    // label interference from the walls of the earlier tests (in the protocol's order) that are
    // not in this one
    double interference = 0.0;
    for (std::size_t e = 0; e < index; ++e) {
      const std::vector<int>& earlier = protocol.tests[e].conditions;
      for (std::size_t ec = 0; ec < earlier.size(); ++ec) {
        if (std::find(test.conditions.begin(), test.conditions.end(), earlier[ec]) !=
            test.conditions.end()) {
          continue;
        }
        for (std::size_t c = 0; c < k; ++c) {
          interference += LabelSimilarity(
              observer, PerceptDistance(means[c], predictions[e].mean_percepts[ec]));
        }
      }
    }
    TestPrediction p;
    p.name = test.name;
    p.distance_jnd = std::numeric_limits<double>::infinity();
    for (std::size_t a = 0; a < k; ++a) {
      for (std::size_t b = a + 1; b < k; ++b) {
        p.distance_jnd = std::min(p.distance_jnd, PerceptDistance(means[a], means[b]));
      }
    }
    p.label_interference = interference;
    p.chance_percent = 100.0 / static_cast<double>(k);
    p.percent_correct =
        k == 2 ? PredictPercentCorrect(observer, test, means[0], means[1], interference)
               : std::nan("");
    p.mean_percepts = means;
    predictions.push_back(p);
  }
  return predictions;
}

// cohorts of simulated participants answering every series of the plan their seed gives
void CohortPredictions(const Protocol& protocol, SampledTapSource& sampled,
                       const ObserverParams& observer, const PredictionConfig& config,
                       std::vector<TestPrediction>& predictions) {
  const std::size_t tests = protocol.tests.size();
  std::vector<std::vector<double>> pc(tests), at_90(tests), at_50(tests);
  std::vector<double> sum_pc(tests, 0.0), n_90(tests, 0.0), n_50(tests, 0.0);
  for (int k = 0; k < config.cohorts; ++k) {
    if (config.progress != nullptr) {
      const std::string where =
          "cohort " + std::to_string(k + 1) + " of " + std::to_string(config.cohorts);
      config.progress->ThrowIfStopped(where, "nothing was written");
      if (config.progress->Due()) {
        config.progress->Report(static_cast<double>(k) / config.cohorts, where);
      }
    }
    std::vector<double> cohort_pc(tests, 0.0), cohort_90(tests, 0.0), cohort_50(tests, 0.0);
    for (int i = 0; i < config.participants; ++i) {
      const std::uint64_t seed =
          DeriveSeed(config.seed,
                     {kCohortStream, static_cast<std::uint64_t>(k), static_cast<std::uint64_t>(i)});
      SimulatedParticipant participant(protocol, observer, sampled, seed);
      std::vector<int> correct(tests, 0), answered(tests, 0);
      for (const Step& step : MakePlan(protocol, seed)) {
        if (step.kind != StepKind::kSeries) continue;
        correct[step.test] += participant.Decide(step) == step.condition ? 1 : 0;
        ++answered[step.test];
      }
      for (std::size_t t = 0; t < tests; ++t) {
        const double percent = 100.0 * correct[t] / answered[t];
        // sums first, divided once: 9 x (1 / 9) is not exactly 1
        cohort_pc[t] += percent;
        cohort_90[t] += percent >= 90.0 ? 1.0 : 0.0;
        cohort_50[t] += percent <= 50.0 ? 1.0 : 0.0;
      }
    }
    for (std::size_t t = 0; t < tests; ++t) {
      cohort_pc[t] /= config.participants;
      cohort_90[t] /= config.participants;
      cohort_50[t] /= config.participants;
      pc[t].push_back(cohort_pc[t]);
      at_90[t].push_back(cohort_90[t]);
      at_50[t].push_back(cohort_50[t]);
      sum_pc[t] += cohort_pc[t] / config.cohorts;
      n_90[t] += cohort_90[t] / config.cohorts;
      n_50[t] += cohort_50[t] / config.cohorts;
    }
  }
  for (std::size_t t = 0; t < tests; ++t) {
    double below = 0.0;
    for (int k = 0; k < config.cohorts; ++k) {
      if (t > 0 && pc[t][k] < pc[t - 1][k]) below += 1.0 / config.cohorts;
    }
    predictions[t].cohorts_below_previous = t > 0 ? below : std::nan("");
    predictions[t].cohort_percent_correct = Summarise(pc[t], sum_pc[t]);
    predictions[t].at_least_90 = Summarise(at_90[t], n_90[t]);
    predictions[t].at_most_50 = Summarise(at_50[t], n_50[t]);
  }
}

}  // namespace

std::vector<TestPrediction> PredictProtocol(const Protocol& protocol, StimulusSource& source,
                                            const ObserverParams& observer,
                                            const PredictionConfig& config) {
  if (config.sample_taps < 1) {
    throw Error("sample taps: " + std::to_string(config.sample_taps) + "; valid: >= 1");
  }
  if (config.participants < 1) {
    throw Error("participants: " + std::to_string(config.participants) + "; valid: >= 1");
  }
  if (config.cohorts < 0) {
    throw Error("cohorts: " + std::to_string(config.cohorts) + "; valid: >= 0");
  }
  // the distinct walls whose taps are rendered (equal configurations share them)
  std::set<std::uint64_t> walls;
  for (const StudyTest& test : protocol.tests) {
    for (const int c : test.conditions)
      walls.insert(Fnv1a64(protocol.conditions[c].ToJson().dump()));
  }
  if (config.progress != nullptr) config.progress->Restart("study predict: rendering taps");
  SampledTapSource sampled(source, config.seed, config.sample_taps, config.progress,
                           static_cast<int>(walls.size()));
  std::vector<TestPrediction> predictions = NominalPredictions(protocol, sampled, observer);
  if (config.progress != nullptr) config.progress->Restart("study predict: simulated cohorts");
  if (config.cohorts > 0) CohortPredictions(protocol, sampled, observer, config, predictions);
  return predictions;
}

std::vector<TestPrediction> PredictProtocol(const Protocol& protocol, StimulusSource& source,
                                            const ObserverParams& observer, std::uint64_t seed,
                                            int sample_taps) {
  PredictionConfig config;
  config.seed = seed;
  config.sample_taps = sample_taps;
  config.cohorts = 0;
  return PredictProtocol(protocol, source, observer, config);
}

}  // namespace rigidtouch::study
