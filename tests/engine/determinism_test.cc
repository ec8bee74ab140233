// The same scene and inputs give bitwise-identical results (Box2D test_determinism), and the
// shipped stack and pile give the committed golden hashes, so that a change of behaviour between
// commits cannot pass unnoticed.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>

#include "dynamics/tree.h"
#include "engine/workspace.h"
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

// FNV-1a over the device command of every tick and the final body states
std::uint64_t GoldenRun(const std::string& scene, RendererKind renderer, int steps,
                        int threads = 1) {
  LoadOptions o;
  o.render.renderer = renderer;
  o.threads = threads;
  const Model m = LoadModel(scene, o);
  Data d = MakeData(m);
  // with two threads the worker exists (and shares most of the tick's stages)
  EXPECT_EQ(d.workspace->worker != nullptr, threads == 2);
  TickInput in;
  in.tool_wrench.force_N = Vec3(0.0, 0.0, -2.0);
  std::uint64_t h = 1469598103934665603ull;
  auto mix = [&h](const Vec3& v) {
    for (int i = 0; i < 3; ++i) {
      std::uint64_t bits;
      std::memcpy(&bits, &v[i], sizeof bits);
      h = (h ^ bits) * 1099511628211ull;
    }
  };
  int impulses = 0;
  for (int s = 0; s < steps; ++s) {
    // a sideways push that changes sign, so friction sticks and slips
    in.tool_wrench.force_N.x() = 0.3 * std::sin(0.01 * s);
    const DeviceCommand out = Tick(m, d, in);
    mix(out.force_N);
    mix(out.impulsive_force_N);
    impulses += d.nimpulse;
  }
  EXPECT_GT(impulses, 0) << scene;  // the run exercised the impulse stage
  return h ^ Hash(d);
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

// The golden hashes of the shipped stack (train) and pile (single impulse) over 2 s with the tool
// pushed down by 2 N and sideways by up to 0.3 N. A change to any stage of the tick that moves
// one bit of one state or command changes them. When a change of behaviour is intended, say why
// in its commit and put the new values here.
// With `threads` 2 (a worker thread sharing the narrow phase and the group solves) the hashes are
// the same.
TEST(DeterminismTest, GoldenHashOfTheShippedStackAndPile) {
  for (const int threads : {1, 2}) {
    EXPECT_EQ(GoldenRun(std::string(RIGIDTOUCH_SCENES) + "/stack.xml", RendererKind::kTrain, 2000,
                        threads),
              0xf9932d8c10f8cb24ull)
        << threads << " threads";
    EXPECT_EQ(GoldenRun(std::string(RIGIDTOUCH_SCENES) + "/pile.xml", RendererKind::kImpulse, 2000,
                        threads),
              0x4a2bd7fdf5c76c67ull)
        << threads << " threads";
  }
}

// FNV-1a over every tree's qpos and qvel after `steps` ticks of a scene without a tool
std::uint64_t TreeGoldenRun(const std::string& scene, int steps, int threads) {
  LoadOptions o;
  o.tool_name = "none";
  o.threads = threads;
  const Model m = LoadModel(scene, o);
  Data d = MakeData(m);
  const TickInput in;
  for (int s = 0; s < steps; ++s) Tick(m, d, in);
  std::uint64_t h = 1469598103934665603ull;
  for (const auto& tree : d.trees) {
    for (const Eigen::VectorXd* v : {&tree->qpos, &tree->qvel}) {
      for (int i = 0; i < v->size(); ++i) {
        std::uint64_t bits;
        std::memcpy(&bits, v->data() + i, sizeof bits);
        h = (h ^ bits) * 1099511628211ull;
      }
    }
  }
  return h;
}

// The golden hashes of two articulated test scenes over 2000 steps: the arm held by its position
// actuators (hinges, a slide, force clamps) and the humanoid-like tree (a free root, ball joints,
// hinges with springs and ref). With `threads` 2 the hashes are the same. The arm's changed when
// joint limits became rows of the contact groups (its finger rests on its slide's lower limit);
// with the limit rows switched off the old hash, 0xb5ddb25b6399c680, came back bit for bit (the
// tree step split around the contact stages does TreeStep's operations in its order).
TEST(DeterminismTest, GoldenHashOfArticulatedTrees) {
  for (const int threads : {1, 2}) {
    EXPECT_EQ(TreeGoldenRun(test::TestScene("articulated/arm.xml"), 2000, threads),
              0x34513448e447ec15ull)
        << threads << " threads";
    EXPECT_EQ(TreeGoldenRun(test::TestScene("articulated/humanoid_like.xml"), 2000, threads),
              0x9195412f1b67d4b6ull)
        << threads << " threads";
  }
}

// threads other than 1 and 2 are refused at load, naming the setting
TEST(DeterminismTest, ThreadsOtherThanOneOrTwoAreRefused) {
  for (const int threads : {0, 3, -1}) {
    LoadOptions o;
    o.threads = threads;
    try {
      LoadModel(std::string(RIGIDTOUCH_SCENES) + "/stack.xml", o);
      ADD_FAILURE() << threads << " accepted";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("threads is " + std::to_string(threads)),
                std::string::npos)
          << e.what();
    }
  }
}

}  // namespace
}  // namespace rigidtouch
