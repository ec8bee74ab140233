// The articulated scenes' gates (bench/harness.h: the tool's penetration and a joint's range,
// after the warm-up), the scenes' plans, and the humanoid's wrapper file.
#include "bench_test_config.h"

#ifdef RIGIDTOUCH_BENCH_ENABLED

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "bench/bullet_engine.h"
#include "bench/engine.h"
#include "bench/harness.h"
#include "bench/mujoco_engine.h"
#include "bench_scenes.h"
#include "null_engine.h"
#include "rigidtouch/rigidtouch.h"

namespace rigidtouch::bench {
namespace {

// an engine whose tool penetration and joint position follow scripts, one value per step
class ScriptedGateEngine : public NullEngine {
 public:
  ScriptedGateEngine(std::vector<double> depth_m, std::vector<double> q)
      : NullEngine("scripted"), depth_m_(std::move(depth_m)), q_(std::move(q)) {}
  void Load(const Scene&) override { step_ = -1; }
  void Step() override { ++step_; }
  double BodyPenetration_m(std::string_view) const override { return depth_m_.at(At()); }
  double JointPosition(std::string_view) const override { return q_.at(At()); }

 private:
  std::size_t At() const { return static_cast<std::size_t>(step_); }
  std::vector<double> depth_m_, q_;
  int step_ = -1;
};

Scene GatedScene() {
  Scene scene;
  scene.name = "gated";
  scene.warmup_steps = 2;
  scene.measured_steps = 3;
  scene.max_tool_penetration_m = 0.001;
  scene.limit_joint = "hinge";
  scene.limit_lo = -1.0;
  scene.limit_hi = 0.0;
  scene.max_limit_overshoot = 0.005;
  return scene;
}

RunResult RunScripted(const Scene& scene, std::vector<double> depth_m, std::vector<double> q) {
  ScriptedGateEngine engine(std::move(depth_m), std::move(q));
  SceneRun run(engine, scene);
  run.Prepare();
  for (int i = 0; i < scene.measured_steps; ++i) run.MeasureOne();
  return run.Finish();
}

TEST(ArticulatedGates, LimitOvershootIsTheDistanceOutsideTheRange) {
  EXPECT_DOUBLE_EQ(LimitOvershoot(-0.5, -1.0, 0.0), 0.0);
  EXPECT_DOUBLE_EQ(LimitOvershoot(0.25, -1.0, 0.0), 0.25);
  EXPECT_DOUBLE_EQ(LimitOvershoot(-1.5, -1.0, 0.0), 0.5);
  EXPECT_TRUE(std::isinf(LimitOvershoot(std::nan(""), -1.0, 0.0)));
}

// values over the limits during the warm-up (the tool's arrival) do not count; after it, one step
// over either limit fails its gate with the value and the count of offending steps
TEST(ArticulatedGates, FailAfterTheWarmupOnlyAndSayBy) {
  const Scene scene = GatedScene();
  // steps 0 and 1 are the warm-up
  const RunResult ok = RunScripted(scene, {0.01, 0.01, 0.0009, 0.0, 0.0}, {1.0, 1.0, 0.004, 0, 0});
  EXPECT_TRUE(ok.gates.ok());
  EXPECT_EQ(ok.gates.gated_steps, 3);
  EXPECT_NEAR(ok.gates.deepest_tool_penetration_m, 0.0009, 1e-15);
  EXPECT_NEAR(ok.gates.largest_limit_overshoot, 0.004, 1e-15);

  const RunResult deep = RunScripted(scene, {0, 0, 0.0, 0.0011, 0.0}, {0, 0, 0, 0, 0});
  ASSERT_EQ(deep.gates.failures.size(), 1u);
  EXPECT_NE(deep.gates.failures[0].find("deepest tool penetration 1.1 mm (limit 1 mm)"),
            std::string::npos)
      << deep.gates.failures[0];
  EXPECT_NE(deep.gates.failures[0].find("in 1 of 3 steps"), std::string::npos);

  const RunResult past = RunScripted(scene, {0, 0, 0, 0, 0}, {0, 0, -1.006, -1.01, 0});
  ASSERT_EQ(past.gates.failures.size(), 1u);
  EXPECT_NE(past.gates.failures[0].find("joint hinge passed its range [-1, 0] by up to 0.01"),
            std::string::npos)
      << past.gates.failures[0];
  EXPECT_NE(past.gates.failures[0].find("in 2 of 3 steps"), std::string::npos);
}

// the scenes as the benchmark runs them: each file has the gated joint with the stated range
TEST(ArticulatedGates, ScenesGateTheirFilesJointsAtTheirRanges) {
  const std::vector<Scene> scenes = ArticulatedBenchmarkScenes(RIGIDTOUCH_SCENES);
  ASSERT_EQ(scenes.size(), 4u);
  for (const Scene& scene : scenes) {
    auto model = LoadMjcf(scene.mjcf_path);
    const int j = mj_name2id(model.get(), mjOBJ_JOINT, scene.limit_joint.c_str());
    ASSERT_GE(j, 0) << scene.name;
    EXPECT_TRUE(model->jnt_limited[j]) << scene.name;
    EXPECT_NEAR(model->jnt_range[2 * j], scene.limit_lo, 1e-12) << scene.name;
    EXPECT_NEAR(model->jnt_range[2 * j + 1], scene.limit_hi, 1e-12) << scene.name;
    EXPECT_TRUE(std::isfinite(scene.max_tool_penetration_m)) << scene.name;
  }
}

// a missing humanoid file names the flag; a stand-in with the humanoid's coordinates (a free
// torso and 21 hinges) wrapped loads in MuJoCo, rigidtouch and Bullet (a floating base and 21
// links) with the tool on its chest at 1 ms
TEST(ArticulatedGates, HumanoidWrapperNamesTheFlagAndLoads) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() /
                                    ("rigidtouch_gates_test_" + std::to_string(::getpid()));
  try {
    WriteHumanoidWrapper((dir / "missing.xml").string(), dir.string(), "rigidtouch_humanoid");
    ADD_FAILURE() << "a missing file must be refused";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("--rigidtouch_humanoid="), std::string::npos) << e.what();
  }
  std::string body = "<geom type=\"capsule\" fromto=\"0 -0.07 0 0 0.07 0\" size=\"0.07\"/>";
  std::string close;
  for (int i = 0; i < 21; ++i) {
    body += "<body name=\"b" + std::to_string(i) + "\" pos=\"0 0 -0.05\"><joint name=\"j" +
            std::to_string(i) + "\" axis=\"0 1 0\"/><geom type=\"sphere\" size=\"0.01\"/>";
    close += "</body>";
  }
  std::filesystem::create_directories(dir);
  const std::string stand_in = (dir / "stand_in.xml").string();
  std::ofstream(stand_in) << "<mujoco model=\"stand-in\"><option timestep=\"0.005\"/><worldbody>"
                             "<geom name=\"floor\" type=\"plane\" size=\"0 0 1\"/><body "
                             "name=\"torso\" pos=\"0 0 1.5\"><freejoint name=\"root\"/>"
                          << body << close << "</body></worldbody></mujoco>";
  const std::string wrapper =
      WriteHumanoidWrapper(stand_in, (dir / "wrapped").string(), "rigidtouch_humanoid");
  auto model = LoadMjcf(wrapper);
  EXPECT_DOUBLE_EQ(model->opt.timestep, 0.001);
  EXPECT_EQ(model->nq, 35);
  LoadOptions options;
  options.tool_name = "tool";
  const Model m = LoadModel(wrapper, options);
  ASSERT_EQ(m.trees.size(), 1u);
  EXPECT_NEAR(m.initial[static_cast<std::size_t>(m.tool)].x_W.z(), 0.205, 1e-12);
  EXPECT_NEAR(m.trees[0].initial_qpos[2], 0.12, 1e-12);
  BulletEngine bullet;
  bullet.Load(HumanoidBenchmarkScene(wrapper));
  ASSERT_EQ(bullet.trees().multibodies().size(), 1u);
  const btMultiBody& tree = *bullet.trees().multibodies()[0];
  EXPECT_FALSE(tree.hasFixedBase());
  EXPECT_EQ(tree.getNumLinks(), 21);
  // the torso's origin as the keyframe puts it; single-precision floats
  EXPECT_NEAR(bullet.BodyPosition("torso").z(), 0.12, 1e-6);
  EXPECT_NEAR(bullet.BodyPosition("tool").z(), 0.205, 1e-6);
}

