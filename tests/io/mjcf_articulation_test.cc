// Articulated trees from MJCF (src/io/mjcf_articulation.cc): what becomes a tree, its links,
// joints, limits, actuators and initial state; each refused input named in its error.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "dynamics/tree.h"
#include "rigidtouch/rigidtouch.h"
#include "test_util.h"

namespace rigidtouch {
namespace {

Model LoadTreeXml(const std::string& xml) {
  LoadOptions o;
  o.tool_name = "none";
  return LoadModel(test::WriteTempFile("articulated.xml", xml), o);
}

std::string TreeXmlError(const std::string& xml) {
  try {
    LoadTreeXml(xml);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

// a world with `body` in it, `after` after the worldbody
std::string World(const std::string& body, const std::string& after = "") {
  return "<mujoco><compiler angle=\"radian\"/><worldbody><geom name=\"floor\" type=\"plane\" "
         "size=\"1 1 0.1\"/>" +
         body + "</worldbody>" + after + "</mujoco>";
}

const char kLink[] = "<geom type=\"box\" size=\"0.05 0.05 0.05\" mass=\"1\"/>";

TEST(MjcfArticulationTest, DoorSceneBecomesTwoTreesWithLinksJointsAndInitialState) {
  const Model m = LoadModel(test::TestScene("articulated/door.xml"), [] {
    LoadOptions o;
    o.tool_name = "none";
    return o;
  }());
  ASSERT_EQ(m.trees.size(), 2u);  // the door (handle welded in) and the drawer
  const ArticulatedTree& door = m.trees[0];
  EXPECT_EQ(door.name, "door");
  ASSERT_EQ(door.link_names.size(), 1u);  // the handle is welded into the door
  ASSERT_EQ(door.joints.size(), 1u);
  EXPECT_EQ(door.joints[0].name, "hinge");
  EXPECT_EQ(door.joints[0].type, JointKind::kHinge);
  EXPECT_TRUE(door.joints[0].limited);
  EXPECT_NEAR(door.joints[0].range_lo_rad_or_m, -100.0 * M_PI / 180.0, 1e-12);  // degrees
  EXPECT_DOUBLE_EQ(door.joints[0].range_hi_rad_or_m, 0.0);
  EXPECT_DOUBLE_EQ(door.initial_qpos[0], -0.5);  // keyframe 'initial'
  EXPECT_DOUBLE_EQ(door.initial_qvel[0], 1.0);
  EXPECT_NEAR(door.dynamics->bodies[0].mass_kg, 10.2, 1e-12);  // panel + handle
  EXPECT_DOUBLE_EQ(m.trees[1].dynamics->joint(0).stiffness, 20.0);
  EXPECT_DOUBLE_EQ(m.trees[1].dynamics->joint(0).spring_ref, -0.1);
  int handle = -1;
  for (int g = 0; g < static_cast<int>(m.geoms.size()); ++g) {
    if (m.geoms[g].name == "handle") handle = g;
  }
  ASSERT_GE(handle, 0);
  EXPECT_EQ(m.geoms[handle].body, -1);
  EXPECT_EQ(m.geoms[handle].tree, 0);
  EXPECT_EQ(m.geoms[handle].link, 0);
  // its world pose at the keyframe: the hinge at (0, 0, 1) turned by -0.5 rad about z
  const Vec3 on_door(0.75, -0.05, 0.0);
  const Vec3 expected = Vec3(0, 0, 1) + Eigen::AngleAxisd(-0.5, Vec3::UnitZ()) * on_door;
  EXPECT_LT((m.geoms[handle].pos_B - expected).norm(), 1e-12);
  EXPECT_FALSE(m.has_tool);
}

TEST(MjcfArticulationTest, ActuatorsAtTheKeyframeControlWithMuJoCosGainsAndClamps) {
  const Model m = LoadModel(test::TestScene("articulated/arm.xml"), [] {
    LoadOptions o;
    o.tool_name = "none";
    return o;
  }());
  ASSERT_EQ(m.trees.size(), 1u);
  const ArticulatedTree& arm = m.trees[0];
  ASSERT_EQ(arm.actuators.size(), 4u);
  const ActuatorModel& shoulder = arm.actuators[1];
  EXPECT_EQ(shoulder.name, "shoulder");
  EXPECT_DOUBLE_EQ(shoulder.gain[0], 200.0);   // position: gain kp
  EXPECT_DOUBLE_EQ(shoulder.bias[1], -200.0);  // bias -kp length
  EXPECT_DOUBLE_EQ(shoulder.ctrl, -0.4);
  EXPECT_TRUE(arm.actuators[2].force_limited);
  EXPECT_DOUBLE_EQ(arm.actuators[2].force_hi, 20.0);
  EXPECT_DOUBLE_EQ(arm.actuators[3].ctrl, 0.5);  // the motor, within its ctrlrange
  EXPECT_EQ(arm.joints[arm.actuators[3].joint].type, JointKind::kSlide);
}

TEST(MjcfArticulationTest, ControlOutsideItsRangeIsClampedAsMuJoCoDoes) {
  const Model m =
      LoadTreeXml(World("<body name=\"b\"><joint name=\"j\"/>" + std::string(kLink) + "</body>",
                        "<actuator><motor name=\"m\" joint=\"j\" ctrlrange=\"-1 1\" "
                        "ctrllimited=\"true\"/></actuator><keyframe><key "
                        "name=\"initial\" ctrl=\"3\"/></keyframe>"));
  EXPECT_DOUBLE_EQ(m.trees[0].actuators[0].ctrl, 1.0);
}

struct Refused {
  const char* name;
  std::string xml;
  std::string expected;
};

// gtest prints a parameter in a failure's message: its name, not its bytes
std::ostream& operator<<(std::ostream& out, const Refused& c) {
  return out << c.name;
}

std::vector<Refused> RefusedInputs() {
  const std::string body = "<body name=\"b\"><joint name=\"j\"/>" + std::string(kLink) + "</body>";
  return {
      {"free_root_stiffness",
       World("<body name=\"b\"><joint name=\"j\" type=\"free\" stiffness=\"3\"/>" +
             std::string(kLink) + "<body name=\"c\" pos=\"0.2 0 0\"><joint name=\"k\"/>" +
             std::string(kLink) + "</body></body>"),
       "<joint> 'j' of body 'b' is a free joint with stiffness=\"3\""},
      {"ball_keyframe_beyond_range",
       World("<body name=\"b\"><joint name=\"j\" type=\"ball\" limited=\"true\" "
             "range=\"0 0.5\"/>" +
                 std::string(kLink) + "</body>",
             "<keyframe><key name=\"initial\" qpos=\"0.8775825619 0.4794255386 0 0\"/>"
             "</keyframe>"),
       "<joint> 'j' of body 'b': its rotation of 1 rad in keyframe 'initial' is beyond its "
       "range 0.5 rad"},
      {"range_min_above_max",
       World("<body name=\"b\"><joint name=\"j\" limited=\"true\" range=\"1 -1\"/>" +
             std::string(kLink) + "</body>"),
       "range[0] should be smaller than range[1] in joint 'j'"},  // MuJoCo's compiler
      {"keyframe_outside_range",
       World("<body name=\"b\"><joint name=\"j\" limited=\"true\" range=\"-0.5 0.5\"/>" +
                 std::string(kLink) + "</body>",
             "<keyframe><key name=\"initial\" qpos=\"0.6\"/></keyframe>"),
       "<joint> 'j' of body 'b': its position 0.6 in keyframe 'initial' is outside its range"},
      {"activation_state",
       World(body,
             "<actuator><general name=\"act\" joint=\"j\" dyntype=\"integrator\"/>"
             "</actuator><keyframe><key name=\"initial\" ctrl=\"1\"/></keyframe>"),
       "<actuator> 'act' has activation dynamics"},
      {"activation_state_with_a_bias",
       World(body,
             "<actuator><general name=\"held\" joint=\"j\" dyntype=\"filter\" "
             "biastype=\"affine\" biasprm=\"0 -1 0\"/></actuator>"),
       "<actuator> 'held' has activation dynamics"},
      {"muscle",
       World(body, "<actuator><muscle name=\"mus\" joint=\"j\" lengthrange=\"-1 1\"/></actuator>"),
       "<actuator> 'mus' has activation dynamics"},
      {"user_gain",
       World(body, "<actuator><general name=\"usr\" joint=\"j\" gaintype=\"user\"/></actuator>"),
       "<actuator> 'usr' has a muscle or user gain"},
      {"tendon_transmission",
       World(body,
             "<tendon><fixed name=\"t\"><joint joint=\"j\" coef=\"1\"/></fixed></tendon>"
             "<actuator><motor name=\"pull\" tendon=\"t\"/></actuator>"),
       "<actuator> 'pull' drives a tendon"},
      {"actuator_on_a_ball",
       World("<body name=\"b\"><joint name=\"j\" type=\"ball\"/>" + std::string(kLink) + "</body>",
             "<actuator><motor name=\"twist\" joint=\"j\"/></actuator>"),
       "<actuator> 'twist' drives <joint> 'j' of body 'b'"},
      {"free_joint_below_the_top",
       World("<body name=\"b\"><joint name=\"j\"/>" + std::string(kLink) +
             "<body name=\"loose\" pos=\"0.2 0 0\"><freejoint name=\"f\"/>" + std::string(kLink) +
             "</body></body>"),
       "free joint can only be used on top level"},  // MuJoCo's compiler
      {"equality",
       World(body + "<body name=\"c\" pos=\"0.5 0 0\"><joint name=\"k\"/>" + std::string(kLink) +
                 "</body>",
             "<equality><joint name=\"couple\" joint1=\"j\" joint2=\"k\"/></equality>"),
       "<equality> <joint> 'couple'"},
      {"plane_on_a_link",
       World("<body name=\"b\"><joint name=\"j\"/>" + std::string(kLink) +
             "<geom name=\"flap\" type=\"plane\" size=\"1 1 0.1\"/></body>"),
       "plane and hfield only allowed in static bodies: geom 'flap'"},  // MuJoCo's compiler
  };
}

class RefusedArticulationTest : public ::testing::TestWithParam<Refused> {};

TEST_P(RefusedArticulationTest, ErrorNamesTheElement) {
  const std::string e = TreeXmlError(GetParam().xml);
  EXPECT_NE(e.find(GetParam().expected), std::string::npos) << e;
  EXPECT_NE(e.find("scene file '"), std::string::npos) << e;  // the project's scene-error style
}

INSTANTIATE_TEST_SUITE_P(MjcfArticulation, RefusedArticulationTest,
                         ::testing::ValuesIn(RefusedInputs()),
                         [](const ::testing::TestParamInfo<Refused>& info) {
                           return std::string(info.param.name);
                         });

bool HasWarning(const Model& m, const std::string& text) {
  for (const std::string& w : m.load_warnings) {
    if (w.find(text) != std::string::npos) return true;
  }
  return false;
}

// frictionloss on every joint type of a tree and a ball joint's stiffness are honoured
TEST(MjcfArticulationTest, FrictionlossAndBallStiffnessReachTheTree) {
  const Model m = LoadTreeXml(
      World("<body name=\"b\"><joint name=\"j\" frictionloss=\"1.5\"/>" + std::string(kLink) +
            "<body name=\"c\" pos=\"0.2 0 0\"><joint name=\"k\" type=\"ball\" "
            "stiffness=\"3\" frictionloss=\"0.25\"/>" +
            std::string(kLink) + "</body></body>"));
  ASSERT_EQ(m.trees.size(), 1u);
  const dynamics::TreeModel& tree = *m.trees[0].dynamics;
  EXPECT_DOUBLE_EQ(tree.joint(0).frictionloss, 1.5);
  EXPECT_DOUBLE_EQ(tree.joint(1).frictionloss, 0.25);
  EXPECT_DOUBLE_EQ(tree.joint(1).stiffness, 3.0);
  EXPECT_EQ(tree.friction_dofs, (std::vector<int>{0, 1, 2, 3}));  // the hinge, the ball's three
  EXPECT_TRUE(tree.joint(1).spring_quat.isApprox(Quat::Identity()));
}

// an actuator with activation dynamics that can only ever exert 0 (integrator or filter from
// activation 0 at control 0, no bias) is left out with a warning instead of refused
TEST(MjcfArticulationTest, IdleActuatorWithActivationIsLeftOutWithAWarning) {
  const Model m = LoadTreeXml(
      World("<body name=\"b\"><joint name=\"j\" type=\"slide\"/>" + std::string(kLink) + "</body>",
            "<actuator><motor name=\"push\" joint=\"j\"/><general name=\"state\" joint=\"j\" "
            "dyntype=\"integrator\"/></actuator>"));
  ASSERT_EQ(m.trees[0].actuators.size(), 1u);
  EXPECT_EQ(m.trees[0].actuators[0].name, "push");
  EXPECT_TRUE(HasWarning(m, "<actuator> 'state' has activation dynamics")) << m.load_warnings[0];
}

// <flag constraint="disable"/> with nothing it could turn off here (a link that collides with
// nothing: its bits are 0): warned, not refused
// without a tool and free bodies the flags are honoured, as MuJoCo honours them (the motion is
// checked in tests/engine/disabled_constraints_test.cc), and said so
TEST(MjcfArticulationTest, ConstraintFlagIsHonouredInASceneWithoutATool) {
  const Model m =
      LoadTreeXml(World("<body name=\"b\"><joint name=\"j\" limited=\"true\" range=\"-1 1\"/>" +
                            std::string(kLink) + "</body>",
                        "<option><flag constraint=\"disable\"/></option>"));
  EXPECT_TRUE(HasWarning(m,
                         "<flag constraint=\"disable\"/> honoured as in MuJoCo: no contacts, "
                         "joint limits or frictionloss"));
  EXPECT_FALSE(m.trees[0].joints[0].limited);
}

// with a tool (a free body) the flags would turn the tool's contacts off: refused
TEST(MjcfArticulationTest, ContactFlagIsRefusedWhenTheSceneHasATool) {
  const std::string tool =
      "<body name=\"tool\" pos=\"0.5 0 0.5\"><freejoint/><geom type=\"sphere\" "
      "size=\"0.01\" mass=\"0.1\"/></body>";
  for (const char* flag : {"contact", "constraint"}) {
    try {
      LoadModel(
          test::WriteTempFile(
              "tool_flag.xml",
              World("<body name=\"b\"><joint name=\"j\"/>" + std::string(kLink) + "</body>" + tool,
                    std::string("<option><flag ") + flag + "=\"disable\"/></option>")),
          {});
      FAIL() << flag << " accepted";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("geoms that may collide"), std::string::npos)
          << e.what();
    }
  }
}

// a <contact><pair> of a link and its parent link: the parent filter keeps them apart, so the
// pair is refused rather than said to collide anyway
TEST(MjcfArticulationTest, PairOfALinkAndItsParentIsRefused) {
  try {
    LoadTreeXml(
        World("<body name=\"b\"><joint name=\"j\"/><geom name=\"gb\" type=\"box\" "
              "size=\"0.05 0.05 0.05\" mass=\"1\"/><body name=\"c\" pos=\"0.2 0 0\">"
              "<joint name=\"k\"/><geom name=\"gc\" type=\"box\" size=\"0.05 0.05 0.05\" "
              "mass=\"1\"/></body></body>",
              "<contact><pair name=\"p\" geom1=\"gb\" geom2=\"gc\"/></contact>"));
    FAIL() << "accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("not a body and its parent"), std::string::npos)
        << e.what();
  }
}

// limit softness on many joints: one warning naming three of them and the count of the rest
TEST(MjcfArticulationTest, LimitSoftnessIsOneWarningForManyJoints) {
  std::string chain;
  for (int i = 0; i < 5; ++i) {
    chain += "<body name=\"l" + std::to_string(i) + "\" pos=\"0.2 0 0\"><joint name=\"j" +
             std::to_string(i) + "\" limited=\"true\" range=\"-1 1\" solreflimit=\"0.05 1\"/>" +
             kLink;
  }
  for (int i = 0; i < 5; ++i) chain += "</body>";
  const Model m = LoadTreeXml(World(chain));
  int count = 0;
  for (const std::string& w : m.load_warnings) {
    count += w.find("solreflimit, solimplimit and margin are ignored") != std::string::npos;
  }
  EXPECT_EQ(count, 1);
  EXPECT_TRUE(HasWarning(m, "<joint> 'j2' of body 'l2' and 2 more: solreflimit"));
}

// MuJoCo's humanoid steps at 5 ms, longer than the default train's 4 ms impulse interval: the
// default frequency becomes 1/h with a warning; a frequency the user gave is kept (and refused)
TEST(MjcfArticulationTest, LongSceneTimestepLowersTheDefaultTrainFrequency) {
  const std::string xml =
      World("<body name=\"b\"><joint name=\"j\"/>" + std::string(kLink) + "</body>",
            "<option timestep=\"0.005\"/>");
  const Model m = LoadTreeXml(xml);
  EXPECT_DOUBLE_EQ(m.render.frequency_hz, 200.0);
  EXPECT_TRUE(HasWarning(m, "the train frequency is 1/h = 200 Hz"));
  LoadOptions o;
  o.tool_name = "none";
  o.render.frequency_given = true;
  try {
    LoadModel(test::WriteTempFile("articulated.xml", xml), o);
    ADD_FAILURE() << "a given 250 Hz at h = 5 ms must be refused";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("frequency_hz = 250"), std::string::npos) << e.what();
  }
}

// a zero joint axis: MuJoCo's compiler refuses it first; the error names the scene either way
TEST(MjcfArticulationTest, ZeroAxisIsRefused) {
  const std::string e = TreeXmlError(World("<body name=\"b\"><joint name=\"j\" axis=\"0 0 0\"/>" +
                                           std::string(kLink) + "</body>"));
  EXPECT_NE(e.find("scene file '"), std::string::npos) << e;
  EXPECT_NE(e.find("axis too small in joint 'j'"), std::string::npos) << e;  // MuJoCo's words
}

// a keyframe within 1e-6 of a limit is accepted (MuJoCo prints keyframes to a few digits)
TEST(MjcfArticulationTest, KeyframeWithinTheToleranceOfALimitIsAccepted) {
  const Model m =
      LoadTreeXml(World("<body name=\"b\"><joint name=\"j\" limited=\"true\" "
                        "range=\"-0.5 0.5\"/>" +
                            std::string(kLink) + "</body>",
                        "<keyframe><key name=\"initial\" qpos=\"0.5000005\"/></keyframe>"));
  EXPECT_DOUBLE_EQ(m.trees[0].initial_qpos[0], 0.5000005);
}

}  // namespace
}  // namespace rigidtouch
