#include "bench_test_config.h"

#ifdef RIGIDTOUCH_BENCH_ENABLED

#include <cmath>

#include "bench/bullet_engine.h"
#include "bench/harness.h"
#include "bench/mujoco_engine.h"
#include "bench_scenes.h"
#include "null_engine.h"

namespace rigidtouch::bench {
namespace {

TEST(StrikeStartHeight, GapIsMeasuredAlongTheUpwardFaceNormal) {
  const Vec3 centre_m(0.3, -0.2, 0.1);
  // upright: half-size + gap + radius above the centre
  EXPECT_NEAR(StrikeStartHeight(centre_m, Quat::Identity(), 0.025, 0.010, 0.005), 0.14, 1e-15);
  // tilted by 10 degrees about x: the face plane and the sphere's offset from it both rise by
  // 1 / cos(10 deg) along the vertical through the centre
  const double tilt = 10.0 * M_PI / 180.0;
  const Quat tilted(Eigen::AngleAxisd(tilt, Vec3::UnitX()));
  EXPECT_NEAR(StrikeStartHeight(centre_m, tilted, 0.025, 0.010, 0.005),
              0.1 + 0.040 / std::cos(tilt), 1e-15);
  // upside down (180 degrees about y): the former bottom face is now the upward one
  const Quat flipped(Eigen::AngleAxisd(M_PI, Vec3::UnitY()));
  EXPECT_NEAR(StrikeStartHeight(centre_m, flipped, 0.025, 0.010, 0.005), 0.14, 1e-15);
  // on its side (90 degrees about x, then 10 degrees about y): a side face is the upward one
  const Quat side = Quat(Eigen::AngleAxisd(tilt, Vec3::UnitY())) *
                    Quat(Eigen::AngleAxisd(M_PI / 2, Vec3::UnitX()));
  EXPECT_NEAR(StrikeStartHeight(centre_m, side, 0.025, 0.010, 0.005), 0.1 + 0.040 / std::cos(tilt),
              1e-15);
  // sphere-to-plane distance check for the tilted case: (z - z_face) n_z - r = gap
  const double z = StrikeStartHeight(centre_m, tilted, 0.025, 0.010, 0.005);
  const double face_z = 0.1 + 0.025 / std::cos(tilt);
  EXPECT_NEAR((z - face_z) * std::cos(tilt) - 0.005, 0.010, 1e-15);
}

TEST(SceneRun, SteadyRunMeasuresEveryStepAndRestoresEachBatch) {
  Scene scene = SceneFor("tap.xml");
  scene.warmup_steps = 200;
  scene.measured_steps = 50;
  scene.batch_steps = 20;
  MujocoEngine engine;
  SceneRun run(engine, scene);
  run.Prepare();
  for (int i = 0; i < scene.measured_steps; ++i) EXPECT_GT(run.MeasureOne(), 0);
  EXPECT_THROW(run.MeasureOne(), Error);  // the duration buffer is sized once
  const RunResult result = run.Finish();
  EXPECT_EQ(result.engine, "mujoco");
  EXPECT_EQ(result.time.count, 50);
  EXPECT_EQ(run.durations_ns().size(), 50u);
  EXPECT_LE(result.time.median_ns, result.time.p99_ns);
  EXPECT_LE(result.time.p999_ns, result.time.max_ns);
  // the tool rests on the floor through every measured step: one contact each
  EXPECT_DOUBLE_EQ(result.mean_contacts, 1.0);
  EXPECT_TRUE(result.gates.ok());
  EXPECT_EQ(result.gates.steps, 200 + 50);
  // restoring every 20 steps keeps the settled pose: the engine is back at the snapshot after
  // 50 = 2 * 20 + 10 steps, i.e. 10 steps after it
  EXPECT_NEAR(engine.BodyPosition("tool").z(), 0.005 - engine.DeepestPenetration_m(), 1e-9);
}

TEST(SceneRun, WatchGateMeasuresTheDisplacement) {
  // no warm-up: the watch run is 5 steps of free fall from rest, a h^2 n (n + 1) / 2 with n = 5
  Scene scene = SceneFor("tap.xml");
  scene.warmup_steps = 0;
  scene.measured_steps = 1;
  scene.watch_body = "tool";
  scene.watch_steps = 5;
  scene.max_watch_displacement_m = 1e-4;
  MujocoEngine engine;
  SceneRun run(engine, scene);
  run.Prepare();
  EXPECT_NEAR(engine.BodyPosition("tool").z(), 0.006, 1e-15);  // restored after the watch run
  run.MeasureOne();
  const RunResult result = run.Finish();
  EXPECT_NEAR(result.gates.watch_displacement_m, kToolAcceleration * kH * kH * 15, 1e-12);
  ASSERT_EQ(result.gates.failures.size(), 1u);
  EXPECT_NE(result.gates.failures[0].find("tool moved"), std::string::npos)
      << result.gates.failures[0];
}

TEST(SceneRun, PenetrationGateCountsTheOffendingSteps) {
  Scene scene = SceneFor("tap.xml");
  scene.warmup_steps = 100;
  scene.measured_steps = 10;
  scene.max_penetration_m = 1e-6;  // MuJoCo's resting penetration is ~0.7 mm
  MujocoEngine engine;
  SceneRun run(engine, scene);
  run.Prepare();
  for (int i = 0; i < scene.measured_steps; ++i) run.MeasureOne();
  const RunResult result = run.Finish();
  ASSERT_FALSE(result.gates.ok());
  EXPECT_GT(result.gates.deepest_penetration_m, 1e-6);
  EXPECT_GE(result.gates.steps_over_penetration, 10);  // every measured step at least
  EXPECT_LE(result.gates.steps_over_penetration, result.gates.steps);
  EXPECT_NE(result.gates.failures[0].find("deepest penetration"), std::string::npos);
}

// smallest n with v0 h n + a h^2 n (n + 1) / 2 >= gap: the first step count after which the
// tool, moving down from rest at v0 under a, has closed the gap (semi-implicit Euler)
int StepsToCloseGap(double gap_m, double v0_mps, double a_mps2) {
  int n = 0;
  while (v0_mps * kH * n + a_mps2 * kH * kH * n * (n + 1) / 2 < gap_m) ++n;
  return n;
}

Scene StackStrike() {
  Scene scene = SceneFor("stack.xml");
  scene.kind = SceneKind::kStrike;
  scene.warmup_steps = 100;
  scene.measured_steps = 3;
  scene.strike_target = "box_9";
  return scene;
}

TEST(SceneRun, StrikeTimesTheStepOfFirstToolContactInMujoco) {
  // 10 mm at 0.3 m/s plus 29.81 m/s^2: closed after n = 18 steps (9.66 mm after 17, 10.50 after
  // 18); MuJoCo finds the contact at the start of the next step, which then resolves it. The
  // top box sinks a few micrometres meanwhile, hence one step of slack.
  const int closed = StepsToCloseGap(0.010, 0.3, kToolAcceleration);
  ASSERT_EQ(closed, 18);
  const Scene scene = StackStrike();
  MujocoEngine engine;
  SceneRun run(engine, scene);
  run.Prepare();
  for (int i = 0; i < scene.measured_steps; ++i) {
    EXPECT_GT(run.MeasureOne(), 0);
    EXPECT_GE(run.last_strike_steps(), closed + 1);
    EXPECT_LE(run.last_strike_steps(), closed + 2);
    EXPECT_GT(engine.BodyContactCount("tool"), 0);
  }
  const RunResult result = run.Finish();
  EXPECT_EQ(result.time.count, scene.measured_steps);
  EXPECT_EQ(result.gates.strikes_missed, 0);
}

TEST(SceneRun, StrikeTimesTheStepOfFirstToolContactInBullet) {
  // Bullet hands contacts closer than its breaking threshold to the solver before they touch,
  // so its first tool contact may come a step earlier than MuJoCo's
  const int closed = StepsToCloseGap(0.010, 0.3, kToolAcceleration);
  const Scene scene = StackStrike();
  BulletEngine engine;
  SceneRun run(engine, scene);
  run.Prepare();
  for (int i = 0; i < scene.measured_steps; ++i) {
    EXPECT_GT(run.MeasureOne(), 0);
    EXPECT_GE(run.last_strike_steps(), closed - 1);
    EXPECT_LE(run.last_strike_steps(), closed + 2);
  }
  EXPECT_EQ(run.Finish().gates.strikes_missed, 0);
}

TEST(SceneRun, StrikeWithoutContactFailsTheGate) {
  Scene scene = StackStrike();
  scene.strike_max_steps = 5;  // far too few to cross 10 mm
  scene.measured_steps = 1;
  MujocoEngine engine;
  SceneRun run(engine, scene);
  run.Prepare();
  EXPECT_EQ(run.MeasureOne(), -1);
  const RunResult result = run.Finish();
  EXPECT_EQ(result.gates.strikes_missed, 1);
  EXPECT_FALSE(result.gates.ok());
}

// an engine that only records, in a log shared by several, which engine stepped
class LoggingEngine : public NullEngine {
 public:
  LoggingEngine(int id, std::vector<int>* log) : NullEngine("logging"), id_(id), log_(log) {}
  void Step() override { log_->push_back(id_); }

