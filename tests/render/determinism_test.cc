// The same scene and inputs give bitwise-identical results (Box2D test_determinism).
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>

#include "rigidtouch/rigidtouch.h"
#include "test_util.h"

namespace rigidtouch {
namespace {

// FNV-1a over the bytes of every body state
std::uint64_t Hash(const Data& d) {
  std::uint64_t h = 1469598103934665603ull;
  auto mix = [&h](const double* v, int n) {
    for (int i = 0; i < n; ++i) {
      std::uint64_t bits;
      std::memcpy(&bits, &v[i], sizeof bits);
      for (int b = 0; b < 8; ++b) {
        h ^= (bits >> (8 * b)) & 0xff;
        h *= 1099511628211ull;
      }
    }
  };
  for (const BodyState& s : d.bodies) {
    mix(s.x_W.data(), 3);
    mix(s.q_WB.coeffs().data(), 4);
    mix(s.v_W.data(), 3);
    mix(s.w_W.data(), 3);
  }
  return h;
}

std::uint64_t RunHash(const Model& m, Data& d, int steps) {
  TickInput in;
  in.tool_wrench.force_N = Vec3(0.0, 0.0, -2.0);
  for (int s = 0; s < steps; ++s) {
    // a varying input, as a hand would give
    in.tool_wrench.force_N.x() = 0.3 * std::sin(0.01 * s);
    Tick(m, d, in);
  }
  return Hash(d);
}

TEST(DeterminismTest, SameInputsGiveBitwiseIdenticalStates) {
  const std::string path =
      test::WriteTempFile("pile_small.xml", test::PileXml(3, 3, 3, 0.051, 0.16));
  const Model m1 = LoadModel(path, {});
  const Model m2 = LoadModel(path, {});
  Data d1 = MakeData(m1);
  Data d2 = MakeData(m2);
  const std::uint64_t h1 = RunHash(m1, d1, 3000);
  const std::uint64_t h2 = RunHash(m2, d2, 3000);
  EXPECT_EQ(h1, h2);
  // the run did something: the state moved away from the initial one
  Data fresh = MakeData(m1);
  EXPECT_NE(h1, Hash(fresh));
  // and ResetData reproduces it on reused buffers
  ResetData(m1, d1);
  EXPECT_EQ(RunHash(m1, d1, 3000), h1);
}

}  // namespace
}  // namespace rigidtouch
