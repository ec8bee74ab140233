// Virtual cohorts for piloting a protocol: N simulated participants, each a session of the same
// kind and log format as a person's (mode "simulated"), deterministic for a cohort seed and
// resumable from their logs.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "base/progress.h"
#include "study/observer.h"
#include "study/protocol.h"
#include "study/session.h"
#include "study/stimulus.h"

namespace rigidtouch::study {

/// How to run a virtual cohort.
struct CohortConfig {
  int participants = 1;          ///< cohort size, >= 1
  std::uint64_t seed = 0;        ///< cohort seed; participant i uses SimulatedParticipantSeed
  std::string log_dir;           ///< one log per participant in this existing directory; empty:
                                 ///< keep records in memory
  bool resume = false;           ///< continue existing logs (complete ones are left as they are)
  ObserverParams observer;       ///< the observer model of every participant
  std::string software_version;  ///< recorded in the logs
  /// Progress of the cohort (may be null); a stop request ends the current participant's session
  /// before its next answer (its log stays resumable) and starts no further participant.
  Progress* progress = nullptr;
};

/// One simulated participant's run.
struct ParticipantRun {
  std::string id;                       ///< e.g. "sim-007"
  std::uint64_t seed = 0;               ///< the participant's session seed
  std::string log_path;                 ///< empty when kept in memory
  SessionOutcome outcome;               ///< how the run ended
  std::vector<nlohmann::json> records;  ///< the participant's whole log after the run
};

/// ID of participant `index` (0-based) in a cohort of `participants`: "sim-" and the 1-based
/// number, zero-padded to at least 3 digits.
std::string SimulatedParticipantId(int index, int participants);

/// Session seed of participant `index` of a cohort with seed `cohort_seed`.
std::uint64_t SimulatedParticipantSeed(std::uint64_t cohort_seed, int index);

/// The session configuration of a simulated participant (mode "simulated", the observer and the
/// stimulus source recorded in session_start and checked on resume).
SessionConfig SimulatedSessionConfig(const std::string& id, std::uint64_t seed,
                                     std::uint64_t cohort_seed, int index,
                                     const ObserverParams& observer, const StimulusSource& source,
                                     const std::string& software_version, bool resume);

/// Runs the whole cohort, one participant after the other. Throws rigidtouch::Error on a refused
/// log (another protocol, participant or observer; not a study log; exists without resume). After
/// a stop request (CohortConfig::progress) it returns the runs so far, the last one stopped.
std::vector<ParticipantRun> SimulateCohort(const Protocol& protocol, StimulusSource& source,
                                           const CohortConfig& config);

/// A share of participants: its expectation and its central 90% interval over cohorts.
struct CohortShare {
  double expected = 0.0;  ///< share over all simulated participants, in [0, 1]
  double low = 0.0;       ///< 5th percentile of the share in cohorts of the given size
  double high = 0.0;      ///< 95th percentile
};

/// The observer model's prediction for one test.
struct TestPrediction {
  std::string name;  ///< test name
  /// Distance between the walls' mean percepts [JND]; k > 2 walls: the smallest pairwise one.
  double distance_jnd = 0.0;
  /// PredictPercentCorrect for the nominal observer; NaN for k > 2 walls (no closed form: the
  /// cohort part is the prediction).
  double percent_correct = 0.0;
  double chance_percent = 50.0;              ///< 100 / k
  std::vector<PerceptVector> mean_percepts;  ///< each wall's mean percept [JND], test order
  /// Label interference from the earlier tests in the protocol's order (LabelLossProbability).
  double label_interference = 0.0;
  /// Simulated cohorts (individual differences, tap variability, label memory): mean percent
  /// correct over all simulated participants, and its 90% interval over cohorts.
  CohortShare cohort_percent_correct;
  CohortShare at_least_90;  ///< share of participants at >= 90% correct
  CohortShare at_most_50;   ///< share of participants at <= 50% correct
  /// Share of simulated cohorts whose mean percent correct in this test is below their mean in
  /// the previous test of the protocol (NaN for the first test).
  double cohorts_below_previous = 0.0;
};

/// How PredictProtocol samples.
struct PredictionConfig {
  std::uint64_t seed = 1;  ///< seed of the sampled taps and of the simulated cohorts
  int sample_taps = 20;    ///< taps rendered per condition (>= 1)
  int participants = 9;    ///< cohort size the intervals refer to (>= 1)
  int cohorts = 1000;      ///< simulated cohorts (>= 1; 0 skips the cohort part)
  /// Progress of the prediction (may be null); a stop request throws Interrupted between taps or
  /// cohorts (a prediction writes nothing before it ends).
  Progress* progress = nullptr;
};

/// Predicts every test of `protocol`. Each condition's taps are rendered once, `sample_taps` taps
/// with seeds derived from the seed and the condition's configuration (so equal configurations
/// share taps); the nominal prediction is PredictPercentCorrect at their mean percepts; the
/// cohort part runs `cohorts` cohorts of `participants` SimulatedParticipants (the same observer
/// code as `study simulate`) whose taps are drawn from those rendered taps.
std::vector<TestPrediction> PredictProtocol(const Protocol& protocol, StimulusSource& source,
                                            const ObserverParams& observer,
                                            const PredictionConfig& config);

/// Nominal prediction only (no cohorts), `sample_taps` taps per condition.
std::vector<TestPrediction> PredictProtocol(const Protocol& protocol, StimulusSource& source,
                                            const ObserverParams& observer, std::uint64_t seed,
                                            int sample_taps);

}  // namespace rigidtouch::study
