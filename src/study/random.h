// Deterministic random numbers for the perception study: series orders, simulated participants and
// per-tap seeds are pure functions of a 64-bit seed, identical on every platform that has IEEE
// doubles (the standard library's distributions are not, so they are not used).
#pragma once

#include <cstdint>
#include <initializer_list>

namespace rigidtouch::study {

/// The SplitMix64 finaliser (Steele, Lea & Flood, OOPSLA 2014): a bijective 64-bit mix.
std::uint64_t Mix64(std::uint64_t x);

/// Derives an independent stream seed from a parent seed and a path of integers (e.g. a stream
/// tag, a test index and a series index). Different paths give unrelated seeds.
std::uint64_t DeriveSeed(std::uint64_t seed, std::initializer_list<std::uint64_t> path);

/// A small deterministic generator (SplitMix64 sequence) with portable distributions.
class Rng {
 public:
  /// Starts the sequence at `seed`.
  explicit Rng(std::uint64_t seed) : state_(seed) {}

  /// Next raw 64-bit output.
  std::uint64_t NextU64();
  /// Uniform double in [0, 1) with 53 random bits.
  double Uniform();
  /// Uniform integer in [0, n) without modulo bias; n must be positive.
  std::uint64_t Below(std::uint64_t n);
  /// True with probability p (p <= 0 never, p >= 1 always).
  bool Bernoulli(double p);
  /// Standard normal deviate (io::BoxMuller of 1 - Uniform() then Uniform(): two uniforms per
  /// call, no cached second value so that the sequence does not depend on call history).
  double Normal();

 private:
  std::uint64_t state_;
};

}  // namespace rigidtouch::study
