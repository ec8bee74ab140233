// One participant's session: familiarization and series steps from the plan, each rendered by a
// WallPresenter, answers from a Responder (a person at a terminal or a simulated observer), every
// event recorded in the log. A session resumes from its log at the first unfinished step.
#pragma once

#include <cstdint>
#include <iosfwd>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "study/log.h"
#include "study/plan.h"
#include "study/protocol.h"
#include "study/stimulus.h"

namespace rigidtouch::study {

/// Who answers the series of a session.
class Responder {
 public:
  virtual ~Responder() = default;
  /// Shows text meant for the participant (instructions, what to do next).
  virtual void Show(std::string_view text) = 0;
  /// Asks which of the test's k conditions the series `step` rendered. Returns 0 to k - 1, or
  /// nothing to stop the session cleanly (it can be resumed later).
  virtual std::optional<int> Ask(const Protocol& protocol, const Step& step) = 0;
  /// Why the last Ask returned nothing (recorded in the log).
  virtual std::string StopReason() const { return "stopped"; }
};

/// A person at a terminal: prompts on `out`, reads one answer per line from `in`. An answer is a
/// test's key or a condition label (without case, surrounding spaces ignored); anything else asks
/// again. End of input or "quit" stops the session.
class TerminalResponder : public Responder {
 public:
  /// Both streams must outlive the responder.
  TerminalResponder(std::istream& in, std::ostream& out) : in_(in), out_(out) {}
  void Show(std::string_view text) override;
  std::optional<int> Ask(const Protocol& protocol, const Step& step) override;
  std::string StopReason() const override { return stop_reason_; }

 private:
  std::istream& in_;
  std::ostream& out_;
  std::string stop_reason_ = "stopped";
};

/// Interprets one typed answer for `test`: the index (0 to k - 1) of the condition whose key or
/// label it is, or nothing if it is neither.
std::optional<int> ParseAnswer(const Protocol& protocol, const StudyTest& test,
                               std::string_view text);

/// Who runs a session and how.
struct SessionConfig {
  std::string participant;            ///< participant ID, [A-Za-z0-9._-], 1 to 64 characters
  std::optional<std::uint64_t> seed;  ///< session seed; default: protocol's, else random
  bool resume = false;                ///< continue an existing log instead of refusing it
  std::string software_version;       ///< recorded in session_start and resume records
  std::string mode = "person";        ///< "person" or "simulated"; a log is resumed in its mode
  nlohmann::json start_extra = nlohmann::json::object();  ///< merged into session_start
  /// Fields of start_extra that must be equal in the log to resume it (e.g. the observer model
  /// of a simulated participant, whose answers depend on it).
  std::vector<std::string> resume_checked_fields;
};

/// How a session run ended.
enum class SessionStatus {
  kComplete,         ///< every step is done (in this run)
  kAlreadyComplete,  ///< the log was already complete; nothing was rendered or written
  kStopped,          ///< the responder stopped; the log can be resumed
};

/// Summary of one run of a session.
struct SessionOutcome {
  SessionStatus status = SessionStatus::kComplete;
  std::uint64_t seed = 0;           ///< the session seed
  bool resumed = false;             ///< the log already had records
  int answers_before = 0;           ///< answers in the log before this run
  int answers_recorded = 0;         ///< answers recorded by this run
  int answers_total = 0;            ///< answers the whole session asks for
  int next_step = 0;                ///< first step not done when the run ended
  std::size_t torn_tail_bytes = 0;  ///< bytes of a torn last line removed before resuming
};

/// Where an existing session stands, from its records.
struct SessionState {
  std::uint64_t seed = 0;
  std::vector<Step> plan;
  int next_step = 0;   ///< steps [0, next_step) are done
  int answers = 0;     ///< answers recorded
  bool ended = false;  ///< a session_end record exists
};

/// Checks that `records` are a valid log (ValidateLog, the check `study analyze` makes too) and
/// belong to this protocol, participant and mode (and seed, if the config gives one). `source`
/// names the log in errors. Throws rigidtouch::Error with the reason otherwise.
SessionState InspectSession(const Protocol& protocol, const SessionConfig& config,
                            const std::vector<nlohmann::json>& records, std::string_view source);

/// Runs or resumes a session. `existing` are the records already in the log (empty for a new
/// session); new records go to `sink`. `torn_tail_bytes` (the size of a torn last line dropped
/// before resuming) is recorded in the resume record. Throws rigidtouch::Error if the log belongs
/// to another session, or if it exists and `config.resume` is false.
SessionOutcome RunSession(const Protocol& protocol, const SessionConfig& config,
                          const std::vector<nlohmann::json>& existing, std::string_view source,
                          RecordSink& sink, WallPresenter& presenter, Responder& responder,
                          std::size_t torn_tail_bytes = 0);

/// Runs or resumes a session on a log file: opens and locks it, checks it, drops a torn last line
/// (only after every check passed), then runs. A refused log is left untouched.
SessionOutcome RunLoggedSession(const Protocol& protocol, const SessionConfig& config,
                                const std::string& log_path, WallPresenter& presenter,
                                Responder& responder);

/// Throws rigidtouch::Error unless `id` is a valid participant ID.
void CheckParticipantId(std::string_view id);

/// Current UTC time as ISO 8601 with milliseconds, e.g. "2024-05-01T12:00:00.000Z".
std::string UtcNow();

}  // namespace rigidtouch::study
