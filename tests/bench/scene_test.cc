#include "bench_test_config.h"

#ifdef RIGIDTOUCH_BENCH_ENABLED

#include <string>

#include "bench/mujoco_engine.h"
#include "bench/scene.h"
#include "io/mjcf_compile.h"

namespace rigidtouch::bench {
namespace {

using ModelPtr = std::unique_ptr<mjModel, void (*)(mjModel*)>;

ModelPtr Load(const std::string& file) {
  return LoadMjcf(std::string(RIGIDTOUCH_SCENES) + "/" + file);
}

// positions and sizes are written with at most three decimals, so 1e-12 m only absorbs the
// decimal-to-binary rounding; inertias are MuJoCo's own arithmetic on those values
constexpr double kTolerance = 1e-12;

void ExpectCommonSetup(const mjModel& model) {
  EXPECT_EQ(model.opt.timestep, 0.001);
  EXPECT_EQ(model.opt.gravity[0], 0.0);
  EXPECT_EQ(model.opt.gravity[1], 0.0);
  EXPECT_EQ(model.opt.gravity[2], -9.81);
  // the static floor: a plane geom of the world body at z = 0
  const int floor = mj_name2id(&model, mjOBJ_GEOM, "floor");
  ASSERT_GE(floor, 0);
  EXPECT_EQ(model.geom_type[floor], mjGEOM_PLANE);
  EXPECT_EQ(model.geom_bodyid[floor], 0);
  EXPECT_EQ(model.geom_pos[3 * floor + 2], 0.0);
  // the tool: a free sphere of radius 5 mm and mass 0.1 kg, inertia 2/5 m r^2 = 1e-6 kg m^2
  const int tool = MjBodyId(model, "tool", "scene");
  ASSERT_EQ(model.body_jntnum[tool], 1);
  EXPECT_EQ(model.jnt_type[model.body_jntadr[tool]], mjJNT_FREE);
  const int tool_geom = model.body_geomadr[tool];
  EXPECT_EQ(model.geom_type[tool_geom], mjGEOM_SPHERE);
  EXPECT_NEAR(model.geom_size[3 * tool_geom], 0.005, kTolerance);
  EXPECT_NEAR(model.body_mass[tool], 0.1, kTolerance);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(model.body_inertia[3 * tool + k], 1e-6, kTolerance);
}

// box_i: a free cube of half-size 25 mm and mass 0.1 kg at `centre`
void ExpectBox(const mjModel& model, int i, const Vec3& centre) {
  const std::string name = "box_" + std::to_string(i);
  const int body = MjBodyId(model, name, "scene");
  ASSERT_EQ(model.body_jntnum[body], 1) << name;
  EXPECT_EQ(model.jnt_type[model.body_jntadr[body]], mjJNT_FREE) << name;
  const int geom = model.body_geomadr[body];
  EXPECT_EQ(model.geom_type[geom], mjGEOM_BOX) << name;
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(model.geom_size[3 * geom + k], 0.025, kTolerance) << name;
    EXPECT_NEAR(model.body_pos[3 * body + k], centre[k], kTolerance) << name;
    // cube inertia m (a^2 + a^2) / 3 with half-size a: 0.1 * 2 * 0.025^2 / 3
    EXPECT_NEAR(model.body_inertia[3 * body + k], 0.1 * 2 * 0.025 * 0.025 / 3, kTolerance) << name;
  }
  EXPECT_NEAR(model.body_mass[body], 0.1, kTolerance) << name;
}

double ToolStartZ(const mjModel& model) {
  return model.body_pos[3 * MjBodyId(model, "tool", "scene") + 2];
}

TEST(SceneFiles, TapIsTheToolAloneAboveTheFloor) {
  const ModelPtr model = Load("tap.xml");
  ExpectCommonSetup(*model);
  EXPECT_EQ(model->nbody, 2);  // world and tool
  EXPECT_NEAR(ToolStartZ(*model), 0.006, kTolerance);
}

TEST(SceneFiles, StackIsTenBoxesAndTheTool) {
  const ModelPtr model = Load("stack.xml");
  ExpectCommonSetup(*model);
  EXPECT_EQ(model->nbody, 12);
  for (int i = 0; i < 10; ++i) ExpectBox(*model, i, Vec3(0, 0, 0.025 + 0.05 * i));
  EXPECT_NEAR(ToolStartZ(*model), 0.506, kTolerance);
}

TEST(SceneFiles, PileIsAFiveByFiveByFourGrid) {
  const ModelPtr model = Load("pile.xml");
  ExpectCommonSetup(*model);
  EXPECT_EQ(model->nbody, 102);
  for (int z = 0; z < 4; ++z) {
    for (int y = 0; y < 5; ++y) {
      for (int x = 0; x < 5; ++x) {
        ExpectBox(*model, x + 5 * y + 25 * z,
                  Vec3(-0.1 + 0.051 * x, -0.1 + 0.051 * y, 0.025 + 0.051 * z));
      }
    }
  }
  EXPECT_NEAR(ToolStartZ(*model), 0.21, kTolerance);
  // room for the settled pile's ~500 contacts (measured) without MuJoCo's contact-full warning
  EXPECT_GE(model->nconmax, 1000);
  EXPECT_GE(model->njmax, 4 * 1000);
}

// the large piles, compiled as rigidtouch and the Bullet adapter compile them (without MuJoCo's
// solver sizes: their mjData alone is 2 GB)
ModelPtr LoadSmall(const std::string& file) {
  char error[1000] = "";
  const std::string path = std::string(RIGIDTOUCH_SCENES) + "/" + file;
  ModelPtr model(io::CompileWithoutSolverSizes(path, error, sizeof(error)), &mj_deleteModel);
  EXPECT_NE(model, nullptr) << error;
  return model;
}

TEST(SceneFiles, LargePilesArePilesBoxesOnTenByTenGrids) {
  for (const int nz : {4, 10, 20}) {
    const std::string file = "pile" + std::to_string(100 * nz) + ".xml";
    const ModelPtr model = LoadSmall(file);
    ASSERT_NE(model, nullptr);
    ExpectCommonSetup(*model);
    EXPECT_EQ(model->nbody, 100 * nz + 2) << file;
    for (int z = 0; z < nz; ++z) {
      for (int y = 0; y < 10; ++y) {
        for (int x = 0; x < 10; ++x) {
          ExpectBox(*model, x + 10 * y + 100 * z,
                    Vec3(-0.2295 + 0.051 * x, -0.2295 + 0.051 * y, 0.025 + 0.051 * z));
        }
      }
    }
    // 2 mm above the top box of column (4, 4), as the pile's tool above its centre column
    const int tool = MjBodyId(*model, "tool", file);
    EXPECT_NEAR(model->body_pos[3 * tool + 0], -0.0255, kTolerance);
    EXPECT_NEAR(model->body_pos[3 * tool + 1], -0.0255, kTolerance);
    EXPECT_NEAR(ToolStartZ(*model), 0.025 + 0.051 * (nz - 1) + 0.025 + 0.002 + 0.005, kTolerance);
  }
}

TEST(BenchmarkScenes, LargeScenesArePile400To2000WithThePilesGate) {
  const std::vector<Scene> scenes = LargeBenchmarkScenes(RIGIDTOUCH_SCENES);
  ASSERT_EQ(scenes.size(), 3u);
  EXPECT_EQ(scenes[0].name, "pile400");
  EXPECT_EQ(scenes[1].name, "pile1000");
  EXPECT_EQ(scenes[2].name, "pile2000");
  for (const Scene& scene : scenes) {
    EXPECT_EQ(scene.kind, SceneKind::kSteady);
    EXPECT_EQ(scene.max_penetration_m, 0.001);
    EXPECT_EQ(scene.tool_force_N, Vec3(0, 0, -2));
    EXPECT_GT(scene.measured_steps, 0);
  }
  EXPECT_THROW(LargeBenchmarkScenes("scenes", 0.0), Error);
}

TEST(SceneFiles, MissingFileThrowsNamingIt) {
  try {
    LoadMjcf("no_such_scene.xml");
    FAIL() << "expected rigidtouch::Error";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("no_such_scene.xml"), std::string::npos);
  }
}

