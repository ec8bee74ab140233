#include "tap_table.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>
#include <vector>

#include "base/text.h"

namespace rigidtouch::cli {
namespace {

using M = analysis::TapMetrics;

// the finite values of `value` over the taps
template <typename F>
std::vector<double> PerTap(const analysis::TapRun& run, F value) {
  std::vector<double> v;
  for (const M& t : run.taps) {
    const double x = value(t);
    if (std::isfinite(x)) v.push_back(x);
  }
  return v;
}

// mean over the taps of the finite values of `value`; NaN when none is finite
template <typename F>
double Mean(const analysis::TapRun& run, F value) {
  const std::vector<double> v = PerTap(run, value);
  if (v.empty()) return std::nan("");
  double sum = 0.0;
  for (double x : v) sum += x;
  return sum / static_cast<double>(v.size());
}

// median (the lower middle for an even count: a value some tap had, so a repetition rate stays a
// rate of the window's ticks); NaN when no value is finite
template <typename F>
double Median(const analysis::TapRun& run, F value) {
  std::vector<double> v = PerTap(run, value);
  if (v.empty()) return std::nan("");
  std::sort(v.begin(), v.end());
  return v[(v.size() - 1) / 2];
}

std::string Cell(double v, int digits = 4) {
  return std::isfinite(v) ? text::Significant(v, digits) : "-";
}

std::string PercentCell(double fraction) {
  return std::isfinite(fraction) ? text::Fixed(100.0 * fraction, 1) : "-";
}

// the transient's repetition rate over the taps: "-" without a transient, "none" for a click
std::string Repetition(const analysis::TapRun& run) {
  const double rate_hz = Median(run, [](const M& t) { return t.transient_repetition_hz; });
  if (!std::isfinite(rate_hz)) return "-";
  if (rate_hz == 0.0) return "none";
  return text::Fixed(rate_hz, 1);
}

double EnergySumJ(const analysis::TapRun& run) {
  double energy_J = 0.0;
  for (const M& t : run.taps) energy_J += t.energy_to_user_J;
  return energy_J;
}

// `text` broken into lines of at most `width` characters at spaces
std::string Wrap(const std::string& text, std::size_t width = 100) {
  std::string out, line;
  std::istringstream words(text);
  std::string word;
  while (words >> word) {
    if (!line.empty() && line.size() + 1 + word.size() > width) {
      out += line + "\n";
      line.clear();
    }
    line += (line.empty() ? "" : " ") + word;
  }
  return out + line;
}

std::string CompactRow(const std::string& name, const analysis::TapRun& run) {
  std::ostringstream s;
  s << "| " << name << " | " << Cell(Mean(run, [](const M& t) { return t.peak_force_N; })) << " | "
    << Cell(Mean(run, [](const M& t) { return t.rate_hardness_N_per_m; })) << " | "
    << Cell(Mean(run, [](const M& t) { return 1e3 * t.max_penetration_m; }), 3) << " | "
    << Cell(Mean(run, [](const M& t) { return 1e3 * t.time_to_stop_s; }), 3) << " | "
    << text::Significant(1e3 * EnergySumJ(run), 3) << " | " << Repetition(run) << " | "
    << PercentCell(Mean(run, [](const M& t) { return t.transient_band_energy_fraction[2]; }))
    << " |";
  return s.str();
}

std::string FullRow(const std::string& name, const analysis::TapRun& run) {
  int bounces = 0;
  for (const M& t : run.taps) bounces += t.bounces;
  const double nonzero = Mean(run, [](const M& t) {
    return static_cast<double>(
        std::count_if(t.impulses.begin(), t.impulses.end(),
                      [](const auto& e) { return e.requested_force_N > 0; }));
  });
  const double periodicity = Median(run, [](const M& t) { return t.transient_periodicity; });
  std::ostringstream s;
  s << "| " << name << " | " << Cell(Mean(run, [](const M& t) { return t.peak_requested_force_N; }))
    << " | " << Cell(Mean(run, [](const M& t) { return t.peak_force_N; })) << " | "
    << Cell(Mean(run, [](const M& t) { return t.rate_hardness_N_per_m; })) << " | "
    << Cell(Mean(run, [](const M& t) { return t.extended_rate_hardness_N_per_m; })) << " | "
    << Cell(Mean(run, [](const M& t) { return 1e3 * t.max_penetration_m; }), 3) << " | "
    << Cell(Mean(run, [](const M& t) { return 1e3 * t.time_to_stop_s; }), 3) << " | "
    << text::Fixed(Mean(run, [](const M& t) { return static_cast<double>(t.impulses.size()); }), 1)
    << " / " << text::Fixed(nonzero, 1) << " | " << bounces << " | "
    << text::Significant(1e3 * EnergySumJ(run), 3) << " | "
    << PercentCell(Mean(run, [](const M& t) { return t.band_energy_fraction[0]; })) << " | "
    << Repetition(run) << " (" << (std::isfinite(periodicity) ? text::Fixed(periodicity, 2) : "-")
    << ") | " << Cell(Median(run, [](const M& t) { return t.transient_peak_to_mean; }), 3) << " | "
    << PercentCell(Mean(run, [](const M& t) { return t.transient_band_energy_fraction[2]; }))
    << " | " << PercentCell(Mean(run, [](const M& t) { return t.transient_power_ratio; })) << " |";
  return s.str();
}

}  // namespace

std::string TapTableHeader(TapTable table) {
  if (table == TapTable::kCompact) {
    return "| renderer | displayed peak [N] | rate hardness [N/m] | max penetration [mm] | "
           "time to stop [ms] | energy to user [mJ] | transient repetition [Hz] | transient "
           "100-400 Hz [%] |\n"
           "|---|---|---|---|---|---|---|---|";
  }
  return "| renderer | requested peak force [N], mean/tap | displayed peak force [N], mean/tap | "
         "rate hardness [N/m], mean/tap | extended rate hardness [N/m], mean/tap | "
         "max penetration [mm], mean/tap | time to stop [ms], mean/tap | "
         "impulses scheduled / non-zero, mean/tap | bounces, sum over taps | "
         "energy to user [mJ], sum over taps | displayed force: power below 40 Hz [%], mean/tap "
         "| transient: repetition rate [Hz] (periodicity), median/tap | transient: spectral "
         "peak/mean power >= 40 Hz, median/tap | transient: power 100-400 Hz [%], mean/tap | "
         "transient / displayed power [%], mean/tap |\n"
         "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|";
}

std::string TapTableRow(TapTable table, const std::string& name, const analysis::TapRun& run) {
  return table == TapTable::kCompact ? CompactRow(name, run) : FullRow(name, run);
}

std::string TapTableNote(TapTable table, const analysis::TapRun& run) {
  double window_s = std::nan(""), resolution_hz = std::nan("");
  for (const M& t : run.taps) {
    if (std::isfinite(t.spectrum_window_s)) {
      window_s = t.spectrum_window_s;
      resolution_hz = t.spectrum_resolution_hz;
      break;
    }
  }
  std::ostringstream s;
  if (table == TapTable::kCompact) {
    s << "Means over " << run.taps.size()
      << " tap(s); energy to user summed over them (> 0: the device gave the hand energy); "
         "repetition: the median tap's. ";
  }
  s << "Repetition: how often the transient (the displayed force minus the penalty force) "
       "repeats, a train's impulse rate or a vibration's frequency (\"none\": a click that does "
       "not repeat, \"-\": no transient). Spectral figures are over ";
  if (std::isfinite(window_s)) {
    s << text::Significant(1e3 * window_s, 3) << " ms from contact onset ("
      << text::Significant(resolution_hz, 3) << " Hz resolution).";
  } else {
    s << "the collision window from contact onset (no tap touched).";
  }
  return Wrap(s.str());
}

std::string JointTableHeader() {
  return "| renderer | joint | inertia about it | damping | swing per tap (end - start), mean | "
         "furthest past its limit, mean | peak joint speed, mean | impulse the tool gave "
         "the joint, mean | impulse / damping (a damped swing's closed form), mean "
         "|\n|---|---|---|---|---|---|---|---|---|";
}

std::string JointTableRow(const std::string& name, const analysis::TapRun& run) {
  if (run.joint_taps.empty()) return "";
  const bool hinge = run.joint_kind == JointKind::kHinge;
  // a hinge in degrees, a slide in millimetres
  const double scale = hinge ? 180.0 / std::numbers::pi : 1e3;
  const std::string unit = hinge ? " deg" : " mm";
  const JointModel& joint = run.model.trees[run.wall.tree].joints[run.wall.joint];
  double swing = 0.0, past = 0.0, speed = 0.0, impulse = 0.0;
  bool limit = false;  // the joint went past a limit (its row pushed back)
  for (const analysis::JointMotion& j : run.joint_taps) {
    swing += j.position_at_end - j.position_at_start;
    const double beyond = std::max(
        {j.max_position - joint.range_hi_rad_or_m, joint.range_lo_rad_or_m - j.min_position, 0.0});
    past += beyond;
    limit = limit || (joint.limited && beyond > 1e-9);
    speed += j.peak_speed;
    impulse += j.impulse;
  }
  const double n = static_cast<double>(run.joint_taps.size());
  std::ostringstream s;
  s << "| " << name << " | " << run.joint_name << " (" << JointKindName(run.joint_kind) << ") | "
    << text::Significant(run.joint_inertia, 4) << (hinge ? " kg m^2" : " kg") << " | "
    << text::Significant(run.joint_damping, 4) << (hinge ? " N m s/rad" : " N s/m") << " | "
    << text::Significant(scale * swing / n, 3) << unit << " | "
    << (joint.limited ? text::Significant(scale * past / n, 3) + unit : std::string("- (no limit)"))
    << " | " << text::Significant(scale * speed / n, 3) << unit << "/s | "
    << text::Significant(impulse / n, 3) << (hinge ? " N m s" : " N s") << " | ";
  // the closed form holds for a damper alone: not with a spring, nor past a limit
  if (limit) {
    s << "- (past its limit)";
  } else if (run.joint_damping > 0.0 && run.joint_stiffness == 0.0) {
    s << text::Significant(scale * impulse / n / run.joint_damping, 3) << unit;
  } else {
    s << "- (a spring or no damping)";
  }
  s << " |\n";
  return s.str();
}

}  // namespace rigidtouch::cli
