#include "study/session.h"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <ctime>
#include <istream>
#include <ostream>
#include <random>
#include <set>
#include <sstream>

#include "base/text.h"
#include "rigidtouch/types.h"

namespace rigidtouch::study {

namespace {

using nlohmann::json;

using text::Lower;
using text::Quote;
using text::Trim;

const Condition& ConditionOf(const Protocol& protocol, const Step& step) {
  return protocol.conditions[protocol.tests[step.test].conditions[step.condition]];
}

// a seed nobody chose: only used when neither the command line nor the protocol gives one
std::uint64_t FreshSeed() {
  std::random_device device;
  return (static_cast<std::uint64_t>(device()) << 32) ^ device();
}

json StepRecord(const char* type, const Protocol& protocol, const Step& step) {
  const StudyTest& test = protocol.tests[step.test];
  const Condition& condition = ConditionOf(protocol, step);
  json r = json::object();
  r["type"] = type;
  r["time_utc"] = UtcNow();
  r["step"] = step.index;
  r["test"] = step.test;
  r["test_name"] = test.name;
  if (step.kind == StepKind::kSeries) r["series"] = step.series;
  r["condition"] = step.condition;
  r["label"] = condition.label;
  return r;
}

std::string TestIntro(const Protocol& protocol, const Step& step) {
  const StudyTest& test = protocol.tests[step.test];
  std::ostringstream out;
  out << "\n== Test " << step.test_position + 1 << " of " << protocol.tests.size() << ": "
      << test.name << " ==\n";
  for (std::size_t c = 0; c < test.keys.size(); ++c) {
    out << "  key " << test.keys[c] << " = " << protocol.conditions[test.conditions[c]].label
        << "\n";
  }
  out << "Familiarization: tap each wall " << test.familiarization_taps << " times. Then "
      << test.series << " series of " << test.taps_per_series
      << " taps: after each series, name the wall.\n";
  if (!test.instructions.empty()) out << test.instructions << "\n";
  return out.str();
}

}  // namespace

void TerminalResponder::Show(std::string_view text) {
  out_ << text;
  if (!text.empty() && text.back() != '\n') out_ << "\n";
  out_.flush();
}

std::optional<int> ParseAnswer(const Protocol& protocol, const StudyTest& test,
                               std::string_view text) {
  const std::string answer = text::Lower(Trim(text));
  if (answer.empty()) return std::nullopt;
  for (std::size_t c = 0; c < test.keys.size(); ++c) {
    if (answer == text::Lower(test.keys[c]) ||
        answer == text::Lower(protocol.conditions[test.conditions[c]].label)) {
      return static_cast<int>(c);
    }
  }
  return std::nullopt;
}

std::optional<int> TerminalResponder::Ask(const Protocol& protocol, const Step& step) {
  const StudyTest& test = protocol.tests[step.test];
  // "1 for wall 0 or 2 for wall 1"; with more conditions "1 for a, 2 for b or 3 for c"
  std::string choices;
  std::string keys;
  for (std::size_t c = 0; c < test.keys.size(); ++c) {
    const std::string sep = c == 0 ? "" : (c + 1 == test.keys.size() ? " or " : ", ");
    choices += sep + test.keys[c] + " for " + protocol.conditions[test.conditions[c]].label;
    keys += sep + test.keys[c];
  }
  for (;;) {
    out_ << "Which wall was it? Type " << choices << ": ";
    out_.flush();
    std::string line;
    if (!std::getline(in_, line)) {
      out_ << "\n";
      stop_reason_ = "end of input";
      return std::nullopt;
    }
    if (text::Lower(Trim(line)) == "quit") {
      stop_reason_ = "quit";
      return std::nullopt;
    }
    if (auto answer = ParseAnswer(protocol, test, line)) return answer;
    out_ << text::Quote(Trim(line)) << " is not an answer: type " << keys
         << " (or the wall's name), or quit to stop.\n";
  }
}

void CheckParticipantId(std::string_view id) {
  const bool ok = !id.empty() && id.size() <= 64 && std::all_of(id.begin(), id.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '_' || c == '-';
  });
  if (!ok) {
    throw Error("participant " + text::Quote(id) +
                " is not a valid ID; valid: 1 to 64 characters among A-Z a-z 0-9 . _ -");
  }
}

std::string UtcNow() {
  const auto now = std::chrono::system_clock::now();
  const std::time_t seconds = std::chrono::system_clock::to_time_t(now);
  const auto ms =
      std::chrono::duration_cast<std::chrono::milliseconds>(now.time_since_epoch()).count() % 1000;
  std::tm utc{};
  gmtime_r(&seconds, &utc);
  char buffer[40];
  const std::size_t n = std::strftime(buffer, sizeof buffer, "%Y-%m-%dT%H:%M:%S", &utc);
  std::snprintf(buffer + n, sizeof buffer - n, ".%03dZ", static_cast<int>(ms));
  return buffer;
}

