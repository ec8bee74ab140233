#include "bench/report.h"

#include <algorithm>
#include <cstdio>
#include <set>
#include <sstream>

namespace rigidtouch::bench {
namespace {

std::string FixedDecimals(double value, int decimals) {
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), "%.*f", decimals, value);
  return buffer;
}

std::string Pad(const std::string& text, std::size_t width) {
  return text.size() >= width ? text + " " : text + std::string(width - text.size(), ' ');
}

const RunResult* FindResult(const std::vector<RunResult>& results, const std::string& scene,
                            std::string_view engine) {
  for (const RunResult& result : results) {
    if (result.scene == scene && result.engine == engine) return &result;
  }
  return nullptr;
}

std::vector<std::string> SceneOrder(const std::vector<RunResult>& results) {
  std::vector<std::string> scenes;
  std::set<std::string> seen;
  for (const RunResult& result : results) {
    if (seen.insert(result.scene).second) scenes.push_back(result.scene);
  }
  return scenes;
}

std::string RatioCell(const RunResult* reference, const RunResult* peer) {
  if (reference == nullptr || peer == nullptr || peer->time.count == 0 ||
      reference->time.count == 0) {
    return "n/a";
  }
  const std::string flag = reference->gates.ok() && peer->gates.ok() ? "" : " !";
  return FixedDecimals(reference->time.median_ns / peer->time.median_ns, 2) + " (" +
         FixedDecimals(reference->time.p999_ns / peer->time.p999_ns, 2) + ")" + flag;
}

// the gates' measured values, so that a pass shows its margin: the watched body's largest
// displacement (stack) and the deepest penetration, in millimetres
std::string GateValues(const RunResult& r) {
  std::string values = " (";
  if (r.gates.watch_displacement_m >= 0) {
    values += "moved " + FixedDecimals(r.gates.watch_displacement_m * 1e3, 3) + " mm, ";
  }
  if (r.gates.gated_steps > 0) {
    // articulated scenes: the tool's deepest penetration and the joint's largest overshoot after
    // the warm-up (rad or m, as the joint)
    values += "tool " + FixedDecimals(r.gates.deepest_tool_penetration_m * 1e3, 3) + " mm, limit " +
              FixedDecimals(r.gates.largest_limit_overshoot * 1e3, 3) + "e-3, ";
  }
  return values + "deepest " + FixedDecimals(r.gates.deepest_penetration_m * 1e3, 3) + " mm)";
}

}  // namespace

std::vector<RunResult> MergeRepetitions(const std::vector<RunResult>& results,
                                        const std::vector<std::string>& scenes,
                                        const std::vector<std::string>& engines) {
  std::vector<RunResult> merged;
  for (const std::string& scene : scenes) {
    for (const std::string& engine : engines) {
      RunResult m;
      double contact_steps = 0.0;
      int repetitions = 0;
      for (const RunResult& r : results) {
        if (r.scene != scene || r.engine != engine) continue;
        if (repetitions++ == 0) {
          m = r;
          m.durations_ns.clear();
          m.gates.failures.clear();
        }
        m.durations_ns.insert(m.durations_ns.end(), r.durations_ns.begin(), r.durations_ns.end());
        contact_steps += r.mean_contacts * static_cast<double>(r.durations_ns.size());
        m.gates.deepest_penetration_m =
            std::max(m.gates.deepest_penetration_m, r.gates.deepest_penetration_m);
        m.gates.finite = m.gates.finite && r.gates.finite;
        m.gates.deepest_tool_penetration_m =
            std::max(m.gates.deepest_tool_penetration_m, r.gates.deepest_tool_penetration_m);
        m.gates.largest_limit_overshoot =
            std::max(m.gates.largest_limit_overshoot, r.gates.largest_limit_overshoot);
        m.gates.watch_displacement_m =
            std::max(m.gates.watch_displacement_m, r.gates.watch_displacement_m);
        for (const std::string& failure : r.gates.failures) {
          if (std::find(m.gates.failures.begin(), m.gates.failures.end(), failure) ==
              m.gates.failures.end()) {
            m.gates.failures.push_back(failure);
          }
        }
      }
      if (repetitions == 0) continue;
      std::vector<std::int64_t> sorted_ns = m.durations_ns;
      m.time = Summarize(sorted_ns);
      m.mean_contacts =
          m.durations_ns.empty() ? 0.0 : contact_steps / static_cast<double>(m.durations_ns.size());
      merged.push_back(std::move(m));
    }
  }
  return merged;
}

std::string FormatResultTable(const std::vector<RunResult>& results) {
  std::ostringstream out;
  out << Pad("scene", 13) << Pad("engine", 12) << Pad("median_us", 11) << Pad("p99_us", 11)
      << Pad("p99.9_us", 11) << Pad("max_us", 11) << Pad("contacts", 10) << Pad("steps", 8)
      << "gates\n";
  std::ostringstream failures;
  for (const RunResult& r : results) {
    out << Pad(r.scene, 13) << Pad(r.engine, 12)
        << Pad(FixedDecimals(r.time.median_ns * 1e-3, 1), 11)
        << Pad(FixedDecimals(r.time.p99_ns * 1e-3, 1), 11)
        << Pad(FixedDecimals(r.time.p999_ns * 1e-3, 1), 11)
        << Pad(FixedDecimals(r.time.max_ns * 1e-3, 1), 11)
        << Pad(FixedDecimals(r.mean_contacts, 1), 10) << Pad(std::to_string(r.time.count), 8)
        << (r.gates.ok() ? "ok" : "FAILED") << GateValues(r) << "\n";
    for (const std::string& failure : r.gates.failures) {
      failures << "  " << r.scene << " / " << r.engine << ": " << failure << "\n";
    }
  }
  if (!failures.str().empty()) out << "failed gates:\n" << failures.str();
  return out.str();
}

std::string FormatRatioTable(const std::vector<RunResult>& results, std::string_view reference,
                             const std::vector<std::string>& peers) {
  std::ostringstream out;
  out << "ratio " << reference << " / peer, median (p99.9) step time; > 1: " << reference
      << " is slower; !: a gate failed\n";
  out << Pad("scene", 13);
  for (const std::string& peer : peers) out << Pad(std::string(reference) + "/" + peer, 24);
  out << "\n";
  for (const std::string& scene : SceneOrder(results)) {
    out << Pad(scene, 13);
    const RunResult* ours = FindResult(results, scene, reference);
    for (const std::string& peer : peers)
      out << Pad(RatioCell(ours, FindResult(results, scene, peer)), 24);
    out << "\n";
  }
  return out.str();
}

}  // namespace rigidtouch::bench
