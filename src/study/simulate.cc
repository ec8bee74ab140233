#include "study/simulate.h"

#include "rigidtouch/types.h"
#include "study/log.h"
#include "study/random.h"

namespace rigidtouch::study {

namespace {
constexpr std::uint64_t kParticipantStream = 31;
constexpr std::uint64_t kPredictionStream = 32;
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

std::vector<ParticipantRun> SimulateCohort(const Protocol& protocol, StimulusSource& source,
                                           const CohortConfig& config) {
  if (config.participants < 1) {
    throw Error("participants: " + std::to_string(config.participants) + "; valid: >= 1");
  }
  std::vector<ParticipantRun> runs;
  runs.reserve(config.participants);
  for (int i = 0; i < config.participants; ++i) {
    ParticipantRun run;
    run.id = SimulatedParticipantId(i, config.participants);
    run.seed = SimulatedParticipantSeed(config.seed, i);
    const SessionConfig session =
        SimulatedSessionConfig(run.id, run.seed, config.seed, i, config.observer, source,
                               config.software_version, config.resume);
    SimulatedParticipant participant(protocol, config.observer, source, run.seed);
    if (config.log_dir.empty()) {
      MemorySink sink;
      run.outcome = RunSession(protocol, session, {}, run.id, sink, participant, participant);
      run.records = std::move(sink.records);
    } else {
      run.log_path = config.log_dir + "/" + run.id + ".jsonl";
      run.outcome = RunLoggedSession(protocol, session, run.log_path, participant, participant);
      run.records = ReadLog(run.log_path).records;
    }
    runs.push_back(std::move(run));
  }
  return runs;
}

std::vector<TestPrediction> PredictProtocol(const Protocol& protocol, StimulusSource& source,
                                            const ObserverParams& observer, std::uint64_t seed,
                                            int sample_taps) {
  if (sample_taps < 1) {
    throw Error("sample taps: " + std::to_string(sample_taps) + "; valid: >= 1");
  }
  std::vector<TestPrediction> predictions;
  for (const StudyTest& test : protocol.tests) {
    std::array<PerceptVector, 2> means;
    for (int c = 0; c < 2; ++c) {
      // the stream depends on the configuration only: equal configurations get the same taps,
      // so two labels for one wall are predicted at exactly chance
      const Condition& condition = protocol.conditions[test.conditions[c]];
      const std::uint64_t config_hash = Fnv1a64(condition.ToJson().dump());
      means[c] = MeanPerceptVector(observer, source, condition, sample_taps,
                                   DeriveSeed(seed, {kPredictionStream, config_hash}));
    }
    TestPrediction p;
    p.name = test.name;
    p.distance_jnd = PerceptDistance(means[0], means[1]);
    p.percent_correct = PredictPercentCorrect(observer, test, means[0], means[1]);
    predictions.push_back(p);
  }
  return predictions;
}

}  // namespace rigidtouch::study