namespace {

// the log is valid (ValidateLog, shared with analysis); then it must be this session's
SessionState InspectRecords(const Protocol& protocol, const SessionConfig& config,
                            const std::vector<nlohmann::json>& records, std::string_view source) {
  const std::string src(source);
  const ValidLog log = ValidateLog(records, source);
  const json& start = records[0];
  const std::string hash = ProtocolHash(protocol);
  if (log.protocol_hash != hash) {
    throw Error(src + ": refusing to resume: the log was written for protocol " +
                text::Quote(log.protocol.name) + " (" + log.protocol_hash + "), not for " +
                text::Quote(protocol.name) + " (" + hash + ")");
  }
  if (log.participant != config.participant) {
    throw Error(src + ": refusing to resume: the log belongs to participant " +
                text::Quote(log.participant) + ", not " + text::Quote(config.participant));
  }
  if (log.mode != config.mode) {
    throw Error(src + ": refusing to resume: the log was written by a " + log.mode +
                " session, not a " + config.mode + " one");
  }
  for (const std::string& field : config.resume_checked_fields) {
    const json expected = config.start_extra.is_object() && config.start_extra.contains(field)
                              ? config.start_extra[field]
                              : json();
    const json found = start.contains(field) ? start[field] : json();
    if (expected != found) {
      throw Error(src + ": refusing to resume: the log was written with a different " + field +
                  " (log: " + found.dump() + ", now: " + expected.dump() + ")");
    }
  }
  if (config.seed && *config.seed != log.seed) {
    throw Error(src + ": refusing to resume: the log's session seed is " +
                std::to_string(log.seed) + ", not " + std::to_string(*config.seed) +
                " (omit --seed to resume with the log's seed)");
  }
  SessionState state;
  state.seed = log.seed;
  state.plan = log.plan;
  state.next_step = log.next_step;
  state.answers = static_cast<int>(log.answers.size());
  state.ended = log.ended;
  return state;
}

}  // namespace

SessionState InspectSession(const Protocol& protocol, const SessionConfig& config,
                            const std::vector<nlohmann::json>& records, std::string_view source) {
  try {
    return InspectRecords(protocol, config, records, source);
  } catch (const json::exception& e) {
    // a field of the wrong type: the log was edited or written by something else
    throw Error(std::string(source) + ": malformed record (" + e.what() + ")");
  }
}

namespace {

// a new session: its plan and the durable start record
SessionState StartSession(const Protocol& protocol, const SessionConfig& config, RecordSink& sink,
                          Responder& responder) {
  SessionState state;
  state.seed = config.seed ? *config.seed : protocol.randomization.seed.value_or(FreshSeed());
  state.plan = MakePlan(protocol, state.seed);
  json start = config.start_extra.is_object() ? config.start_extra : json::object();
  start["type"] = "session_start";
  start["format"] = std::string(kLogFormat);
  start["format_version"] = kLogFormatVersion;
  start["time_utc"] = UtcNow();
  start["software_version"] = config.software_version;
  start["protocol_name"] = protocol.name;
  start["protocol_hash"] = ProtocolHash(protocol);
  start["protocol_hash_method"] = "FNV-1a 64 of the canonical protocol JSON";
  start["protocol"] = protocol.ToJson();
  start["participant"] = config.participant;
  start["mode"] = config.mode;
  start["seed"] = state.seed;
  start["steps"] = state.plan.size();
  sink.Append(start, /*durable=*/true);
  responder.Show("Protocol " + text::Quote(protocol.name) + ", participant " + config.participant +
                 ", " + std::to_string(protocol.tests.size()) + " test(s).");
  if (!protocol.instructions.empty()) responder.Show(protocol.instructions);
  return state;
}

// the durable resume record of a session continued at state.next_step
void WriteResume(const Protocol& protocol, const SessionConfig& config, const SessionState& state,
                 std::size_t torn_tail_bytes, RecordSink& sink, Responder& responder) {
  json resume = json::object();
  resume["type"] = "resume";
  resume["time_utc"] = UtcNow();
  resume["software_version"] = config.software_version;
  resume["next_step"] = state.next_step;
  resume["answers_so_far"] = state.answers;
  resume["torn_tail_bytes_dropped"] = torn_tail_bytes;
  sink.Append(resume, /*durable=*/true);
  responder.Show("Resuming participant " + config.participant + " at step " +
                 std::to_string(state.next_step + 1) + " of " + std::to_string(state.plan.size()) +
                 " (" + std::to_string(state.answers) + " answers recorded).");
  if (!protocol.instructions.empty()) responder.Show(protocol.instructions);
}

// one series step k: present, ask, record the answer durably. False (a stop record written) if
// the participant stopped instead of answering.
bool RunSeries(const Protocol& protocol, const Step& step, int k, bool repeated, RecordSink& sink,
               WallPresenter& presenter, Responder& responder) {
  const StudyTest& test = protocol.tests[step.test];
  const Condition& condition = ConditionOf(protocol, step);
  responder.Show("Series " + std::to_string(step.series + 1) + " of " +
                 std::to_string(test.series) + ": tap the wall " + std::to_string(step.taps) +
                 " times.");
  presenter.Present(condition, step.taps);
  json series = StepRecord("series", protocol, step);
  series["taps"] = step.taps;
  series["rendered"] = condition.ToJson();
  if (repeated) series["repeated"] = true;
  sink.Append(series, /*durable=*/false);

  const auto asked = std::chrono::steady_clock::now();
  const std::optional<int> answer = responder.Ask(protocol, step);
  const double response_time_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - asked).count();
  if (!answer) {
    json stop = json::object();
    stop["type"] = "stop";
    stop["time_utc"] = UtcNow();
    stop["reason"] = responder.StopReason();
    stop["next_step"] = k;
    sink.Append(stop, /*durable=*/true);
    return false;
  }
  json a = StepRecord("answer", protocol, step);
  a["answer"] = *answer;
  a["answer_label"] = protocol.conditions[test.conditions[*answer]].label;
  a["correct"] = *answer == step.condition;
  a["response_time_s"] = response_time_s;
  sink.Append(a, /*durable=*/true);
  return true;
}

}  // namespace