TEST(BenchmarkScenes, FourScenesWithTheirGates) {
  const std::vector<Scene> scenes = BenchmarkScenes(RIGIDTOUCH_SCENES);
  ASSERT_EQ(scenes.size(), 4u);
  EXPECT_EQ(scenes[0].name, "tap");
  EXPECT_EQ(scenes[1].name, "stack");
  EXPECT_EQ(scenes[2].name, "pile");
  EXPECT_EQ(scenes[3].name, "pile-strike");
  for (const Scene& scene : scenes) {
    EXPECT_EQ(scene.tool_force_N, Vec3(0, 0, -2)) << scene.name;
    EXPECT_GE(scene.warmup_steps, 2000) << scene.name;
    EXPECT_GT(scene.measured_steps, 0) << scene.name;
  }
  EXPECT_EQ(scenes[1].watch_body, "box_9");
  EXPECT_EQ(scenes[1].watch_steps, 10000);  // 10 s at h = 1 ms
  EXPECT_EQ(scenes[1].max_watch_displacement_m, 0.001);
  EXPECT_EQ(scenes[2].max_penetration_m, 0.001);
  EXPECT_EQ(scenes[3].kind, SceneKind::kStrike);
  EXPECT_EQ(scenes[3].strike_gap_m, 0.010);
  EXPECT_EQ(scenes[3].strike_speed_mps, 0.3);

  // the strike target is the top box of the centre column: grid (2, 2, 3)
  const ModelPtr pile = Load("pile.xml");
  const int target = MjBodyId(*pile, scenes[3].strike_target, "pile.xml");
  EXPECT_NEAR(pile->body_pos[3 * target + 0], 0.002, kTolerance);
  EXPECT_NEAR(pile->body_pos[3 * target + 1], 0.002, kTolerance);
  EXPECT_NEAR(pile->body_pos[3 * target + 2], 0.178, kTolerance);
}

