// The Bullet peer's btMultiBody trees (bench/bullet_tree.h): the links where MuJoCo's kinematics
// put them, a hinged pendulum's period and a damped door's decay against their closed forms, the
// joint-limit stop, and a floating base with welded bodies (as MuJoCo's humanoid) against MuJoCo.
#include "bench_test_config.h"

#ifdef RIGIDTOUCH_BENCH_ENABLED

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
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

// A floating tree as MuJoCo's humanoid has: a free root body (its centre of mass off its origin)
// with a body welded to it (no joint: merged into the base) and an arm on a hinge ending in a
// welded hand, the root turned and moving, the hinge bent. The base's pose and twist come from the
// free joint's qpos and qvel, the welded bodies' masses and inertias join their parents'.
std::string FloatingTreeMjcf(double gravity) {
  return "<mujoco><compiler angle=\"radian\"/><option timestep=\"0.001\" gravity=\"0 0 " +
         std::to_string(gravity) +
         "\"/><worldbody><body name=\"base\" pos=\"0 0 1\" euler=\"0.3 -0.2 0.5\"><freejoint "
         "name=\"root\"/><geom type=\"box\" pos=\"0.05 0.02 0\" size=\"0.1 0.06 0.04\" "
         "mass=\"2\"/><body name=\"cap\" pos=\"0 0 0.08\" euler=\"0 0.4 0\"><geom "
         "type=\"sphere\" pos=\"0.02 0 0\" size=\"0.03\" mass=\"0.5\"/></body><body name=\"arm\" "
         "pos=\"0.15 0 0\"><joint name=\"elbow\" axis=\"0 1 0.3\" pos=\"-0.02 0 0\"/><geom "
         "type=\"capsule\" fromto=\"0 0 0 0.2 0 0\" size=\"0.02\" mass=\"0.8\"/><body "
         "name=\"hand\" pos=\"0.22 0 0\"><geom type=\"sphere\" size=\"0.03\" mass=\"0.3\"/>"
         "</body></body></body><body name=\"tool\" pos=\"10 0 0\"><freejoint/><geom "
         "type=\"sphere\" size=\"0.005\" mass=\"0.1\"/></body></worldbody><keyframe><key "
         "name=\"initial\" qpos=\"0.1 -0.2 2 0.923380517 0.102597835 -0.307793506 0.205195670 "
         "0.4 10 0 0 1 0 0 0\" qvel=\"0.3 -0.2 0.1 1.5 -2 0.7 3 0 0 0 0 0 0\"/></keyframe>"
         "</mujoco>";
}

// every body's pose in Bullet against MuJoCo's kinematics at `data`'s qpos (mj_step leaves xpos
// and xquat at the step's start: they are recomputed here)
void ExpectBodiesWhereMujocoHasThem(const BulletEngine& bullet, const mjModel& model, mjData& data,
                                    double position_m, double angle_rad, const char* what) {
  mj_kinematics(&model, &data);
  for (const char* body : {"base", "cap", "arm", "hand"}) {
    const int id = mj_name2id(&model, mjOBJ_BODY, body);
    const Vec3 x(data.xpos[3 * id], data.xpos[3 * id + 1], data.xpos[3 * id + 2]);
    const Quat q(data.xquat[4 * id], data.xquat[4 * id + 1], data.xquat[4 * id + 2],
                 data.xquat[4 * id + 3]);
    EXPECT_LT((bullet.BodyPosition(body) - x).norm(), position_m) << what << " " << body;
    EXPECT_LT(bullet.BodyOrientation(body).angularDistance(q), angle_rad) << what << " " << body;
  }
}

