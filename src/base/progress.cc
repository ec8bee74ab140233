#include "base/progress.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ostream>
#include <utility>

namespace rigidtouch {
namespace {

double SteadySeconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

constexpr double kBarEvery_s = 0.1;  // a terminal's bar: redrawn at most ten times a second
constexpr int kBarWidth = 24;
constexpr int kSigint = 2;

}  // namespace

std::string FormatDuration(double seconds) {
  if (!std::isfinite(seconds) || seconds < 0.0) seconds = 0.0;
  char text[48];
  if (seconds < 9.95) {
    std::snprintf(text, sizeof text, "%.1f s", seconds);
  } else if (seconds < 59.5) {
    std::snprintf(text, sizeof text, "%.0f s", seconds);
  } else if (seconds < 3599.5) {
    const long s = std::lround(seconds);
    std::snprintf(text, sizeof text, "%ld min %02ld s", s / 60, s % 60);
  } else {
    const long m = std::lround(seconds / 60.0);
    std::snprintf(text, sizeof text, "%ld h %02ld min", m / 60, m % 60);
  }
  return text;
}

Progress::Progress(std::ostream& out, std::string task, Options options,
                   const std::atomic<bool>* stop, const std::atomic<int>* signal, Clock clock)
    : out_(out),
      task_(std::move(task)),
      options_(options),
      stop_(stop),
      signal_(signal),
      clock_(clock != nullptr ? clock : &SteadySeconds) {
  start_s_ = Now();
}

Progress::~Progress() {
  Finish();
}

double Progress::Now() const {
  return clock_();
}

bool Progress::Due() const {
  if (!options_.enabled) return false;
  const double now = Now();
  if (now - start_s_ < options_.first_after_s) return false;
  const double every = options_.terminal ? kBarEvery_s : options_.every_s;
  return last_print_s_ < 0.0 || now - last_print_s_ >= every;
}

std::string Progress::Text(double fraction, std::string_view where, double now) const {
  fraction = std::clamp(std::isfinite(fraction) ? fraction : 0.0, 0.0, 1.0);
  char percent[16];
  std::snprintf(percent, sizeof percent, "%.0f%%", std::floor(100.0 * fraction));
  std::string text = percent;
  if (!where.empty()) text += " (" + std::string(where) + ")";
  text += ", " + FormatDuration(now - start_s_) + " elapsed";
  const double done_since = fraction - first_fraction_;
  const double time_since = now - first_report_s_;
  if (first_report_s_ >= 0.0 && done_since > 0.0 && time_since > 0.0) {
    text += ", about " + FormatDuration((1.0 - fraction) * time_since / done_since) + " left";
  } else {
    text += ", estimating the time left";
  }
  return text;
}

void Progress::Report(double fraction, std::string_view where) {
  const double now = Now();
  if (first_report_s_ < 0.0) {
    first_report_s_ = now;
    first_fraction_ = std::clamp(std::isfinite(fraction) ? fraction : 0.0, 0.0, 1.0);
  }
  if (!Due()) return;
  last_print_s_ = now;
  ++printed_;
  const std::string text = Text(fraction, where, now);
  if (options_.terminal) {
    const double f = std::clamp(std::isfinite(fraction) ? fraction : 0.0, 0.0, 1.0);
    const int filled = static_cast<int>(std::floor(f * kBarWidth));
    // \r back to the line's start, \033[K clears what a longer earlier report left
    out_ << "\r\033[K" << task_ << " [" << std::string(filled, '#')
         << std::string(kBarWidth - filled, '.') << "] " << text << std::flush;
    bar_open_ = true;
  } else {
    out_ << "rigidtouch: progress: " << task_ << ": " << text << "\n" << std::flush;
  }
}

void Progress::Restart(std::string task) {
  task_ = std::move(task);
  first_report_s_ = -1.0;
  first_fraction_ = 0.0;
}

void Progress::Finish() {
  if (!bar_open_) return;
  out_ << "\n" << std::flush;
  bar_open_ = false;
}

bool Progress::StopRequested() const {
  return stop_ != nullptr && stop_->load(std::memory_order_acquire);
}

int Progress::StopSignal() const {
  const int s = signal_ != nullptr ? signal_->load(std::memory_order_acquire) : 0;
  return s > 0 ? s : kSigint;
}

void Progress::ThrowIfStopped(std::string_view where, std::string_view kept) const {
  if (!StopRequested()) return;
  std::string what = task_ + " stopped";
  if (!where.empty()) what += " at " + std::string(where);
  if (!kept.empty()) what += "; " + std::string(kept);
  throw Interrupted(StopSignal(), what);
}

}  // namespace rigidtouch
