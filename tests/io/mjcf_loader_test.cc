#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "rigidtouch/rigidtouch.h"
#include "test_util.h"

namespace rigidtouch {
namespace {

using test::TestScene;

std::string LoadError(const std::string& path, const LoadOptions& options = {}) {
  try {
    LoadModel(path, options);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(MjcfLoaderTest, CopiesMassInertiaAndToolFromMuJoCo) {
  const Model m = LoadModel(TestScene("box_plane.xml"), {});
  ASSERT_EQ(m.bodies.size(), 2u);
  EXPECT_EQ(m.bodies[m.tool].name, "tool");
  const BodyModel& box = m.bodies[0];
  EXPECT_DOUBLE_EQ(box.mass_kg, 0.1);
  // solid cube of side a = 0.05: I = m a^2 / 6 (MuJoCo's compiler, to rounding)
  EXPECT_NEAR(box.inertia_kgm2.x(), 0.1 * 0.05 * 0.05 / 6.0, 1e-12);
  EXPECT_DOUBLE_EQ(m.timestep_s, 0.001);
  EXPECT_NEAR(m.initial[0].x_W.z(), 0.025, 1e-12);
  EXPECT_EQ(m.geoms[0].type, GeomType::kPlane);
  EXPECT_EQ(m.geoms[0].body, -1);
  EXPECT_DOUBLE_EQ(m.geoms[0].friction, 0.5);
}

TEST(MjcfLoaderTest, KeyframeInitialSetsPositionsAndVelocities) {
  const Model m = LoadModel(TestScene("two_spheres.xml"), {});
  EXPECT_NEAR(m.initial[0].v_W.x(), 0.5, 1e-12);
  EXPECT_NEAR(m.initial[1].v_W.x(), -0.2, 1e-12);
  EXPECT_NEAR(m.initial[1].x_W.x(), 0.0105, 1e-12);
}

TEST(MjcfLoaderTest, ToolFlagAndTimestepOverride) {
  LoadOptions o;
  o.tool_name = "box";
  o.timestep_s = 0.0005;
  const Model m = LoadModel(TestScene("box_plane.xml"), o);
  EXPECT_EQ(m.bodies[m.tool].name, "box");
  EXPECT_DOUBLE_EQ(m.timestep_s, 0.0005);
}

TEST(MjcfLoaderTest, MalformedXmlGivesMuJoCoMessageWithFileAndLine) {
  const std::string e = LoadError(TestScene("malformed.xml"));
  EXPECT_NE(e.find("malformed.xml"), std::string::npos) << e;
  // MuJoCo (tinyxml2) reports the line of the mismatched element: the unclosed geom on line 5
  EXPECT_NE(e.find("Line number=5"), std::string::npos) << e;
}

TEST(MjcfLoaderTest, MissingFileIsNamed) {
  const std::string e = LoadError("no/such/scene.xml");
  EXPECT_NE(e.find("no/such/scene.xml"), std::string::npos) << e;
}

TEST(MjcfLoaderTest, CylinderGeomLoads) {
  // refused before issue 16; now collided through MuJoCo's pair functions (mjcf_coverage_test.cc)
  const Model m = LoadModel(TestScene("cylinder.xml"), {});
  EXPECT_EQ(m.geoms[1].type, GeomType::kMesh);  // collided by MuJoCo, as meshes are
  EXPECT_EQ(m.geoms[1].mj_type, 5);             // mjGEOM_CYLINDER
  EXPECT_EQ(m.geoms[1].name, "can");
}

TEST(MjcfLoaderTest, UnsupportedJointNamesTheBody) {
  const std::string e = LoadError(TestScene("hinge.xml"));
  EXPECT_NE(e.find("'tool'"), std::string::npos) << e;
  EXPECT_NE(e.find("freejoint"), std::string::npos) << e;
}

TEST(MjcfLoaderTest, NoToolBodyNamesWhatWasLookedFor) {
  LoadOptions o;
  o.tool_name = "stylus";
  const std::string e = LoadError(TestScene("box_plane.xml"), o);
  EXPECT_NE(e.find("'stylus'"), std::string::npos) << e;
  EXPECT_NE(e.find("box, tool"), std::string::npos) << e;  // lists the candidates
}

struct BadParam {
  const char* name;
  void (*set)(LoadOptions&);
  const char* expected;
};

TEST(MjcfLoaderTest, OutOfRangeParametersNameParameterAndRange) {
  const BadParam cases[] = {
      {"stiffness_N_per_m", [](LoadOptions& o) { o.contact.stiffness_N_per_m = -1; }, ">= 0"},
      {"damping_Ns_per_m", [](LoadOptions& o) { o.contact.damping_Ns_per_m = NAN; }, ">= 0"},
      {"restitution",
       [](LoadOptions& o) {
         o.render.renderer = RendererKind::kImpulse;
         o.render.restitution = 1.5;
       },
       "0 <= e <= 1"},
      {"t_collision_s", [](LoadOptions& o) { o.render.t_collision_s = 0.2; }, "0.1 s"},
      {"timestep_s", [](LoadOptions& o) { o.timestep_s = INFINITY; }, "h <= 0.1 s"},
      {"frequency_hz", [](LoadOptions& o) { o.render.frequency_hz = 5.0; }, "[1/t_c, 1/h]"},
      {"max_force_N", [](LoadOptions& o) { o.device.limits.max_force_N = -3; }, ">= 0 N"},
      {"friction_static",
       [](LoadOptions& o) {
         o.contact.friction_static = 0.2;
         o.contact.friction_kinetic = 0.4;
       },
       ">= friction_kinetic"},
  };
  for (const BadParam& c : cases) {
    LoadOptions o;
    c.set(o);
    const std::string e = LoadError(TestScene("sphere_plane.xml"), o);
    EXPECT_NE(e.find(c.name), std::string::npos) << c.name << ": " << e;
    EXPECT_NE(e.find(c.expected), std::string::npos) << c.name << ": " << e;
  }
}

TEST(MjcfLoaderTest, TrainRequiresPerfectlyPlasticCollisions) {
  LoadOptions o;
  o.render.renderer = RendererKind::kTrain;
  o.render.restitution = 0.5;
  const std::string e = LoadError(TestScene("sphere_plane.xml"), o);
  EXPECT_NE(e.find("restitution"), std::string::npos) << e;
  EXPECT_NE(e.find("perfectly plastic"), std::string::npos) << e;
  o.render.renderer = RendererKind::kImpulse;  // allowed with the single impulse
  EXPECT_EQ(LoadError(TestScene("sphere_plane.xml"), o), "");
}

// a tool sphere above a floor, with the parts the bounds tests change
std::string BoundsScene(const std::string& option, const std::string& tool_attrs,
                        const std::string& key, const std::string& extra_body = "") {
  return "<mujoco><option " + option +
         "/><worldbody><geom name=\"floor\" type=\"plane\" size=\"1 1 0.1\"/>"
         "<body name=\"tool\" pos=\"0 0 0.1\"><freejoint/><geom name=\"tip\" type=\"sphere\" " +
         tool_attrs + "/></body>" + extra_body + "</worldbody>" + key + "</mujoco>";
}

std::string BoundsError(const std::string& xml) {
  return LoadError(test::WriteTempFile("bounds.xml", xml));
}

TEST(MjcfLoaderTest, SaneSceneLoads) {
  EXPECT_EQ(BoundsError(BoundsScene("gravity=\"0 0 -9.81\"", "size=\"0.01\" mass=\"0.1\"", "")),
            "");
}

// the scene's own time step out of range is refused naming the file and the element (Configure
// named only the parameter); a step the caller gives instead is used
TEST(MjcfLoaderTest, ASceneTimestepOutOfRangeNamesTheFileAndElement) {
  const std::string tool = "size=\"0.01\" mass=\"0.1\"";
  for (const std::string h : {"0.5", "1e-9"}) {
    const std::string path =
        test::WriteTempFile("timestep.xml", BoundsScene("timestep=\"" + h + "\"", tool, ""));
    const std::string e = LoadError(path);
    EXPECT_NE(e.find("scene file '" + path + "': <option timestep=\""), std::string::npos) << e;
    EXPECT_NE(e.find("is out of range: valid 1e-06 to 0.1 s"), std::string::npos) << e;
  }
  LoadOptions o;
  o.timestep_s = 0.001;
  const Model m =
      LoadModel(test::WriteTempFile("timestep.xml", BoundsScene("timestep=\"0.5\"", tool, "")), o);
  EXPECT_EQ(m.timestep_s, 0.001);
}

// a number the file gives that is not finite is refused before MuJoCo compiles it (MuJoCo 2.2.2
// warns about a NaN and uses its default, and keeps an infinity), naming the line, element and
// attribute; names and references that read like numbers are text
TEST(MjcfLoaderTest, NonFiniteNumbersInTheFileAreRefusedNamingElementAndAttribute) {
  const std::string tool = "size=\"0.01\" mass=\"0.1\"";
  struct Case {
    std::string xml, element, attribute, value;
  };
  const std::vector<Case> cases = {
      {BoundsScene("", "size=\"0.01\" mass=\"nan\"", ""), "geom", "mass", "nan"},
      {BoundsScene("", "size=\"NaN\" mass=\"0.1\"", ""), "geom", "size", "NaN"},
      {BoundsScene("", tool + " pos=\"0 inf 0\"", ""), "geom", "pos", "0 inf 0"},
      {BoundsScene("", tool + " quat=\"1 0 0 -Infinity\"", ""), "geom", "quat", "1 0 0 -Infinity"},
      {BoundsScene("", tool + " friction=\"1e999 0.005 0.0001\"", ""), "geom", "friction",
       "1e999 0.005 0.0001"},
      {BoundsScene("timestep=\"nan\"", tool, ""), "option", "timestep", "nan"},
  };
  for (const Case& c : cases) {
    const std::string path = test::WriteTempFile("nonfinite.xml", c.xml);
    EXPECT_EQ(LoadError(path), "scene file '" + path + "' line 1: <" + c.element + "> attribute " +
                                   c.attribute + "=\"" + c.value +
                                   "\" is not a finite number (MuJoCo would replace it with its "
                                   "default or keep the infinity); give a finite value");
  }
  // in a file the scene includes, named with its own line
  const std::string part =
      test::WriteTempFile("nonfinite_part.xml",
                          "<mujoco>\n<worldbody>\n<geom type=\"box\" size=\"1 1 inf\"/>\n"
                          "</worldbody>\n</mujoco>");
  const std::string main =
      test::WriteTempFile("nonfinite_main.xml", BoundsScene("", tool, "", "") +
                                                    "<!-- size=\"nan\" in a comment is text -->");
  std::string with_include = BoundsScene("", tool, "");
  with_include.insert(
      with_include.find("<worldbody>"),
      "<include file=\"" + std::filesystem::path(part).filename().string() + "\"/>");
  const std::string including = test::WriteTempFile("nonfinite_including.xml", with_include);
  EXPECT_EQ(
      LoadError(including).rfind("scene file '" + part + "' line 3: <geom> attribute size=", 0), 0u)
      << LoadError(including);
  // a comment, and names that read like numbers, are not numbers of the scene
  EXPECT_EQ(LoadError(main), "");
  EXPECT_EQ(BoundsError(BoundsScene("", tool, "",
                                    "<body name=\"inf\"><geom name=\"nan\" type=\"box\" "
                                    "size=\"0.01 0.01 0.01\" pos=\"0.5 0 0.5\"/></body>")),
            "");
}

TEST(MjcfLoaderTest, AbsurdOrNonFiniteValuesNameTheBodyGeomKeyframeOrOption) {
  const std::string tool = "size=\"0.01\" mass=\"0.1\"";
  // each offset in range, the composed pose not: a static body far out (it loaded)
  const std::string far = BoundsError(
      BoundsScene("", tool, "",
                  "<body pos=\"9000 0 0\"><body pos=\"9000 0 0\"><geom name=\"far\" type=\"box\" "
                  "size=\"0.1 0.1 0.1\"/></body></body>"));
  EXPECT_NE(far.find("the position of geom 'far' in the world[0] is 18000 m, outside the valid "
                     "range [-10000, 10000] m"),
            std::string::npos)
      << far;
  std::string e = BoundsError(BoundsScene("", "size=\"0.01\" mass=\"1e300\"", ""));
  EXPECT_NE(e.find("the mass of body 'tool' is 1e+300 kg, outside the valid range [1e-09, 1e+09]"),
            std::string::npos)
      << e;
  e = BoundsError(BoundsScene("gravity=\"0 0 -1e6\"", tool, ""));
  EXPECT_NE(e.find("option gravity (0 0 -1e+06) m/s^2 is not finite or longer than 1000"),
            std::string::npos)
      << e;
  e = BoundsError(BoundsScene(
      "", tool, "<keyframe><key name=\"initial\" qpos=\"1e300 0 0.1 1 0 0 0\"/></keyframe>"));
  EXPECT_NE(e.find("the position of body 'tool' in keyframe 'initial'[0] is 1e+300 m"),
            std::string::npos)
      << e;
  e = BoundsError(BoundsScene(
      "", tool, "<keyframe><key name=\"initial\" qpos=\"nan 0 0.1 1 0 0 0\"/></keyframe>"));
  // refused before MuJoCo reads it (MuJoCo would replace the NaN)
  EXPECT_NE(e.find("line 1: <key> attribute qpos=\"nan 0 0.1 1 0 0 0\" is not a finite number"),
            std::string::npos)
      << e;
  e = BoundsError(BoundsScene("", tool,
                              "<keyframe><key name=\"initial\" qpos=\"0 0 0.1 1 0 0 0\" "
                              "qvel=\"0 0 -1e9 0 0 0\"/></keyframe>"));
  EXPECT_NE(e.find("the velocity of body 'tool' in keyframe 'initial'[2] is -1e+09 m/s"),
            std::string::npos)
      << e;
  e = BoundsError(BoundsScene(
      "", tool, "", "<geom name=\"wall\" type=\"box\" size=\"1e12 1 1\" pos=\"0 5 0\"/>"));
  EXPECT_NE(e.find("size[0] of geom 'wall' is 1e+12 m"), std::string::npos) << e;
}

TEST(MjcfLoaderTest, BodiesOverlappingAtTheStartNameBothGeomsAndTheDepth) {
  const std::string tool = "size=\"0.01\" mass=\"0.1\"";
  // a ball 5 mm into the tool
  std::string e = BoundsError(
      BoundsScene("gravity=\"0 0 0\"", tool, "",
                  "<body name=\"ball\" pos=\"0.015 0 0.1\"><freejoint/><geom name=\"ball_geom\" "
                  "type=\"sphere\" size=\"0.01\" mass=\"0.1\"/></body>"));
  EXPECT_NE(e.find("geoms 'tip' and 'ball_geom' overlap by 0.005 m at the start"),
            std::string::npos)
      << e;
  // the tool 5 mm into the floor
  e = BoundsError(BoundsScene(
      "", tool, "<keyframe><key name=\"initial\" qpos=\"0 0 0.005 1 0 0 0\"/></keyframe>"));
  EXPECT_NE(e.find("geoms 'floor' and 'tip' overlap by 0.005 m"), std::string::npos) << e;
  // touching within the 1 mm tolerance is a resting contact, not an error
  EXPECT_EQ(
      BoundsError(BoundsScene(
          "", tool, "<keyframe><key name=\"initial\" qpos=\"0 0 0.0095 1 0 0 0\"/></keyframe>")),
      "");
}

}  // namespace
}  // namespace rigidtouch