// At the keyframe every body starts where MuJoCo's kinematics put it (the welded ones too), and
// the base's mass is the root's plus the welded cap's (the arm's link, the arm's plus the hand's).
// Tolerance: single-precision floats.
TEST(BulletTree, FloatingTreeStartsWhereMujocoPutsIt) {
  const Scene scene = WriteTreeScene("floating_start", FloatingTreeMjcf(-9.81));
  BulletEngine bullet;
  bullet.Load(scene);
  auto model = LoadMjcf(scene.mjcf_path);
  mjData* data = mj_makeData(model.get());
  mj_resetDataKeyframe(model.get(), data, 0);
  ExpectBodiesWhereMujocoHasThem(bullet, *model, *data, 2e-6, 2e-6, "start");
  mj_deleteData(data);
  const btMultiBody& tree = *bullet.trees().multibodies().at(0);
  EXPECT_FALSE(tree.hasFixedBase());
  EXPECT_NEAR(tree.getBaseMass(), 2.5, 1e-6);
  ASSERT_EQ(tree.getNumLinks(), 1);
  EXPECT_NEAR(tree.getLinkMass(0), 1.1, 1e-6);
  EXPECT_NEAR(bullet.JointPosition("elbow"), 0.4, 1e-6);
}

// Dropped with gravity (nothing below it), the tree falls as a free body: its centre of mass
// follows z_n = z_0 + v_0 n h - g h^2 n (n + 1) / 2, the semi-implicit Euler step both engines
// take (the continuous z_0 + v_0 t - g t^2 / 2 is 1.5 mm higher after 0.3 s), its horizontal
// velocity constant. The arm's spin moves the base but not the tree's centre of mass, which is the
// one checked. Tolerance 0.1 mm: Bullet integrates the base and the joints, not the centre of mass,
// which so drifts off its line by 0.016 mm here (measured); a wrong g or a lost base velocity is
// millimetres to decimetres off.
TEST(BulletTree, DroppedFloatingTreeFallsAtG) {
  BulletEngine bullet;
  bullet.Load(WriteTreeScene("floating_drop", FloatingTreeMjcf(-9.81)));
  const btMultiBody& tree = *bullet.trees().multibodies().at(0);
  const auto tree_com = [&tree]() {
    const btVector3 base = tree.getBasePos();
    Vec3 moment = tree.getBaseMass() * Vec3(base.x(), base.y(), base.z());
    double mass = tree.getBaseMass();
    for (int i = 0; i < tree.getNumLinks(); ++i) {
      // the collider's pose is the link's after the step (the cached one is from its start)
      const btVector3 x = tree.getLink(i).m_collider->getWorldTransform().getOrigin();
      moment += tree.getLinkMass(i) * Vec3(x.x(), x.y(), x.z());
      mass += tree.getLinkMass(i);
    }
    return Vec3(moment / mass);
  };
  const Vec3 start = tree_com();
  Vec3 start_velocity = Vec3::Zero();
  const int n = 300;
  const double g = 9.81, h = 0.001;
  for (int k = 0; k < n; ++k) {
    bullet.Step();
    if (k == 0) start_velocity = (tree_com() - start) / h + Vec3(0, 0, g * h);
  }
  const Vec3 end = tree_com();
  EXPECT_NEAR(end.z(), start.z() + start_velocity.z() * n * h - g * h * h * n * (n + 1) / 2, 1e-4);
  EXPECT_NEAR(end.x(), start.x() + start_velocity.x() * n * h, 1e-5);
  EXPECT_NEAR(end.y(), start.y() + start_velocity.y() * n * h, 1e-5);
}

// Without gravity, the tree thrown with a twist (linear and angular velocity of the free joint,
// the elbow spinning at 3 rad/s) tumbles as MuJoCo's does: after 0.5 s every body is within 0.5 mm
// and 0.1 mrad of MuJoCo's (two integrators of the same equations at 1 ms: measured 0.11 mm and
// 0.007 mrad). A base velocity in the wrong frame fails it: MuJoCo's angular velocity taken as the
// world's rather than the body's puts the base 12 mm and 0.48 rad off, its linear velocity taken
// as the centre of mass's rather than the body origin's 59 mm off (both measured).
TEST(BulletTree, FloatingTreeTumblesAsInMujoco) {
  const Scene scene = WriteTreeScene("floating_tumble", FloatingTreeMjcf(0.0));
  BulletEngine bullet;
  bullet.Load(scene);
  auto model = LoadMjcf(scene.mjcf_path);
  mjData* data = mj_makeData(model.get());
  mj_resetDataKeyframe(model.get(), data, 0);
  for (int k = 0; k < 500; ++k) {
    bullet.Step();
    mj_step(model.get(), data);
  }
  ExpectBodiesWhereMujocoHasThem(bullet, *model, *data, 5e-4, 1e-4, "after 0.5 s");
  mj_deleteData(data);
}

