#include "bench_test_config.h"

#ifdef RIGIDTOUCH_BENCH_ENABLED

#include <algorithm>

#include "bench/mujoco_engine.h"
#include "bench_scenes.h"

namespace rigidtouch::bench {
namespace {

TEST(MujocoEngine, ToolFallsWithGravityPlusPushBeforeContact) {
  MujocoEngine engine;
  engine.Load(SceneFor("tap.xml"));
  // semi-implicit Euler from rest: z_n = z_0 - a h^2 n (n + 1) / 2; the tool touches the floor
  // only after about 8 steps (1 mm gap); 1e-12 m absorbs rounding over 5 steps
  for (int n = 1; n <= 5; ++n) {
    engine.Step();
    EXPECT_NEAR(engine.BodyPosition("tool").z(),
                0.006 - kToolAcceleration * kH * kH * n * (n + 1) / 2, 1e-12)
        << "step " << n;
    EXPECT_EQ(engine.ContactCount(), 0);
  }
}

TEST(MujocoEngine, ToolRestsOnTheFloorWithSmallPenetration) {
  MujocoEngine engine;
  engine.Load(SceneFor("tap.xml"));
  for (int i = 0; i < 2000; ++i) engine.Step();
  EXPECT_EQ(engine.ContactCount(), 1);
  EXPECT_EQ(engine.BodyContactCount("tool"), 1);
  const double penetration_m = engine.DeepestPenetration_m();
  EXPECT_GT(penetration_m, 0.0);
  EXPECT_LT(penetration_m, 0.001);
  // at rest the centre sits one radius minus the penetration above the floor; 1e-9 m allows the
  // contact being measured at the start of the (motionless) last step
  EXPECT_NEAR(engine.BodyPosition("tool").z(), 0.005 - penetration_m, 1e-9);
  EXPECT_TRUE(engine.StateIsFinite());
  EXPECT_EQ(engine.WarningCount(), 0);
}

TEST(MujocoEngine, RestoreReplaysTheSameSteps) {
  MujocoEngine engine;
  engine.Load(SceneFor("stack.xml"));
  for (int i = 0; i < 100; ++i) engine.Step();
  engine.SaveSnapshot();
  for (int i = 0; i < 50; ++i) engine.Step();
  const Vec3 first_m = engine.BodyPosition("box_9");
  const int first_contacts = engine.ContactCount();
  engine.RestoreSnapshot();
  for (int i = 0; i < 50; ++i) engine.Step();
  // MuJoCo is deterministic from a full mjData copy: bit-identical
  EXPECT_EQ(engine.BodyPosition("box_9"), first_m);
  EXPECT_EQ(engine.ContactCount(), first_contacts);
}

TEST(MujocoEngine, SetBodyMotionPlacesAndLaunchesTheTool) {
  MujocoEngine engine;
  engine.Load(SceneFor("tap.xml"));
  engine.SetBodyMotion("tool", Vec3(0.1, 0.2, 0.3), Vec3(0, 0, -0.3));
  EXPECT_EQ(engine.BodyPosition("tool"), Vec3(0.1, 0.2, 0.3));
  EXPECT_TRUE(engine.BodyOrientation("tool").isApprox(Quat::Identity(), 1e-15));
  engine.Step();
  // one semi-implicit Euler step: z = z0 + (v0 - a h) h
  const Vec3 after_m = engine.BodyPosition("tool");
  EXPECT_NEAR(after_m.z(), 0.3 + (-0.3 - kToolAcceleration * kH) * kH, 1e-12);
  EXPECT_NEAR(after_m.x(), 0.1, 1e-12);
  EXPECT_NEAR(after_m.y(), 0.2, 1e-12);
}

TEST(MujocoEngine, UnknownBodyThrowsNamingIt) {
  MujocoEngine engine;
  engine.Load(SceneFor("tap.xml"));
  try {
    engine.BodyPosition("hand");
    FAIL() << "expected rigidtouch::Error";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("'hand'"), std::string::npos);
  }
  Scene no_tool = SceneFor("tap.xml");
  no_tool.tool_body = "stylus";
  EXPECT_THROW(engine.Load(no_tool), Error);
}

TEST(MujocoEngine, ConfigurationStatesTheDefaults) {
  MujocoEngine engine;
  Scene scene = SceneFor("tap.xml");
  scene.peer_settings = PeerSettings::kDefaults;
  engine.Load(scene);
  const std::string configuration = engine.Configuration();
  EXPECT_NE(configuration.find("settings defaults"), std::string::npos) << configuration;
  EXPECT_NE(configuration.find("solver Newton"), std::string::npos) << configuration;
  EXPECT_NE(configuration.find("iterations 100"), std::string::npos) << configuration;
  EXPECT_NE(configuration.find("cone pyramidal"), std::string::npos) << configuration;
  EXPECT_NE(configuration.find("solref 0.02 1"), std::string::npos) << configuration;
}

TEST(MujocoEngine, StackingSettingsReachTheModelAndItsConfigurationLine) {
  MujocoEngine engine;
  Scene scene = SceneFor("stack.xml");
  scene.peer_settings = PeerSettings::kStacking;
  engine.Load(scene);
  const mjModel& model = *engine.model();
  const MujocoStackingSettings expected;
  EXPECT_EQ(model.opt.cone, mjCONE_ELLIPTIC);
  EXPECT_EQ(model.opt.impratio, expected.impratio);
  EXPECT_EQ(model.opt.tolerance, expected.tolerance);
  EXPECT_EQ(model.opt.timestep, kH);  // the scene's step, never changed
  for (int g = 0; g < model.ngeom; ++g) {
    EXPECT_EQ(model.geom_solref[mjNREF * g], expected.solref_timeconst_s) << g;
    EXPECT_EQ(model.geom_solimp[mjNIMP * g + 1], expected.solimp_dmax) << g;
  }
  const std::string configuration = engine.Configuration();
  EXPECT_NE(configuration.find("settings stacking"), std::string::npos) << configuration;
  EXPECT_NE(configuration.find("cone elliptic, impratio 10"), std::string::npos) << configuration;
  EXPECT_NE(configuration.find("solimp 0.99 0.999 0.001"), std::string::npos) << configuration;
}

// the stack gate of the benchmark (bench/scene.cc): with the stacking settings the top box moves
// less than 1 mm over 10 s after 2 s of settling (with MuJoCo's defaults the stack falls)
TEST(MujocoEngine, StackHoldsTheGateWithTheStackingSettings) {
  MujocoEngine engine;
  Scene scene = SceneFor("stack.xml");
  scene.peer_settings = PeerSettings::kStacking;
  engine.Load(scene);
  for (int i = 0; i < 2000; ++i) engine.Step();
  const Vec3 start_m = engine.BodyPosition("box_9");
  double largest_m = 0.0;
  for (int i = 0; i < 10000; ++i) {
    engine.Step();
    largest_m = std::max(largest_m, (engine.BodyPosition("box_9") - start_m).norm());
  }
  EXPECT_LT(largest_m, 0.001);
  EXPECT_TRUE(engine.StateIsFinite());
  EXPECT_EQ(engine.WarningCount(), 0);
}

}  // namespace
}  // namespace rigidtouch::bench

#else
RIGIDTOUCH_BENCH_SKIPPED_TEST(MujocoEngine)
#endif
