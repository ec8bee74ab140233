#include "study/analysis.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>
#include <sstream>

#include "rigidtouch/types.h"
#include "study/log.h"
#include "study/protocol.h"

namespace rigidtouch::study {

namespace {

using nlohmann::json;

struct Counts {
  int answers = 0;
  int correct = 0;
  int signal = 0;                       // condition 1 presented
  int noise = 0;                        // condition 0 presented
  int hits = 0;                         // condition 1 named 1
  int false_alarms = 0;                 // condition 0 named 1
  std::vector<std::vector<int>> named;  // [presented][named], k x k
};

// one participant's result in a test of k conditions
ParticipantResult ResultOf(const std::string& id, const std::string& mode, const Counts& k,
                           const StudyTest& test) {
  const std::size_t conditions = test.conditions.size();
  ParticipantResult p;
  p.id = id;
  p.mode = mode;
  p.answers = k.answers;
  p.correct = k.correct;
  p.percent_correct = 100.0 * k.correct / k.answers;
  p.binomial = ExactBinomialTest(k.correct, k.answers, 1.0 / static_cast<double>(conditions));
  // d' of a yes/no task: two conditions only (k > 2 would need an identification model)
  if (conditions == 2) {
    p.d_prime = LogLinearDPrime(k.hits, k.signal, k.false_alarms, k.noise);
  } else {
    const double nan = std::nan("");
    p.d_prime = {nan, nan, nan, nan};
  }
  p.reached_criterion = p.percent_correct >= kCriterionPercent;
  p.label_swap_suspected = p.binomial.p_less < kLabelSwapAlpha;
  p.complete = k.answers == test.series;
  return p;
}

TestResult ResultOf(const Protocol& protocol, std::size_t t,
                    const std::map<std::string, std::vector<Counts>>& counts,
                    const std::map<std::string, std::string>& modes) {
  const StudyTest& test = protocol.tests[t];
  const std::size_t k = test.conditions.size();
  TestResult result;
  result.name = test.name;
  for (int c : test.conditions) result.conditions.push_back(protocol.conditions[c].label);
  result.chance = 1.0 / static_cast<double>(k);
  result.confusion.assign(k, std::vector<int>(k, 0));
  std::vector<double> percents;
  double d_sum = 0.0;
  for (const auto& [id, per_test] : counts) {
    const Counts& n = per_test[t];
    if (n.answers == 0) continue;
    const ParticipantResult p = ResultOf(id, modes.at(id), n, test);
    for (std::size_t a = 0; a < k; ++a) {
      for (std::size_t b = 0; b < k; ++b) result.confusion[a][b] += n.named[a][b];
    }
    percents.push_back(p.percent_correct);
    d_sum += p.d_prime.d_prime;
    result.reached_criterion += p.reached_criterion ? 1 : 0;
    result.pooled_answers += n.answers;
    result.pooled_correct += n.correct;
    result.participants.push_back(p);
  }
  result.percent_correct = ComputeMeanSd(percents);
  result.mean_d_prime = percents.empty() ? std::nan("") : d_sum / percents.size();
  result.pooled = ExactBinomialTest(result.pooled_correct, result.pooled_answers, result.chance);
  return result;
}

json NumberOrNull(double v) {
  return std::isfinite(v) ? json(v) : json();
}

std::string Format(const char* format, double v) {
  if (!std::isfinite(v)) return "-";
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, format, v);
  return buffer;
}

// the pooled confusion matrix, one row per condition presented
std::string ConfusionText(const TestResult& t) {
  std::ostringstream out;
  out << "  pooled answers (row: presented, column: named)\n";
  std::size_t width = 8;
  for (const std::string& label : t.conditions) width = std::max(width, label.size() + 1);
  const int w = static_cast<int>(width);
  char cell[160];
  std::snprintf(cell, sizeof cell, "  %-*s", w, "");
  out << cell;
  for (const std::string& label : t.conditions) {
    std::snprintf(cell, sizeof cell, " %*s", w, label.c_str());
    out << cell;
  }
  out << "\n";
  for (std::size_t a = 0; a < t.conditions.size(); ++a) {
    std::snprintf(cell, sizeof cell, "  %-*s", w, t.conditions[a].c_str());
    out << cell;
    for (int n : t.confusion[a]) {
      std::snprintf(cell, sizeof cell, " %*d", w, n);
      out << cell;
    }
    out << "\n";
  }
  return out.str();
}

}  // namespace