// A floating base restored from its snapshot steps as it did from it: the base's pose and twist
// are part of the snapshot (the joints' were). Tolerance: floats (no contacts here, so nothing
// else in Bullet carries over).
TEST(BulletTree, RestoredFloatingBaseStepsAsFromTheSnapshot) {
  BulletEngine bullet;
  bullet.Load(WriteTreeScene("floating_restore", FloatingTreeMjcf(-9.81)));
  for (int k = 0; k < 100; ++k) bullet.Step();
  bullet.SaveSnapshot();
  bullet.Step();
  const Vec3 x = bullet.BodyPosition("hand");
  const Quat q = bullet.BodyOrientation("base");
  for (int k = 0; k < 100; ++k) bullet.Step();
  bullet.RestoreSnapshot();
  bullet.Step();
  EXPECT_LT((bullet.BodyPosition("hand") - x).norm(), 1e-6);
  EXPECT_LT(bullet.BodyOrientation("base").angularDistance(q), 1e-6);
}

// A root body welded to the world (no joint) with a hinged body below it: the root is the
// multibody's fixed base at its pose (its geoms static), the hinged body a link; both start where
// MuJoCo puts them and the root stays there while the link swings. Tolerance: floats.
TEST(BulletTree, RootWeldedToTheWorldIsAFixedBase) {
  const Scene scene = WriteTreeScene(
      "welded_root",
      TreeMjcf("<body name=\"stand\" pos=\"0.2 0 1\" euler=\"0 0 0.3\"><geom type=\"box\" "
               "size=\"0.05 0.05 0.05\"/><body name=\"flap\" pos=\"0 0 -0.1\"><joint "
               "name=\"pin\" axis=\"1 0 0\"/><geom type=\"capsule\" fromto=\"0 0 0 0 0.2 0\" "
               "size=\"0.02\" mass=\"0.3\"/></body></body>",
               "qpos=\"0.3 10 0 0 1 0 0 0\""));
  BulletEngine bullet;
  bullet.Load(scene);
  const btMultiBody& tree = *bullet.trees().multibodies().at(0);
  EXPECT_TRUE(tree.hasFixedBase());
  EXPECT_EQ(tree.getNumLinks(), 1);
  auto model = LoadMjcf(scene.mjcf_path);
  mjData* data = mj_makeData(model.get());
  mj_resetDataKeyframe(model.get(), data, 0);
  mj_kinematics(model.get(), data);
  for (const char* body : {"stand", "flap"}) {
    const int id = mj_name2id(model.get(), mjOBJ_BODY, body);
    const Vec3 x(data->xpos[3 * id], data->xpos[3 * id + 1], data->xpos[3 * id + 2]);
    EXPECT_LT((bullet.BodyPosition(body) - x).norm(), 2e-6) << body;
  }
  const Vec3 stand = bullet.BodyPosition("stand");
  for (int k = 0; k < 200; ++k) bullet.Step();
  EXPECT_LT((bullet.BodyPosition("stand") - stand).norm(), 1e-9);
  EXPECT_LT(bullet.JointPosition("pin"), 0.25);  // it swung down from 0.3 rad
  mj_deleteData(data);
}