 private:
  int id_;
  std::vector<int>* log_;
};

// three engines, 7 measurements each in turns of 3: blocks of 3, 3 and 1 steps, the order
// rotating by one engine per turn; every engine ends with exactly its 7 measurements
TEST(MeasureInterleaved, TurnsOfBlockStepsInRotatingOrder) {
  Scene scene;
  scene.name = "log";
  scene.warmup_steps = 0;
  scene.measured_steps = 7;
  std::vector<int> log;
  LoggingEngine e0(0, &log), e1(1, &log), e2(2, &log);
  SceneRun r0(e0, scene), r1(e1, scene), r2(e2, scene);
  for (SceneRun* r : {&r0, &r1, &r2}) r->Prepare();
  SceneRun* runs[] = {&r0, &r1, &r2};
  MeasureInterleaved(runs, scene.measured_steps, 3);
  const std::vector<int> expected = {0, 0, 0, 1, 1, 1, 2, 2, 2,  // turn 0: 0, 1, 2
                                     1, 1, 1, 2, 2, 2, 0, 0, 0,  // turn 1: 1, 2, 0
                                     2, 0, 1};                   // turn 2: 2, 0, 1
  EXPECT_EQ(log, expected);
  for (SceneRun* r : runs) EXPECT_EQ(r->durations_ns().size(), 7u);
  EXPECT_THROW(MeasureInterleaved(runs, 1, 0), Error);
}

}  // namespace
}  // namespace rigidtouch::bench

#else
RIGIDTOUCH_BENCH_SKIPPED_TEST(SceneRun)
#endif