TEST(BenchmarkScenes, PeerSettingsAreStackingUnlessAskedAndUnknownNamesAreRefused) {
  for (const Scene& scene : BenchmarkScenes(RIGIDTOUCH_SCENES)) {
    EXPECT_EQ(scene.peer_settings, PeerSettings::kStacking) << scene.name;
  }
  EXPECT_EQ(ParsePeerSettings("defaults"), PeerSettings::kDefaults);
  EXPECT_EQ(ParsePeerSettings("stacking"), PeerSettings::kStacking);
  EXPECT_STREQ(PeerSettingsName(PeerSettings::kDefaults), "defaults");
  EXPECT_STREQ(PeerSettingsName(PeerSettings::kStacking), "stacking");
  try {
    ParsePeerSettings("tuned");
    FAIL() << "expected rigidtouch::Error";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("'tuned'"), std::string::npos) << error.what();
  }
}

TEST(BenchmarkScenes, ScaleShortensMeasurementOnlyAndIsChecked) {
  const std::vector<Scene> full = BenchmarkScenes("scenes");
  const std::vector<Scene> tenth = BenchmarkScenes("scenes", 0.1);
  for (std::size_t i = 0; i < full.size(); ++i) {
    EXPECT_EQ(tenth[i].measured_steps, full[i].measured_steps / 10) << full[i].name;
    EXPECT_EQ(tenth[i].warmup_steps, full[i].warmup_steps) << full[i].name;
    EXPECT_EQ(tenth[i].watch_steps, full[i].watch_steps) << full[i].name;
  }
  EXPECT_THROW(BenchmarkScenes("scenes", 0.0), Error);
  EXPECT_THROW(BenchmarkScenes("scenes", 1.5), Error);
}

}  // namespace
}  // namespace rigidtouch::bench

#else
RIGIDTOUCH_BENCH_SKIPPED_TEST(SceneFiles)
#endif
