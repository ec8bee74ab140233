#include "study/statistics.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace rigidtouch::study {

double NormalCdf(double x) {
  return 0.5 * std::erfc(-x / std::numbers::sqrt2);
}

double NormalQuantile(double p) {
  if (!(p > 0.0)) return -std::numeric_limits<double>::infinity();
  if (!(p < 1.0)) return std::numeric_limits<double>::infinity();
  // bisection on the monotone cdf: slow but exact to the resolution of erfc
  double lo = -40.0;
  double hi = 40.0;
  for (int i = 0; i < 200 && hi - lo > 1e-15; ++i) {
    const double mid = 0.5 * (lo + hi);
    if (NormalCdf(mid) < p) {
      lo = mid;
    } else {
      hi = mid;
    }
  }
  return 0.5 * (lo + hi);
}

double BinomialPmf(int k, int n, double p) {
  if (k < 0 || k > n) return 0.0;
  if (p <= 0.0) return k == 0 ? 1.0 : 0.0;
  if (p >= 1.0) return k == n ? 1.0 : 0.0;
  const double log_choose = std::lgamma(n + 1.0) - std::lgamma(k + 1.0) - std::lgamma(n - k + 1.0);
  return std::exp(log_choose + k * std::log(p) + (n - k) * std::log1p(-p));
}

int BinomialQuantile(int n, double p, double q) {
  double cdf = 0.0;
  for (int k = 0; k <= n; ++k) {
    cdf += BinomialPmf(k, n, p);
    if (cdf >= q) return k;
  }
  return n;
}

BinomialTest ExactBinomialTest(int k, int n, double p0) {
  BinomialTest t;
  if (n <= 0) return t;
  const double observed = BinomialPmf(k, n, p0);
  const double tolerance = 1.0 + 1e-7;
  double greater = 0.0;
  double less = 0.0;
  double two = 0.0;
  for (int i = 0; i <= n; ++i) {
    const double pi = BinomialPmf(i, n, p0);
    if (i >= k) greater += pi;
    if (i <= k) less += pi;
    if (pi <= observed * tolerance) two += pi;
  }
  t.p_greater = std::min(1.0, greater);
  t.p_less = std::min(1.0, less);
  t.p_two_sided = std::min(1.0, two);
  return t;
}

DPrime LogLinearDPrime(int hits, int signal_trials, int false_alarms, int noise_trials) {
  DPrime d;
  d.hit_rate = (hits + 0.5) / (signal_trials + 1.0);
  d.false_alarm_rate = (false_alarms + 0.5) / (noise_trials + 1.0);
  const double zh = NormalQuantile(d.hit_rate);
  const double zf = NormalQuantile(d.false_alarm_rate);
  d.d_prime = zh - zf;
  d.criterion = -0.5 * (zh + zf);
  return d;
}

MeanSd ComputeMeanSd(std::span<const double> values) {
  MeanSd m;
  m.n = static_cast<int>(values.size());
  if (values.empty()) {
    m.mean = std::numeric_limits<double>::quiet_NaN();
    m.sd = std::numeric_limits<double>::quiet_NaN();
    return m;
  }
  double sum = 0.0;
  for (double v : values) sum += v;
  m.mean = sum / m.n;
  if (m.n < 2) {
    m.sd = std::numeric_limits<double>::quiet_NaN();
    return m;
  }
  double ss = 0.0;
  for (double v : values) ss += (v - m.mean) * (v - m.mean);
  m.sd = std::sqrt(ss / (m.n - 1));
  return m;
}

}  // namespace rigidtouch::study