StudyReport AnalyzeLogs(const std::vector<LogInput>& logs) {
  if (logs.empty()) throw Error("no logs to analyse");
  StudyReport report;
  Protocol protocol;
  std::set<std::string> ids;
  // participant id -> per test counts
  std::map<std::string, std::vector<Counts>> counts;
  std::map<std::string, std::string> modes;

  for (const LogInput& log : logs) {
    // the same check as `study run --resume` (ValidateLog): both accept and refuse alike
    ValidLog valid = ValidateLog(log.records, log.source);
    if (report.sessions == 0) {
      protocol = valid.protocol;
      report.protocol_name = protocol.name;
      report.protocol_hash = valid.protocol_hash;
    } else if (valid.protocol_hash != report.protocol_hash) {
      throw Error(log.source + ": protocol " + valid.protocol_hash + " differs from " +
                  report.protocol_hash + " of " + logs[0].source +
                  "; analyse logs of one protocol at a time");
    }
    const std::string& id = valid.participant;
    if (!ids.insert(id).second) {
      throw Error(log.source + ": participant \"" + id +
                  "\" appears in two logs; analyse one log per participant");
    }
    ++report.sessions;
    modes[id] = valid.mode;
    std::vector<Counts>& per_test = counts[id];
    per_test.assign(protocol.tests.size(), Counts{});
    for (std::size_t t = 0; t < protocol.tests.size(); ++t) {
      const std::size_t k = protocol.tests[t].conditions.size();
      per_test[t].named.assign(k, std::vector<int>(k, 0));
    }
    for (const LoggedAnswer& answer : valid.answers) {
      Counts& k = per_test[answer.test];
      const int c = answer.condition, a = answer.answer;
      ++k.answers;
      k.correct += a == c ? 1 : 0;
      ++k.named[c][a];
      if (c == 1) {
        ++k.signal;
        k.hits += a == 1 ? 1 : 0;
      } else {
        ++k.noise;
        k.false_alarms += a == 1 ? 1 : 0;
      }
    }
  }

  for (std::size_t t = 0; t < protocol.tests.size(); ++t) {
    report.tests.push_back(ResultOf(protocol, t, counts, modes));
  }
  return report;
}

