// Virtual cohorts for piloting a protocol: N simulated participants, each a session of the same
// kind and log format as a person's (mode "simulated"), deterministic for a cohort seed and
// resumable from their logs.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

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
/// log (another protocol, participant or observer; not a study log; exists without resume).
std::vector<ParticipantRun> SimulateCohort(const Protocol& protocol, StimulusSource& source,
                                           const CohortConfig& config);

/// The observer model's analytic prediction for one test.
struct TestPrediction {
  std::string name;              ///< test name
  double distance_jnd = 0.0;     ///< distance between the walls' mean percepts [JND]
  double percent_correct = 0.0;  ///< PredictPercentCorrect for the nominal observer
};

/// Predicts every test of `protocol`: mean percepts from `sample_taps` taps per condition (seeds
/// derived from `seed` and the condition's configuration, so equal configurations share taps),
/// then PredictPercentCorrect.
std::vector<TestPrediction> PredictProtocol(const Protocol& protocol, StimulusSource& source,
                                            const ObserverParams& observer, std::uint64_t seed,
                                            int sample_taps);

}  // namespace rigidtouch::study
