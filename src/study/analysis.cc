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
  int signal = 0;        // condition 1 presented
  int noise = 0;         // condition 0 presented
  int hits = 0;          // condition 1 named 1
  int false_alarms = 0;  // condition 0 named 1
};

json NumberOrNull(double v) {
  return std::isfinite(v) ? json(v) : json();
}

std::string Format(const char* format, double v) {
  if (!std::isfinite(v)) return "-";
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, format, v);
  return buffer;
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
    for (const LoggedAnswer& answer : valid.answers) {
      Counts& k = per_test[answer.test];
      const int c = answer.condition, a = answer.answer;
      ++k.answers;
      k.correct += a == c ? 1 : 0;
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
    const StudyTest& test = protocol.tests[t];
    TestResult result;
    result.name = test.name;
    result.conditions = {protocol.conditions[test.conditions[0]].label,
                         protocol.conditions[test.conditions[1]].label};
    std::vector<double> percents;
    double d_sum = 0.0;
    for (const auto& [id, per_test] : counts) {
      const Counts& k = per_test[t];
      if (k.answers == 0) continue;
      ParticipantResult p;
      p.id = id;
      p.mode = modes[id];
      p.answers = k.answers;
      p.correct = k.correct;
      p.percent_correct = 100.0 * k.correct / k.answers;
      p.binomial = ExactBinomialTest(k.correct, k.answers, 0.5);
      p.d_prime = LogLinearDPrime(k.hits, k.signal, k.false_alarms, k.noise);
      p.reached_criterion = p.percent_correct >= kCriterionPercent;
      p.label_swap_suspected = p.binomial.p_less < kLabelSwapAlpha;
      p.complete = k.answers == test.series;
      percents.push_back(p.percent_correct);
      d_sum += p.d_prime.d_prime;
      result.reached_criterion += p.reached_criterion ? 1 : 0;
      result.pooled_answers += k.answers;
      result.pooled_correct += k.correct;
      result.participants.push_back(p);
    }
    result.percent_correct = ComputeMeanSd(percents);
    result.mean_d_prime = percents.empty() ? std::nan("") : d_sum / percents.size();
    result.pooled = ExactBinomialTest(result.pooled_correct, result.pooled_answers, 0.5);
    report.tests.push_back(std::move(result));
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
                   "exact binomial test against 0.5; two-sided p sums outcomes no more likely "
                   "than the observed one"},
                  {"d_prime",
                   "one-interval two-alternative identification (yes/no): z(H) - z(F), condition "
                   "1 as signal, log-linear correction (Hautus 1995): H = (hits + 0.5) / "
                   "(signal series + 1), F = (false alarms + 0.5) / (noise series + 1)"},
                  {"label_swap_suspected", "one-sided binomial p (below chance) < 0.05"},
                  {"reached_90", "percent correct >= 90"}};
  json tests = json::array();
  for (const TestResult& t : report.tests) {
    json tj = json::object();
    tj["name"] = t.name;
    tj["conditions"] = {t.conditions[0], t.conditions[1]};
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
                    {"d_prime", p.d_prime.d_prime},
                    {"criterion", p.d_prime.criterion},
                    {"hit_rate", p.d_prime.hit_rate},
                    {"false_alarm_rate", p.d_prime.false_alarm_rate},
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
    out << "\n" << t.name << ": " << t.conditions[0] << " vs " << t.conditions[1] << "\n";
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
      std::snprintf(line, sizeof line, "  %-16s %7d %7d %9.1f %10.3g %10.3g %10.3g %6.2f  %s\n",
                    p.id.c_str(), p.answers, p.correct, p.percent_correct, p.binomial.p_two_sided,
                    p.binomial.p_greater, p.binomial.p_less, p.d_prime.d_prime, notes.c_str());
      out << line;
    }
  }
  return out.str();
}

}  // namespace rigidtouch::study
