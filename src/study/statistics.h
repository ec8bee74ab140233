// Statistics for the analysis of study logs: the normal distribution, exact binomial tests, d'
// for a one-interval two-alternative identification task, mean and standard deviation.
#pragma once

#include <span>

namespace rigidtouch::study {

/// Standard normal cumulative distribution function Phi(x).
double NormalCdf(double x);

/// Inverse of NormalCdf for p in (0, 1), by bisection to 1e-14 in x; -inf at 0 and +inf at 1.
double NormalQuantile(double p);

/// Probability of exactly k successes in n Bernoulli(p) trials.
double BinomialPmf(int k, int n, double p);

/// Smallest k with P(X <= k) >= q for X ~ Binomial(n, p).
int BinomialQuantile(int n, double p, double q);

/// Exact binomial test of k successes in n trials against success probability p0.
struct BinomialTest {
  double p_greater = 1.0;    ///< one-sided P(X >= k): evidence of better than p0
  double p_less = 1.0;       ///< one-sided P(X <= k): evidence of worse than p0
  double p_two_sided = 1.0;  ///< sum of P(X = i) over every i no more likely than k
};

/// Exact binomial test. The two-sided p sums the probabilities of all outcomes at most as likely
/// as the observed one (relative tolerance 1e-7, as R's binom.test); n = 0 gives p = 1.
BinomialTest ExactBinomialTest(int k, int n, double p0 = 0.5);

/// Sensitivity of a one-interval, two-alternative identification (yes/no design): each series
/// presents one condition and the participant names it. Condition 1 is "signal", condition 0
/// "noise"; hits are condition-1 series named 1, false alarms condition-0 series named 1.
struct DPrime {
  double d_prime = 0.0;           ///< z(H) - z(F)
  double criterion = 0.0;         ///< c = -(z(H) + z(F)) / 2
  double hit_rate = 0.0;          ///< corrected H
  double false_alarm_rate = 0.0;  ///< corrected F
};

/// d' with the log-linear correction of Hautus (1995), applied to every cell:
/// H = (hits + 0.5) / (signal + 1), F = (false alarms + 0.5) / (noise + 1). It keeps rates of 0
/// and 1 finite and is less biased than the 1/(2N) rule.
DPrime LogLinearDPrime(int hits, int signal_trials, int false_alarms, int noise_trials);

/// Mean and sample standard deviation (n - 1 in the denominator; NaN when n < 2).
struct MeanSd {
  double mean = 0.0;
  double sd = 0.0;
  int n = 0;
};

/// Mean and sample standard deviation of `values` (mean NaN when empty).
MeanSd ComputeMeanSd(std::span<const double> values);

}  // namespace rigidtouch::study
