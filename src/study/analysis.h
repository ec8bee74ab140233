// Analysis of study logs: per participant and test percent correct, exact binomial tests against
// chance (1/k for a test of k conditions), d' (log-linear correction; two conditions), group mean
// and SD, who reached 90%, who is far below chance (telling the walls apart but holding the labels
// swapped), and for k > 2 the confusion matrix of presented against named conditions.
#pragma once

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "study/statistics.h"

namespace rigidtouch::study {

/// The records of one log and a name for it in messages.
struct LogInput {
  std::string source;                   ///< usually the log's path
  std::vector<nlohmann::json> records;  ///< as read by ReadLog (complete lines only)
};

/// Below this one-sided binomial p toward "worse than chance" a participant is flagged as
/// discriminating the walls but swapping their labels.
inline constexpr double kLabelSwapAlpha = 0.05;
/// Percent correct counted as "reached 90% or better".
inline constexpr double kCriterionPercent = 90.0;

/// One participant in one test.
struct ParticipantResult {
  std::string id;
  std::string mode;  ///< "person" or "simulated"
  int answers = 0;   ///< series answered
  int correct = 0;   ///< series named correctly
  double percent_correct = 0.0;
  BinomialTest binomial;           ///< against chance, 1/k
  DPrime d_prime;                  ///< condition 1 as signal, log-linear correction; NaN for k > 2
  bool reached_criterion = false;  ///< percent_correct >= 90
  bool label_swap_suspected = false;  ///< binomial.p_less < 0.05
  bool complete = false;              ///< every series of the test answered
};

/// One test over all participants.
struct TestResult {
  std::string name;
  std::vector<std::string> conditions;  ///< labels of conditions 0 to k - 1
  double chance = 0.5;                  ///< 1/k: percent correct / 100 by guessing
  /// Pooled answers: confusion[presented][named], counts over all participants (k x k).
  std::vector<std::vector<int>> confusion;
  std::vector<ParticipantResult> participants;  ///< those with at least one answer, by ID
  MeanSd percent_correct;                       ///< over participants (SD with n - 1)
  double mean_d_prime = 0.0;                    ///< mean of the participants' d'
  int reached_criterion = 0;                    ///< participants at 90% or better
  int pooled_answers = 0;                       ///< all answers of all participants
  int pooled_correct = 0;
  BinomialTest pooled;  ///< exact binomial test of the pooled answers against chance (treats them
                        ///< as independent)
};

/// The whole analysis.
struct StudyReport {
  std::string protocol_name;
  std::string protocol_hash;
  int sessions = 0;
  std::vector<TestResult> tests;  ///< in protocol order
};

/// Analyses logs of one protocol. Throws rigidtouch::Error if a log is not valid (ValidateLog in
/// study/log.h, the same check `study run --resume` makes, with the same message), the logs
/// belong to different protocols or two logs have the same participant.
StudyReport AnalyzeLogs(const std::vector<LogInput>& logs);

/// The report as JSON: "protocol_name", "protocol_hash", "sessions", "methods" and "tests"
/// (each: "name", "conditions", "chance", "n_participants", "mean_percent_correct", "sd",
/// "mean_d_prime", "reached_90_count", "label_swap_suspected", "pooled", "participants" with
/// "id", "percent_correct" and the per-participant statistics; for k > 2 also "confusion", rows
/// presented and columns named). NaN is written as null.
nlohmann::json ReportToJson(const StudyReport& report);

/// The report as a human-readable table.
std::string ReportToText(const StudyReport& report);

}  // namespace rigidtouch::study
