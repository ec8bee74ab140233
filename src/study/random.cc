#include "study/random.h"

#include "io/normal_deviate.h"

namespace rigidtouch::study {

namespace {
constexpr std::uint64_t kGoldenGamma = 0x9e3779b97f4a7c15ULL;
}  // namespace

std::uint64_t Mix64(std::uint64_t x) {
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

std::uint64_t DeriveSeed(std::uint64_t seed, std::initializer_list<std::uint64_t> path) {
  std::uint64_t h = Mix64(seed + kGoldenGamma);
  for (std::uint64_t part : path) {
    // chain through the mix so that (a, b) and (b, a) differ
    h = Mix64(h ^ Mix64(part + kGoldenGamma));
    h += kGoldenGamma;
  }
  return Mix64(h);
}

std::uint64_t Rng::NextU64() {
  state_ += kGoldenGamma;
  return Mix64(state_);
}

double Rng::Uniform() {
  return static_cast<double>(NextU64() >> 11) * 0x1.0p-53;
}

std::uint64_t Rng::Below(std::uint64_t n) {
  // rejection of the incomplete top block keeps every value equally likely
  const std::uint64_t limit = UINT64_MAX - UINT64_MAX % n;
  std::uint64_t x = NextU64();
  while (x >= limit) x = NextU64();
  return x % n;
}

bool Rng::Bernoulli(double p) {
  const double u = Uniform();
  return u < p;
}

double Rng::Normal() {
  const double u1 = 1.0 - Uniform();  // (0, 1]: log is finite
  const double u2 = Uniform();
  return io::BoxMuller(u1, u2);
}

}  // namespace rigidtouch::study