SessionOutcome RunSession(const Protocol& protocol, const SessionConfig& config,
                          const std::vector<nlohmann::json>& existing, std::string_view source,
                          RecordSink& sink, WallPresenter& presenter, Responder& responder,
                          std::size_t torn_tail_bytes) {
  CheckParticipantId(config.participant);
  SessionOutcome outcome;
  outcome.torn_tail_bytes = torn_tail_bytes;
  SessionState state;
  std::set<int> presented;  // series steps already presented (a repeat is marked as such)
  if (existing.empty()) {
    state = StartSession(protocol, config, sink, responder);
  } else {
    if (!config.resume) {
      throw Error(std::string(source) + ": the log already holds a session (" +
                  std::to_string(existing.size()) +
                  " records); pass --resume to continue it, or choose another log");
    }
    state = InspectSession(protocol, config, existing, source);
    outcome.resumed = true;
    for (const json& r : existing) {
      if (r.value("type", "") == "series") presented.insert(r.value("step", -1));
    }
  }
  outcome.seed = state.seed;
  outcome.answers_before = state.answers;
  outcome.next_step = state.next_step;
  for (const Step& s : state.plan) outcome.answers_total += s.kind == StepKind::kSeries ? 1 : 0;

  const int steps = static_cast<int>(state.plan.size());
  if (outcome.resumed) {
    if (state.next_step >= steps && state.ended) {
      outcome.status = SessionStatus::kAlreadyComplete;
      responder.Show("The session of participant " + config.participant + " is already complete.");
      return outcome;
    }
    WriteResume(protocol, config, state, torn_tail_bytes, sink, responder);
  }

  int shown_test = -1;
  for (int k = state.next_step; k < steps; ++k) {
    const Step& step = state.plan[k];
    if (step.test_position != shown_test) {
      responder.Show(TestIntro(protocol, step));
      shown_test = step.test_position;
    }
    if (step.kind == StepKind::kFamiliarization) {
      const StudyTest& test = protocol.tests[step.test];
      const Condition& condition = ConditionOf(protocol, step);
      responder.Show("Familiarization: tap " + condition.label + " (key " +
                     test.keys[step.condition] + ") " + std::to_string(step.taps) + " times.");
      presenter.Present(condition, step.taps);
      json r = StepRecord("familiarization", protocol, step);
      r["key"] = test.keys[step.condition];
      r["taps"] = step.taps;
      r["rendered"] = condition.ToJson();
      sink.Append(r, /*durable=*/false);
      continue;
    }
    if (!RunSeries(protocol, step, k, presented.count(k) > 0, sink, presenter, responder)) {
      outcome.status = SessionStatus::kStopped;
      outcome.next_step = k;
      responder.Show("Session stopped after " +
                     std::to_string(outcome.answers_before + outcome.answers_recorded) + " of " +
                     std::to_string(outcome.answers_total) +
                     " answers; it can be continued with --resume.");
      return outcome;
    }
    ++outcome.answers_recorded;
  }
  json end = json::object();
  end["type"] = "session_end";
  end["time_utc"] = UtcNow();
  end["answers"] = outcome.answers_before + outcome.answers_recorded;
  sink.Append(end, /*durable=*/true);
  outcome.status = SessionStatus::kComplete;
  outcome.next_step = steps;
  responder.Show("Session complete: " + std::to_string(outcome.answers_total) +
                 " answers recorded. Thank you.");
  return outcome;
}

SessionOutcome RunLoggedSession(const Protocol& protocol, const SessionConfig& config,
                                const std::string& log_path, WallPresenter& presenter,
                                Responder& responder) {
  CheckParticipantId(config.participant);
  auto log = LogFile::Open(log_path);
  const std::vector<json>& existing = log->contents().records;
  if (!existing.empty()) {
    if (!config.resume) {
      throw Error(log_path + ": the log already holds a session (" +
                  std::to_string(existing.size()) +
                  " records); pass --resume to continue it, or choose another log");
    }
    // every check passes before the file is changed in any way
    InspectSession(protocol, config, existing, log_path);
  }
  const std::size_t torn = log->contents().torn_tail_bytes;
  log->DropTornTail();
  return RunSession(protocol, config, existing, log_path, *log, presenter, responder, torn);
}

}  // namespace rigidtouch::study