// Contacts between the links of one tree follow MuJoCo's filter: a chain upper - lower - tip whose
// tip folds back onto upper, with two more bodies below tip that overlap upper too: `ghost`
// (contype and conaffinity 2 against upper's 1) and `pin` (an <exclude> with upper). Lower
// overlaps upper at their joint (parent and child: no contact). The body pairs in contact after
// one step are MuJoCo's: upper with tip only.
TEST(BulletTree, ContactsInsideATreeFollowMujocosFilter) {
  std::string mjcf = TreeMjcf(
      "<body name=\"upper\" pos=\"0 0 1\"><joint type=\"hinge\" axis=\"0 1 0\"/><geom "
      "type=\"capsule\" fromto=\"0 0 0 0.3 0 0\" size=\"0.03\"/><body name=\"lower\" "
      "pos=\"0.3 0 0\"><joint type=\"hinge\" axis=\"0 1 0\"/><geom type=\"capsule\" "
      "fromto=\"0 0 0 0 0 -0.2\" size=\"0.03\"/><body name=\"tip\" pos=\"0 0 -0.2\"><joint "
      "type=\"hinge\" axis=\"0 1 0\"/><geom type=\"sphere\" pos=\"-0.25 0 0.2\" size=\"0.04\"/>"
      "<body name=\"ghost\"><joint type=\"hinge\" axis=\"0 1 0\"/><geom type=\"sphere\" "
      "pos=\"-0.15 0 0.2\" size=\"0.04\" contype=\"2\" conaffinity=\"2\"/></body><body "
      "name=\"pin\"><joint type=\"hinge\" axis=\"0 1 0\"/><geom type=\"sphere\" pos=\"-0.1 0 "
      "0.2\" size=\"0.04\"/></body></body></body></body>",
      "qpos=\"0 0 0 0 0 10 0 0 1 0 0 0\"");
  mjcf.insert(mjcf.find("<keyframe>"),
              "<contact><exclude body1=\"upper\" body2=\"pin\"/></contact>");
  const Scene scene = WriteTreeScene("self_contact", mjcf);
  auto model = LoadMjcf(scene.mjcf_path);
  mjData* data = mj_makeData(model.get());
  mj_resetDataKeyframe(model.get(), data, 0);
  mj_forward(model.get(), data);
  std::set<std::string> mujoco_pairs;
  for (int c = 0; c < data->ncon; ++c) {
    std::string a = mj_id2name(model.get(), mjOBJ_BODY, model->geom_bodyid[data->contact[c].geom1]);
    std::string b = mj_id2name(model.get(), mjOBJ_BODY, model->geom_bodyid[data->contact[c].geom2]);
    mujoco_pairs.insert(std::min(a, b) + "-" + std::max(a, b));
  }
  mj_deleteData(data);
  BulletEngine bullet;
  bullet.Load(scene);
  bullet.Step();
  std::set<std::string> bullet_pairs;
  const btDispatcher& dispatcher = *bullet.world()->getDispatcher();
  const char* names[] = {"upper", "lower", "tip", "ghost", "pin"};
  for (int m = 0; m < dispatcher.getNumManifolds(); ++m) {
    const btPersistentManifold* manifold =
        const_cast<btDispatcher&>(dispatcher).getManifoldByIndexInternal(m);
    if (manifold->getNumContacts() == 0) continue;
    std::string a, b;
    for (const char* name : names) {
      if (bullet.trees().Collider(name) == manifold->getBody0()) a = name;
      if (bullet.trees().Collider(name) == manifold->getBody1()) b = name;
    }
    bullet_pairs.insert(std::min(a, b) + "-" + std::max(a, b));
  }
  EXPECT_EQ(mujoco_pairs, std::set<std::string>{"tip-upper"});
  EXPECT_EQ(bullet_pairs, mujoco_pairs);
}

// A ball joint is refused with the joint's and body's names rather than built wrong.
TEST(BulletTree, BallJointIsRefused) {
  BulletEngine engine;
  const Scene scene = WriteTreeScene(
      "ball", TreeMjcf("<body name=\"torso\" pos=\"0 0 1\"><freejoint/><geom "
                       "type=\"sphere\" size=\"0.1\"/><body name=\"thigh\" pos=\"0 0 -0.2\">"
                       "<joint name=\"hip\" type=\"ball\"/><geom type=\"sphere\" "
                       "size=\"0.05\"/></body></body>",
                       "qpos=\"0 0 1 1 0 0 0 1 0 0 0 10 0 0 1 0 0 0\""));
  try {
    engine.Load(scene);
    ADD_FAILURE() << "a ball joint must be refused";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("joint 'hip' of body 'thigh' is a ball joint"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace rigidtouch::bench

#else
RIGIDTOUCH_BENCH_SKIPPED_TEST(BulletTree)
#endif