// every engine restored to its snapshot steps as it did from the snapshot: the trees' state and
// everything the next step reads of them (rigidtouch: the link geoms' poses in the collision
// stage) come back. The arm's forearm sags by about a millimetre under the tool in the 1000 steps
// between, which a stale pose adds to the tool's penetration (1.3 mm against 0.13 mm).
TEST(ArticulatedGates, RestoredArmStepsAsFromTheSnapshot) {
  for (const EngineEntry& entry : Engines()) {
    const auto engine = entry.make();
    Scene scene = ArticulatedBenchmarkScenes(RIGIDTOUCH_SCENES)[3];
    ASSERT_EQ(scene.name, "arm");
    engine->Load(scene);
    for (int i = 0; i < 1500; ++i) engine->Step();
    engine->SaveSnapshot();
    engine->Step();
    const double depth_m = engine->BodyPenetration_m("tool");
    const double q = engine->JointPosition("elbow");
    for (int i = 0; i < 1000; ++i) engine->Step();
    engine->RestoreSnapshot();
    engine->Step();
    // Bullet's contact manifolds (warm starts) are not part of its snapshot: 10 um
    EXPECT_NEAR(engine->BodyPenetration_m("tool"), depth_m, 1e-5) << entry.name;
    EXPECT_NEAR(engine->JointPosition("elbow"), q, 1e-6) << entry.name;
  }
}

}  // namespace
}  // namespace rigidtouch::bench

#else
RIGIDTOUCH_BENCH_SKIPPED_TEST(ArticulatedGates)
#endif
