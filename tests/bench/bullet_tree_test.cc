// The Bullet peer's btMultiBody trees (bench/bullet_tree.h): the links where MuJoCo's kinematics
// put them, a hinged pendulum's period and a damped door's decay against their closed forms, and
// the joint-limit stop.
#include "bench_test_config.h"

#ifdef RIGIDTOUCH_BENCH_ENABLED

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "bench/bullet_engine.h"
#include "bench/mujoco_engine.h"
#include "bench_scenes.h"

namespace rigidtouch::bench {
namespace {

constexpr double kPiTree = 3.14159265358979323846;

Scene WriteTreeScene(const std::string& name, const std::string& mjcf) {
  Scene scene;
  scene.name = name;
  const std::filesystem::path dir = std::filesystem::temp_directory_path() /
                                    ("rigidtouch_bullet_tree_test_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  scene.mjcf_path = (dir / (name + ".xml")).string();
  std::ofstream(scene.mjcf_path) << mjcf;
  return scene;
}

// a scene of one tree body `body` (MJCF text) below the world, and a tool far away in free fall
std::string TreeMjcf(const std::string& body, const std::string& keyframe) {
  return "<mujoco><compiler angle=\"radian\"/><option timestep=\"0.001\" gravity=\"0 0 -9.81\"/>"
         "<worldbody>" +
         body +
         "<body name=\"tool\" pos=\"10 0 0\"><freejoint/><geom type=\"sphere\" size=\"0.005\" "
         "mass=\"0.1\"/></body></worldbody><keyframe><key name=\"initial\" " +
         keyframe + "/></keyframe></mujoco>";
}

// Every link of the shipped scenes' trees starts where MuJoCo's kinematics put its body at the
// keyframe 'initial' (a drawer 0.1 m out, a lever at -0.35 rad, the arm's six hinges): the
// builder's frames, pivot offsets and joint origins are right. Tolerance: single-precision floats.
TEST(BulletTree, LinksStartWhereMujocoPutsThem) {
  const struct {
    const char* file;
    std::vector<const char*> bodies;
  } cases[] = {{"door.xml", {"door"}},
               {"drawer.xml", {"drawer"}},
               {"lever.xml", {"lever"}},
               {"arm.xml", {"turret", "upper_arm", "forearm", "wrist", "hand"}}};
  for (const auto& c : cases) {
    BulletEngine bullet;
    bullet.Load(SceneFor(c.file));
    auto model = LoadMjcf(SceneFor(c.file).mjcf_path);
    mjData* data = mj_makeData(model.get());
    const int key = mj_name2id(model.get(), mjOBJ_KEY, "initial");
    if (key >= 0) mj_resetDataKeyframe(model.get(), data, key);
    mj_forward(model.get(), data);
    for (const char* body : c.bodies) {
      const int id = mj_name2id(model.get(), mjOBJ_BODY, body);
      const Vec3 expected(data->xpos[3 * id], data->xpos[3 * id + 1], data->xpos[3 * id + 2]);
      EXPECT_LT((bullet.BodyPosition(body) - expected).norm(), 2e-6) << c.file << " " << body;
      const Quat q(data->xquat[4 * id], data->xquat[4 * id + 1], data->xquat[4 * id + 2],
                   data->xquat[4 * id + 3]);
      EXPECT_LT(bullet.BodyOrientation(body).angularDistance(q), 2e-6) << c.file << " " << body;
    }
    mj_deleteData(data);
  }
}

// A sphere of 0.2 kg and radius 2 cm hanging 0.5 m below a hinge, released from 0.05 rad: period
// 2 pi sqrt(I / (m g L)), I = 2/5 m r^2 + m L^2 (1.4196 s; the amplitude's correction, 1 + q0^2 /
// 16, is 1.6e-4). Measured between the first and third downward zero crossings; tolerance 0.2%.
TEST(BulletTree, PendulumPeriodMatchesTheClosedForm) {
  const double m = 0.2, r = 0.02, L = 0.5, g = 9.81;
  BulletEngine engine;
  engine.Load(WriteTreeScene(
      "pendulum", TreeMjcf("<body name=\"bob\" pos=\"0 0 2\"><joint name=\"pin\" type=\"hinge\" "
                           "axis=\"0 1 0\"/><geom type=\"sphere\" pos=\"0 0 -0.5\" size=\"0.02\" "
                           "mass=\"0.2\"/></body>",
                           "qpos=\"0.05 10 0 0 1 0 0 0\"")));
  ASSERT_NEAR(engine.JointPosition("pin"), 0.05, 1e-7);
  const double period = 2 * kPiTree * std::sqrt((0.4 * m * r * r + m * L * L) / (m * g * L));
  std::vector<double> crossings;
  double last = engine.JointPosition("pin");
  for (int n = 1; n <= 4000 && crossings.size() < 3; ++n) {
    engine.Step();
    const double q = engine.JointPosition("pin");
    // interpolated time of a downward zero crossing
    if (last > 0 && q <= 0) crossings.push_back(0.001 * (n - 1 + last / (last - q)));
    last = q;
  }
  ASSERT_EQ(crossings.size(), 3u);
  EXPECT_NEAR((crossings[2] - crossings[0]) / 2, period, 0.002 * period);
}

// A 12 kg door panel on a vertical hinge (no gravity torque), damping 2 N m s/rad and armature
// 0.5 kg m^2, opened at 1 rad/s: the explicit damping torque gives w_n = w_0 (1 - h d / I)^n with
// I = the panel's inertia about the hinge plus the armature (3.2584 kg m^2). After 1 s the speed
// is 0.5411 rad/s; without the armature it would be 0.4844, without damping 1. Tolerance 0.2%.
TEST(BulletTree, DampedDoorSlowsAsTheClosedFormWithArmature) {
  BulletEngine engine;
  engine.Load(WriteTreeScene(
      "swing", TreeMjcf("<body name=\"door\" pos=\"0 0 1\"><joint name=\"hinge\" type=\"hinge\" "
                        "axis=\"0 0 1\" damping=\"2\" armature=\"0.5\"/><geom type=\"box\" "
                        "pos=\"0.42 0 0\" size=\"0.4 0.02 0.9\" mass=\"12\"/></body>",
                        "qpos=\"0 10 0 0 1 0 0 0\" qvel=\"1 0 0 0 0 0 0\"")));
  const double inertia = 12.0 / 3 * (0.4 * 0.4 + 0.02 * 0.02) + 12.0 * 0.42 * 0.42 + 0.5;
  for (int n = 0; n < 1000; ++n) engine.Step();
  const btMultiBody& door = *engine.trees().multibodies().at(0);
  const double expected = std::pow(1.0 - 0.001 * 2.0 / inertia, 1000);
  EXPECT_NEAR(door.getJointVel(0), expected, 0.002 * expected);
}

// A hinge spring (stiffness 4 N m/rad, rest -0.6 rad) and a position servo (kp 10 N m/rad,
// target 0.3 rad) on a vertical axis settle where their torques cancel: q = (4 (-0.6) + 10 0.3) /
// 14 = 0.04286 rad; a lower limit at 0.1 rad stops it there instead, within 2 mrad.
TEST(BulletTree, SpringServoAndLimitSettleWhereTheirTorquesCancel) {
  const std::string body =
      "<body name=\"arm\" pos=\"0 0 1\"><joint name=\"j\" type=\"hinge\" axis=\"0 0 1\" "
      "stiffness=\"4\" springref=\"-0.6\" damping=\"1\" %LIMIT%/><geom type=\"capsule\" "
      "fromto=\"0 0 0 0.3 0 0\" size=\"0.02\" mass=\"0.5\"/></body>";
  const std::string actuator = "<actuator><position joint=\"j\" kp=\"10\"/></actuator>";
  for (const bool limited : {false, true}) {
    std::string text = body;
    text.replace(text.find("%LIMIT%"), 7, limited ? "range=\"0.1 1\" limited=\"true\"" : "");
    std::string mjcf = TreeMjcf(text, "qpos=\"0.5 10 0 0 1 0 0 0\" ctrl=\"0.3\"");
    mjcf.insert(mjcf.find("<keyframe>"), actuator);
    BulletEngine engine;
    engine.Load(WriteTreeScene(limited ? "servo_limited" : "servo", mjcf));
    for (int n = 0; n < 3000; ++n) engine.Step();
    const double expected = limited ? 0.1 : (4 * -0.6 + 10 * 0.3) / 14.0;
    EXPECT_NEAR(engine.JointPosition("j"), expected, limited ? 2e-3 : 1e-4) << limited;
  }
}

// A body with two hinges (anchors apart, axes crossed) below a slide, each away from 0 in the
// keyframe: the chain of links reproduces MuJoCo's composition of a body's joints in order.
TEST(BulletTree, BodyWithTwoJointsComposesThemInOrder) {
  const Scene scene = WriteTreeScene(
      "two_joints",
      TreeMjcf("<body name=\"carriage\" pos=\"0.1 0 1\" euler=\"0.2 0 0\"><joint name=\"s\" "
               "type=\"slide\" axis=\"1 0 0\"/><geom type=\"box\" size=\"0.05 0.05 0.05\"/>"
               "<body name=\"wrist\" pos=\"0 0 -0.2\" euler=\"0 0.3 0\"><joint name=\"a\" "
               "axis=\"1 0 0\" pos=\"0 0 0.03\"/><joint name=\"b\" axis=\"0 1 0.5\" "
               "pos=\"0.02 0 0\"/><geom type=\"capsule\" fromto=\"0 0 0 0.1 0.02 -0.15\" "
               "size=\"0.02\"/></body></body>",
               "qpos=\"0.07 0.4 -0.7 10 0 0 1 0 0 0\""));
  BulletEngine bullet;
  bullet.Load(scene);
  EXPECT_NEAR(bullet.JointPosition("b"), -0.7, 1e-6);
  auto model = LoadMjcf(scene.mjcf_path);
  mjData* data = mj_makeData(model.get());
  mj_resetDataKeyframe(model.get(), data, 0);
  mj_forward(model.get(), data);
  for (const char* body : {"carriage", "wrist"}) {
    const int id = mj_name2id(model.get(), mjOBJ_BODY, body);
    const Vec3 expected(data->xpos[3 * id], data->xpos[3 * id + 1], data->xpos[3 * id + 2]);
    EXPECT_LT((bullet.BodyPosition(body) - expected).norm(), 2e-6) << body;
    const Quat q(data->xquat[4 * id], data->xquat[4 * id + 1], data->xquat[4 * id + 2],
                 data->xquat[4 * id + 3]);
    EXPECT_LT(bullet.BodyOrientation(body).angularDistance(q), 2e-6) << body;
  }
  mj_deleteData(data);
}

// A tree below a free body (a floating base, as MuJoCo's humanoid) is refused with the bodies'
// names rather than built wrong.
TEST(BulletTree, TreeBelowAFreeBodyIsRefused) {
  BulletEngine engine;
  const Scene scene = WriteTreeScene(
      "floating", TreeMjcf("<body name=\"torso\" pos=\"0 0 1\"><freejoint/><geom "
                           "type=\"sphere\" size=\"0.1\"/><body name=\"thigh\" pos=\"0 0 -0.2\">"
                           "<joint type=\"hinge\" axis=\"1 0 0\"/><geom type=\"sphere\" "
                           "size=\"0.05\"/></body></body>",
                           "qpos=\"0 0 1 1 0 0 0 0 10 0 0 1 0 0 0\""));
  try {
    engine.Load(scene);
    ADD_FAILURE() << "a tree below a free body must be refused";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("body 'thigh' hangs from the free body 'torso'"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace rigidtouch::bench

#else
RIGIDTOUCH_BENCH_SKIPPED_TEST(BulletTree)
#endif
