// Seeded random draws in a fixed order, for the tests' random problems.
#pragma once

#include <Eigen/Core>

namespace rigidtouch::test {

/// Three draws of `dist`: x, then y, then z. `Vec3(d(rng), d(rng), d(rng))` leaves the order of
/// the draws to the compiler (gcc draws z first, clang x), so one seed would give each compiler
/// other samples; every random vector of the tests is drawn through here or in statements.
template <class Dist, class Rng>
Eigen::Vector3d Draw3(Dist& dist, Rng& rng) {
  const double x = dist(rng);
  const double y = dist(rng);
  const double z = dist(rng);
  return {x, y, z};
}

/// Two draws of `dist` (x, then y) and a given z.
template <class Dist, class Rng>
Eigen::Vector3d Draw2(Dist& dist, Rng& rng, double z) {
  const double x = dist(rng);
  const double y = dist(rng);
  return {x, y, z};
}

}  // namespace rigidtouch::test