nlohmann::json ReportToJson(const StudyReport& report) {
  json j = json::object();
  j["protocol_name"] = report.protocol_name;
  j["protocol_hash"] = report.protocol_hash;
  j["sessions"] = report.sessions;
  j["methods"] = {{"percent_correct", "100 * correct / answered series, per participant and test"},
                  {"sd", "sample standard deviation over participants (n - 1)"},
                  {"binomial",
                   "exact binomial test against chance, 1/k for a test of k conditions (0.5 for "
                   "two); two-sided p sums outcomes no more likely than the observed one"},
                  {"d_prime",
                   "two conditions only (null for more): one-interval two-alternative "
                   "identification (yes/no): z(H) - z(F), condition "
                   "1 as signal, log-linear correction (Hautus 1995): H = (hits + 0.5) / "
                   "(signal series + 1), F = (false alarms + 0.5) / (noise series + 1)"},
                  {"confusion",
                   "tests of more than two conditions: pooled answers, row = condition "
                   "presented, column = condition named, in the test's order"},
                  {"label_swap_suspected", "one-sided binomial p (below chance) < 0.05"},
                  {"reached_90", "percent correct >= 90"}};
  json tests = json::array();
  for (const TestResult& t : report.tests) {
    json tj = json::object();
    tj["name"] = t.name;
    tj["conditions"] = t.conditions;
    tj["chance"] = t.chance;
    if (t.conditions.size() > 2) tj["confusion"] = t.confusion;
    tj["n_participants"] = t.percent_correct.n;
    tj["mean_percent_correct"] = NumberOrNull(t.percent_correct.mean);
    tj["sd"] = NumberOrNull(t.percent_correct.sd);
    tj["mean_d_prime"] = NumberOrNull(t.mean_d_prime);
    tj["reached_90_count"] = t.reached_criterion;
    json swapped = json::array();
    for (const auto& p : t.participants) {
      if (p.label_swap_suspected) swapped.push_back(p.id);
    }
    tj["label_swap_suspected"] = swapped;
    tj["pooled"] = {{"answers", t.pooled_answers},
                    {"correct", t.pooled_correct},
                    {"percent_correct",
                     NumberOrNull(t.pooled_answers > 0 ? 100.0 * t.pooled_correct / t.pooled_answers
                                                       : std::nan(""))},
                    {"p_two_sided", t.pooled.p_two_sided},
                    {"p_greater", t.pooled.p_greater},
                    {"p_less", t.pooled.p_less}};
    json ps = json::array();
    for (const auto& p : t.participants) {
      ps.push_back({{"id", p.id},
                    {"mode", p.mode},
                    {"answers", p.answers},
                    {"correct", p.correct},
                    {"percent_correct", p.percent_correct},
                    {"p_two_sided", p.binomial.p_two_sided},
                    {"p_greater", p.binomial.p_greater},
                    {"p_less", p.binomial.p_less},
                    {"d_prime", NumberOrNull(p.d_prime.d_prime)},
                    {"criterion", NumberOrNull(p.d_prime.criterion)},
                    {"hit_rate", NumberOrNull(p.d_prime.hit_rate)},
                    {"false_alarm_rate", NumberOrNull(p.d_prime.false_alarm_rate)},
                    {"reached_90", p.reached_criterion},
                    {"label_swap_suspected", p.label_swap_suspected},
                    {"complete", p.complete}});
    }
    tj["participants"] = ps;
    tests.push_back(tj);
  }
  j["tests"] = tests;
  return j;
}

std::string ReportToText(const StudyReport& report) {
  std::ostringstream out;
  out << "Protocol \"" << report.protocol_name << "\" (" << report.protocol_hash << "), "
      << report.sessions << " session(s)\n";
  for (const TestResult& t : report.tests) {
    out << "\n" << t.name << ": ";
    for (std::size_t c = 0; c < t.conditions.size(); ++c) {
      out << (c == 0 ? "" : " vs ") << t.conditions[c];
    }
    if (t.conditions.size() > 2) out << " (chance " << Format("%.1f", 100.0 * t.chance) << "%)";
    out << "\n";
    out << "  participants " << t.percent_correct.n << ", mean "
        << Format("%.1f", t.percent_correct.mean) << "% correct (SD "
        << Format("%.1f", t.percent_correct.sd) << "), mean d' " << Format("%.2f", t.mean_d_prime)
        << ", " << t.reached_criterion << " at 90% or better\n";
    out << "  pooled " << t.pooled_correct << "/" << t.pooled_answers
        << " correct, exact binomial p two-sided " << Format("%.3g", t.pooled.p_two_sided)
        << ", above chance " << Format("%.3g", t.pooled.p_greater) << ", below chance "
        << Format("%.3g", t.pooled.p_less) << "\n";
    char header[160];
    std::snprintf(header, sizeof header, "  %-16s %7s %7s %9s %10s %10s %10s %6s  %s\n",
                  "participant", "answers", "correct", "%correct", "p(2-sided)", "p(above)",
                  "p(below)", "d'", "notes");
    out << header;
    for (const auto& p : t.participants) {
      std::string notes;
      if (p.reached_criterion) notes += ">=90% ";
      if (p.label_swap_suspected) notes += "below chance: labels swapped? ";
      if (!p.complete) notes += "incomplete ";
      char line[200];
      std::snprintf(line, sizeof line, "  %-16s %7d %7d %9.1f %10.3g %10.3g %10.3g %6s  %s\n",
                    p.id.c_str(), p.answers, p.correct, p.percent_correct, p.binomial.p_two_sided,
                    p.binomial.p_greater, p.binomial.p_less,
                    Format("%.2f", p.d_prime.d_prime).c_str(), notes.c_str());
      out << line;
    }
    if (t.conditions.size() > 2) out << ConfusionText(t);
  }
  return out.str();
}

}  // namespace rigidtouch::study
