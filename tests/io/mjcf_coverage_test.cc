// MJCF coverage (issue 16): welded child bodies merged into their free body, <contact><exclude>,
// condim 1, cylinders and ellipsoids, and the elements rigidtouch refuses or warns about.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include <mujoco/mujoco.h>

#include "cli/cli_util.h"
#include "rigidtouch/rigidtouch.h"
#include "test_util.h"

namespace rigidtouch {
namespace {

using test::TestScene;

std::string CoverageLoadError(const std::string& path) {
  try {
    LoadModel(path, {});
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

Model LoadXml(const std::string& xml, const std::string& name = "scene.xml") {
  return LoadModel(test::WriteTempFile(name, xml), {});
}

std::string XmlError(const std::string& xml) {
  return CoverageLoadError(test::WriteTempFile("refused.xml", xml));
}

void Step(const Model& m, Data& d, double seconds, int* max_contacts = nullptr) {
  const TickInput input;
  const long steps = std::lround(seconds / m.timestep_s);
  for (long s = 0; s < steps; ++s) {
    Tick(m, d, input);
    if (max_contacts != nullptr) *max_contacts = std::max(*max_contacts, d.ncontact);
  }
}

int BodyIndex(const Model& m, const std::string& name) {
  for (std::size_t i = 0; i < m.bodies.size(); ++i) {
    if (m.bodies[i].name == name) return static_cast<int>(i);
  }
  ADD_FAILURE() << "no body " << name;
  return -1;
}

// the body's inertia tensor about its centre of mass, in the MJCF body frame
Mat3 Tensor(const BodyModel& b) {
  const Mat3 R = b.iquat_B.toRotationMatrix();
  return R * b.inertia_kgm2.asDiagonal() * R.transpose();
}

// solid box of mass m and half-sizes h: principal moments about its centre
Vec3 BoxInertia(double m, const Vec3& h) {
  return m / 3.0 *
         Vec3(h.y() * h.y() + h.z() * h.z(), h.x() * h.x() + h.z() * h.z(),
              h.x() * h.x() + h.y() * h.y());
}

void ExpectTensorNear(const Mat3& got, const Mat3& want, double rel) {
  const double scale = want.norm();
  EXPECT_LE((got - want).norm(), rel * scale) << "got\n" << got << "\nwant\n" << want;
}

// ---------------------------------------------------------------------------- welded parts

TEST(MjcfCoverageTest, WeldedChildMergesMassCentreAndInertia) {
  const Model m = LoadModel(TestScene("welded.xml"), {});
  ASSERT_EQ(m.bodies.size(), 2u);  // "fin" is part of "part", not a body of its own
  const BodyModel& b = m.bodies[BodyIndex(m, "part")];
  EXPECT_NEAR(b.mass_kg, 1.5, 1.5e-12);
  // centre of mass: (1 kg * 0 + 0.5 kg * 0.1 m) / 1.5 kg along x
  EXPECT_NEAR(b.ipos_B.x(), 0.1 / 3.0, 1e-12 * 0.1 / 3.0);
  EXPECT_NEAR(b.ipos_B.y(), 0.0, 1e-15);
  EXPECT_NEAR(b.ipos_B.z(), 0.0, 1e-15);
  // base: m/3 (b^2 + c^2, a^2 + c^2, a^2 + b^2) with (a, b, c) = (50, 30, 20) mm; the fin's own
  // moments (40, 20, 10) mm swap x and y under the 90 degree turn; both shifted to the common
  // centre along x by d = -100/3 mm and +200/3 mm: + (0, 1, 1) (1 d1^2 + 0.5 d2^2) = 1/300
  const double shift = 1.0 * 0.01 / 9.0 + 0.5 * 0.04 / 9.0;
  EXPECT_NEAR(shift, 1.0 / 300.0, 1e-15);
  const Vec3 want(0.0013 / 3.0 + 0.5 * 0.0017 / 3.0, 0.0029 / 3.0 + 0.5 * 0.0005 / 3.0 + shift,
                  0.0034 / 3.0 + 0.5 * 0.002 / 3.0 + shift);
  ExpectTensorNear(Tensor(b), Mat3(want.asDiagonal()), 1e-12);
  EXPECT_NEAR(b.inertia_kgm2.sum(), want.sum(), 1e-12 * want.sum());  // the trace
  // the fin's geom is the free body's, 100 mm along x from the base, turned 90 degrees about z
  ASSERT_EQ(m.geoms.size(), 4u);
  const GeomModel& base = m.geoms[1];
  const GeomModel& fin = m.geoms[2];
  EXPECT_EQ(fin.body, base.body);
  const Quat q = b.iquat_B;
  const Vec3 fin_centre = b.ipos_B + q * fin.pos_B;
  EXPECT_NEAR((fin_centre - Vec3(0.1, 0.0, 0.0)).norm(), 0.0, 1e-12);
  const Mat3 fin_axes = (q * fin.quat_B).toRotationMatrix();
  const Mat3 turned = Eigen::AngleAxisd(M_PI / 2.0, Vec3::UnitZ()).toRotationMatrix();
  EXPECT_LE((fin_axes - turned).norm(), 1e-12);
}

TEST(MjcfCoverageTest, WeldedChildAtAnyRotationMatchesTheClosedForm) {
  // the child 0.2 kg box (half-sizes 30, 10, 5 mm) at (20, -40, 30) mm, turned 40 degrees about
  // the unit axis (1, 2, 2) / 3, inside a 0.3 kg cube of half-size 20 mm
  const Model m = LoadXml(
      "<mujoco><worldbody><body name=\"tool\" pos=\"0 0 1\"><freejoint/>"
      "<geom type=\"box\" size=\"0.02 0.02 0.02\" mass=\"0.3\"/>"
      "<body pos=\"0.02 -0.04 0.03\" axisangle=\"1 2 2 40\">"
      "<geom type=\"box\" size=\"0.03 0.01 0.005\" mass=\"0.2\"/></body>"
      "</body></worldbody></mujoco>");
  const BodyModel& b = m.bodies[0];
  const Vec3 p(0.02, -0.04, 0.03);
  const double m1 = 0.3, m2 = 0.2, mass = m1 + m2;
  const Vec3 com = m2 * p / mass;
  const Mat3 R = Eigen::AngleAxisd(40.0 * M_PI / 180.0, Vec3(1, 2, 2) / 3.0).toRotationMatrix();
  auto shift = [](double mi, const Vec3& d) {
    return Mat3(mi * (d.squaredNorm() * Mat3::Identity() - d * d.transpose()));
  };
  const Mat3 want = Mat3(BoxInertia(m1, Vec3(0.02, 0.02, 0.02)).asDiagonal()) + shift(m1, -com) +
                    R * BoxInertia(m2, Vec3(0.03, 0.01, 0.005)).asDiagonal() * R.transpose() +
                    shift(m2, p - com);
  EXPECT_NEAR(b.mass_kg, mass, 1e-12 * mass);
  EXPECT_LE((b.ipos_B - com).norm(), 1e-12 * com.norm());
  ExpectTensorNear(Tensor(b), want, 1e-12);
  EXPECT_NEAR(b.iquat_B.norm(), 1.0, 1e-14);
}

TEST(MjcfCoverageTest, WeldedPartFallsAndRestsAsOneBody) {
  const Model m = LoadModel(TestScene("welded.xml"), {});
  Data d = MakeData(m);
  const int part = BodyIndex(m, "part");
  // free fall for 20 ms (the base's bottom starts 30 mm above the floor): v = g t, no spin
  Step(m, d, 0.02);
  EXPECT_NEAR(d.bodies[part].v_W.z(), -9.81 * 0.02, 1e-9);
  EXPECT_LT(d.bodies[part].w_W.norm(), 1e-12);
  // the centre of mass is over the base's footprint: it lands flat and rests on the base's face,
  // 20 mm up less the penalty compression m g / k
  Step(m, d, 1.5);
  const BodyState& s = d.bodies[part];
  const double sink = 1.5 * 9.81 / m.contact.scene_stiffness_N_per_m;
  EXPECT_NEAR(s.x_W.z(), 0.02 - sink, 1e-4);
  EXPECT_LT(s.v_W.norm(), 1e-3);
  EXPECT_LT(s.w_W.norm(), 1e-2);
  // upright: the body's z axis (principal frame times iquat^-1) is the world's
  const Quat q_W_body = s.q_WB * m.bodies[part].iquat_B.conjugate();
  EXPECT_GT((q_W_body * Vec3::UnitZ()).z(), 1.0 - 1e-6);
}

// ---------------------------------------------------------------------------- exclude

std::string PassScene(const std::string& contact) {
  // two balls, no gravity, the left one moving right at 0.5 m/s through where the right one is
  return "<mujoco><option gravity=\"0 0 0\"/><worldbody>"
         "<body name=\"tool\" pos=\"-0.03 0 0\"><freejoint/>"
         "<geom type=\"sphere\" size=\"0.01\" mass=\"0.1\"/></body>"
         "<body name=\"ball\" pos=\"0.0 0 0\"><freejoint/>"
         "<geom type=\"sphere\" size=\"0.01\" mass=\"0.1\"/></body>"
         "</worldbody>" +
         contact +
         "<keyframe><key name=\"initial\" qpos=\"-0.03 0 0 1 0 0 0 0 0 0 1 0 0 0\" "
         "qvel=\"0.5 0 0 0 0 0 0 0 0 0 0 0\"/></keyframe></mujoco>";
}

TEST(MjcfCoverageTest, ExcludedBodiesPassThroughEachOther) {
  const Model m = LoadXml(PassScene("<contact><exclude body1=\"ball\" body2=\"tool\"/></contact>"));
  ASSERT_EQ(m.excluded_geom_pairs.size(), 1u);
  EXPECT_EQ(m.excluded_geom_pairs[0], std::make_pair(0, 1));  // the two balls' geoms
  Data d = MakeData(m);
  int most = 0;
  Step(m, d, 0.2, &most);  // 100 mm: right through
  EXPECT_EQ(most, 0);
  EXPECT_NEAR(d.bodies[BodyIndex(m, "tool")].v_W.x(), 0.5, 1e-12);
  EXPECT_NEAR(d.bodies[BodyIndex(m, "ball")].v_W.norm(), 0.0, 1e-12);
  // without the exclude they collide
  const Model m2 = LoadXml(PassScene(""));
  EXPECT_TRUE(m2.excluded_geom_pairs.empty());
  Data d2 = MakeData(m2);
  most = 0;
  Step(m2, d2, 0.2, &most);
  EXPECT_GT(most, 0);
  EXPECT_GT(d2.bodies[BodyIndex(m2, "ball")].v_W.x(), 0.1);
}

TEST(MjcfCoverageTest, ExcludeWithTheWorldLetsABodyFallThroughTheFloor) {
  const Model m = LoadXml(
      "<mujoco><worldbody><geom name=\"floor\" type=\"plane\" size=\"1 1 0.1\"/>"
      "<body name=\"tool\" pos=\"0 0 0.011\"><freejoint/>"
      "<geom type=\"sphere\" size=\"0.01\" mass=\"0.1\"/></body></worldbody>"
      "<contact><exclude body1=\"world\" body2=\"tool\"/></contact></mujoco>");
  ASSERT_EQ(m.excluded_geom_pairs.size(), 1u);
  EXPECT_EQ(m.excluded_geom_pairs[0], std::make_pair(0, 1));  // the floor and the tool's sphere
  Data d = MakeData(m);
  int most = 0;
  Step(m, d, 0.3, &most);
  EXPECT_EQ(most, 0);
  EXPECT_LT(d.bodies[0].x_W.z(), -0.3);
}

// every static MJCF body is static geometry to rigidtouch (body -1), but an exclude names one of
// them: excluding the shelf leaves the tool on the floor (it fell through the floor when the
// exclude was kept by rigidtouch's bodies), as MuJoCo does; excluding the world drops the floor
// and keeps the shelf
TEST(MjcfCoverageTest, ExcludeWithOneStaticBodyKeepsTheOthers) {
  const auto scene = [](const std::string& other) {
    return "<mujoco><worldbody><geom name=\"floor\" type=\"plane\" size=\"1 1 0.1\"/>"
           "<body name=\"shelf\" pos=\"0.5 0 0.1\"><geom type=\"box\" size=\"0.1 0.1 0.01\"/>"
           "</body>"
           "<body name=\"tool\" pos=\"0 0 0.02\"><freejoint/>"
           "<geom type=\"sphere\" size=\"0.01\" mass=\"0.1\"/></body></worldbody>"
           "<contact><exclude body1=\"tool\" body2=\"" +
           other + "\"/></contact></mujoco>";
  };
  const Model shelf = LoadXml(scene("shelf"));
  ASSERT_EQ(shelf.excluded_geom_pairs.size(), 1u);
  EXPECT_EQ(shelf.excluded_geom_pairs[0], std::make_pair(1, 2));  // the shelf's box, the tool's
  Data d = MakeData(shelf);
  Step(shelf, d, 0.5);
  EXPECT_GT(d.bodies[0].x_W.z(), 0.005);  // resting on the floor (centre 10 mm up, less sink)
  EXPECT_LT(d.bodies[0].v_W.norm(), 1e-2);

  const Model world = LoadXml(scene("world"));
  ASSERT_EQ(world.excluded_geom_pairs.size(), 1u);
  EXPECT_EQ(world.excluded_geom_pairs[0], std::make_pair(0, 2));  // the floor, the tool's
  Data dw = MakeData(world);
  Step(world, dw, 0.5);
  EXPECT_LT(dw.bodies[0].x_W.z(), -0.5);  // through the floor
}

// ---------------------------------------------------------------------------- condim 1

TEST(MjcfCoverageTest, Condim1IsFrictionlessOnAnIncline) {
  // tests/scenes/incline.xml (friction 0.5 holds the box) with condim 1 on the box and the ramp
  const double theta = 20.0 * M_PI / 180.0;
  const std::string xml =
      "<mujoco><option timestep=\"0.001\" gravity=\"0 0 -9.81\"/><worldbody>"
      "<geom name=\"ramp\" type=\"plane\" size=\"1 0.5 0.05\" euler=\"0 20 0\" friction=\"0.5\" "
      "condim=\"1\"/>"
      "<body name=\"box\" pos=\"0.008554 0 0.023502\" euler=\"0 20 0\"><freejoint/>"
      "<geom name=\"box_geom\" type=\"box\" size=\"0.025 0.025 0.025\" mass=\"0.1\" "
      "friction=\"0.5\" condim=\"1\"/></body>"
      "<body name=\"tool\" pos=\"0 3 0.5\"><freejoint/>"
      "<geom type=\"sphere\" size=\"0.005\" mass=\"0.1\"/></body></worldbody></mujoco>";
  const Model m = LoadXml(xml);
  EXPECT_EQ(m.geoms[0].condim, 1);
  EXPECT_EQ(m.geoms[0].friction, 0.0);
  EXPECT_EQ(m.geoms[0].mjcf_friction, 0.5);
  const Vec3 downhill(std::cos(theta), 0.0, -std::sin(theta));
  Data d = MakeData(m);
  Step(m, d, 0.2);
  const double v1 = d.bodies[0].v_W.dot(downhill);
  Step(m, d, 0.5);
  const double v2 = d.bodies[0].v_W.dot(downhill);
  const double a = (v2 - v1) / 0.5, expected = 9.81 * std::sin(theta);
  EXPECT_NEAR(a, expected, 0.01 * expected);
  // MuJoCo's rule: a contact's condim is the larger of its geoms', so condim 1 on the box alone
  // keeps the ramp's friction, and the box stays put
  std::string one_sided = xml;
  one_sided.replace(one_sided.find("condim=\"1\""), 10, "condim=\"3\"");
  const Model m3 = LoadXml(one_sided, "one_sided.xml");
  Data d3 = MakeData(m3);
  Step(m3, d3, 0.2);
  const Vec3 settled = d3.bodies[0].x_W;
  Step(m3, d3, 1.0);
  EXPECT_LT((d3.bodies[0].x_W - settled).norm(), 1e-4);
}

// ---------------------------------------------------------------------------- cylinder, ellipsoid

// a body resting on the floor, the tool far away; returns the body's centre height after 1.5 s
double RestHeight(const std::string& geom, const Model** out_model, Data* out_data) {
  static Model model;
  model = LoadXml(
      "<mujoco><option timestep=\"0.001\"/><worldbody>"
      "<geom name=\"floor\" type=\"plane\" size=\"1 1 0.1\" friction=\"0.5\"/>"
      "<body name=\"thing\" pos=\"0 0 0.03\"><freejoint/>" +
          geom +
          "</body><body name=\"tool\" pos=\"0 0.5 0.5\"><freejoint/>"
          "<geom type=\"sphere\" size=\"0.005\" mass=\"0.1\"/></body></worldbody></mujoco>",
      "rest.xml");
  *out_data = MakeData(model);
  *out_model = &model;
  Step(model, *out_data, 1.5);
  return out_data->bodies[0].x_W.z();
}

TEST(MjcfCoverageTest, CylinderRestsUprightOnItsFlatFace) {
  const Model* m = nullptr;
  Data d;
  const double z =
      RestHeight("<geom name=\"can\" type=\"cylinder\" size=\"0.015 0.02\" mass=\"0.1\"/>", &m, &d);
  EXPECT_EQ(m->geoms[1].mj_type, mjGEOM_CYLINDER);
  const double sink = 0.1 * 9.81 / m->contact.scene_stiffness_N_per_m;
  EXPECT_NEAR(z, 0.02 - sink, 1e-4);
  EXPECT_LT(d.bodies[0].v_W.norm(), 1e-3);
  EXPECT_LT(d.bodies[0].w_W.norm(), 1e-2);
  EXPECT_GT((d.bodies[0].q_WB * Vec3::UnitZ()).z(), 1.0 - 1e-6);
}

TEST(MjcfCoverageTest, EllipsoidRestsOnItsShortestSemiAxis) {
  const Model* m = nullptr;
  Data d;
  const double z = RestHeight(
      "<geom name=\"egg\" type=\"ellipsoid\" size=\"0.03 0.02 0.01\" mass=\"0.1\"/>", &m, &d);
  EXPECT_EQ(m->geoms[1].mj_type, mjGEOM_ELLIPSOID);
  const double sink = 0.1 * 9.81 / m->contact.scene_stiffness_N_per_m;
  EXPECT_NEAR(z, 0.01 - sink, 1e-4);
  EXPECT_LT(d.bodies[0].v_W.norm(), 1e-3);
}

// ---------------------------------------------------------------------------- refused, warned

// a sane scene with `body` inside the tool's body, `world` in the worldbody and `top` in <mujoco>
std::string Scene(const std::string& top, const std::string& world = "",
                  const std::string& body = "") {
  return "<mujoco>" + top +
         "<worldbody><geom name=\"floor\" type=\"plane\" size=\"1 1 0.1\"/>"
         "<body name=\"tool\" pos=\"0 0 0.1\"><freejoint name=\"free\"/>"
         "<geom name=\"tip\" type=\"sphere\" size=\"0.01\" mass=\"0.1\"/>" +
         body + "</body>" + world + "</worldbody></mujoco>";
}

const char kBall[] =
    "<body name=\"ball\" pos=\"0.1 0 0.1\"><freejoint/>"
    "<geom name=\"ball_geom\" type=\"sphere\" size=\"0.01\" mass=\"0.1\"/></body>";

// one MJCF element rigidtouch refuses or warns about, in a scene, and what the message must say
struct ElementCase {
  const char* name;  // the test's name
  std::string xml;
  std::string expected;
};

// gtest prints a parameter in a failure's message: its name, not its bytes
void PrintTo(const ElementCase& c, std::ostream* out) {
  *out << c.name;
}

std::string CaseName(const ::testing::TestParamInfo<ElementCase>& info) {
  return info.param.name;
}

std::vector<ElementCase> RefusedCases() {
  return {
      {"equality",
       Scene("<equality><weld name=\"glue\" body1=\"tool\" body2=\"ball\"/></equality>", kBall),
       "<equality> <weld> 'glue'"},
      {"actuator", Scene("<actuator><motor name=\"push\" joint=\"free\"/></actuator>"),
       "<actuator> 'push'"},
      {"tendon",
       Scene("<tendon><spatial name=\"rope\" limited=\"true\" range=\"0 0.2\"><site site=\"a\"/>"
             "<site site=\"b\"/></spatial></tendon>",
             "<site name=\"a\" pos=\"0 0 0.5\"/>", "<site name=\"b\"/>"),
       "<tendon> 'rope' has a limit"},
      {"free_joint_stiffness",
       "<mujoco><worldbody><body name=\"tool\" pos=\"0 0 0.1\">"
       "<joint name=\"springy\" type=\"free\" stiffness=\"1\"/>"
       "<geom type=\"sphere\" size=\"0.01\" mass=\"0.1\"/></body></worldbody></mujoco>",
       "<joint> 'springy' has damping, armature, frictionloss or stiffness"},
      {"tool_with_a_joint_below",
       Scene("", "",
             "<body name=\"arm\" pos=\"0.05 0 0\"><joint name=\"elbow\"/>"
             "<geom type=\"box\" size=\"0.01 0.01 0.01\" mass=\"0.1\"/></body>"),
       "body 'tool' is a link of the articulated body 'tool'"},
      {"joint_damping",
       "<mujoco><worldbody><body name=\"tool\" pos=\"0 0 0.1\">"
       "<joint name=\"slow\" type=\"free\" damping=\"1\"/>"
       "<geom type=\"sphere\" size=\"0.01\" mass=\"0.1\"/></body></worldbody></mujoco>",
       "<joint> 'slow' has damping"},
      {"density", Scene("<option density=\"1.2\"/>"), "<option density=\"1.2\""},
      {"viscosity", Scene("<option viscosity=\"0.01\"/>"), "viscosity=\"0.01\""},
      {"wind", Scene("<option wind=\"1 0 0\"/>"), "<option wind=\"1 0 0\">"},
      {"contact_disabled", Scene("<option><flag contact=\"disable\"/></option>"),
       "<flag contact=\"disable\"/>"},
      {"constraint_disabled", Scene("<option><flag constraint=\"disable\"/></option>"),
       "<flag constraint=\"disable\"/>"},
      {"predefined_collision", Scene("<option collision=\"predefined\"/>"),
       "<option collision=\"predefined\">"},
      {"pair_of_filtered_geoms",
       Scene("<contact><pair name=\"p\" geom1=\"tip\" geom2=\"ball_geom\"/></contact>",
             "<body name=\"ball\" pos=\"0.1 0 0.1\"><freejoint/><geom name=\"ball_geom\" "
             "type=\"sphere\" size=\"0.01\" mass=\"0.1\" contype=\"2\" conaffinity=\"2\"/></body>"),
       "<contact><pair> 'p' of geoms 'tip' and 'ball_geom'"},
      {"hfield",
       "<mujoco><asset><hfield name=\"h\" nrow=\"2\" ncol=\"2\" size=\"1 1 0.1 0.1\"/></asset>"
       "<worldbody><geom name=\"terrain\" type=\"hfield\" hfield=\"h\"/>"
       "<body name=\"tool\" pos=\"0 0 0.5\"><freejoint/>"
       "<geom type=\"sphere\" size=\"0.01\" mass=\"0.1\"/></body></worldbody></mujoco>",
       "geom 'terrain' has type hfield"},
  };
}

class RefusedElementTest : public ::testing::TestWithParam<ElementCase> {};

TEST_P(RefusedElementTest, ErrorNamesTheElement) {
  const std::string e = XmlError(GetParam().xml);
  EXPECT_NE(e.find(GetParam().expected), std::string::npos) << e;
}

INSTANTIATE_TEST_SUITE_P(MjcfCoverage, RefusedElementTest, ::testing::ValuesIn(RefusedCases()),
                         CaseName);

std::vector<ElementCase> WarnedCases() {
  return {
      {"geom_solref",
       Scene("", "",
             "<geom name=\"soft\" type=\"box\" size=\"0.01 0.01 0.01\" "
             "mass=\"0.1\" solref=\"0.01 1\"/>"),
       "<geom> solref, solimp, margin, gap, solmix or priority set on geom 'soft'"},
      {"geom_solimp",
       Scene("", "",
             "<geom name=\"soft\" type=\"box\" size=\"0.01 0.01 0.01\" "
             "mass=\"0.1\" solimp=\"0.8 0.9 0.01\"/>"),
       "on geom 'soft'"},
      {"geom_margin",
       Scene("", "",
             "<geom name=\"wide\" type=\"box\" size=\"0.01 0.01 0.01\" "
             "mass=\"0.1\" margin=\"0.001\"/>"),
       "on geom 'wide'"},
      {"condim_4",
       Scene("", "",
             "<geom name=\"grip\" type=\"box\" size=\"0.01 0.01 0.01\" "
             "mass=\"0.1\" condim=\"4\"/>"),
       "<geom condim=\"4\" or \"6\"> on geom 'grip'"},
      {"integrator", Scene("<option integrator=\"RK4\"/>"), "<option> integrator ignored"},
      {"keyframe_not_initial",
       Scene("<keyframe><key name=\"home\" qpos=\"0 0 0.3 1 0 0 0\"/></keyframe>"),
       "keyframe 'home' is not used: rigidtouch starts from the keyframe named 'initial'"},
      {"keyframe_time",
       Scene("<keyframe><key name=\"initial\" time=\"5\" qpos=\"0 0 0.1 1 0 0 0\"/></keyframe>"),
       "keyframe 'initial' has time=\"5\"; rigidtouch starts every run at t = 0 and ignores it"},
      {"impratio_and_cone", Scene("<option impratio=\"10\" cone=\"elliptic\"/>"),
       "<option> cone, impratio ignored"},
      {"warmstart_flag", Scene("<option><flag warmstart=\"disable\"/></option>"),
       "<flag warmstart=\"disable\"/> is ignored"},
      {"sensor",
       Scene("<sensor><framepos name=\"where\" objtype=\"body\" objname=\"tool\"/></sensor>"),
       "<sensor> 'where' ignored"},
      {"passive_tendon",
       Scene("<tendon><spatial name=\"string\"><site site=\"a\"/><site site=\"b\"/></spatial>"
             "</tendon>",
             "<site name=\"a\" pos=\"0 0 0.5\"/>", "<site name=\"b\"/>"),
       "<tendon> 'string' ignored"},
      {"mocap",
       Scene("",
             "<body name=\"target\" mocap=\"true\" pos=\"0.3 0 0.3\">"
             "<geom type=\"box\" size=\"0.01 0.01 0.01\"/></body>"),
       "body 'target' is a mocap body"},
      {"pair_of_colliding_geoms",
       Scene("<contact><pair name=\"p\" geom1=\"tip\" geom2=\"ball_geom\" condim=\"1\"/>"
             "</contact>",
             kBall),
       "<contact><pair> 'p' of geoms 'tip' and 'ball_geom': the geoms collide anyway"},
  };
}

class WarnedElementTest : public ::testing::TestWithParam<ElementCase> {};

TEST_P(WarnedElementTest, SceneLoadsAndAWarningNamesTheElement) {
  const Model m = LoadXml(GetParam().xml, "warned.xml");
  std::string all;
  for (const std::string& w : m.load_warnings) all += w + "\n";
  EXPECT_NE(all.find(GetParam().expected), std::string::npos) << all;
  EXPECT_NE(all.find("warned.xml"), std::string::npos) << all;
}

INSTANTIATE_TEST_SUITE_P(MjcfCoverage, WarnedElementTest, ::testing::ValuesIn(WarnedCases()),
                         CaseName);

// MuJoCo's own warning while it compiles becomes a load warning naming the file; it printed an
// unprefixed line and wrote MUJOCO_LOG.TXT into the working directory
// MuJoCo 2.2.2's one compile-time warning (its library holds no other) is "XML contains a 'NaN'",
// after which it uses its default for the value. rigidtouch refuses the NaN before MuJoCo reads
// the file, in any attribute, a colour's too, and MuJoCo writes no MUJOCO_LOG.TXT
TEST(MjcfCoverageTest, ANanMujocoWouldWarnAboutIsRefusedFirst) {
  std::filesystem::remove("MUJOCO_LOG.TXT");
  std::string error;
  try {
    LoadXml(
        Scene("", "<geom type=\"box\" size=\"0.1 0.1 0.01\" pos=\"1 0 0\" rgba=\"nan 0 0 1\"/>"),
        "nan.xml");
  } catch (const Error& e) {
    error = e.what();
  }
  EXPECT_NE(
      error.find("nan.xml' line 1: <geom> attribute rgba=\"nan 0 0 1\" is not a finite number"),
      std::string::npos)
      << error;
  EXPECT_FALSE(std::filesystem::exists("MUJOCO_LOG.TXT"));
}

TEST(MjcfCoverageTest, PlainScenesLoadWithoutWarnings) {
  for (const char* name : {"box_plane.xml", "sphere_plane.xml", "stack3.xml", "two_spheres.xml",
                           "incline.xml", "capsule_mesh.xml", "welded.xml"}) {
    const Model m = LoadModel(TestScene(name), {});
    EXPECT_TRUE(m.load_warnings.empty()) << name << ": " << m.load_warnings.front();
  }
}

TEST(MjcfCoverageTest, GravityDisabledByFlagIsHonoured) {
  const Model m = LoadXml(Scene("<option><flag gravity=\"disable\"/></option>"));
  EXPECT_EQ(m.gravity_W, Vec3::Zero());
  EXPECT_TRUE(m.load_warnings.empty());
}

TEST(MjcfCoverageTest, CliPrintsLoadWarningsToStderr) {
  const std::string path =
      test::WriteTempFile("cli_warned.xml", Scene("<option integrator=\"RK4\"/>"));
  const test::CliResult r = test::RunCli("simulate --scene " + path + " --steps 10 --json");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("rigidtouch: warning: scene file '" + path + "': <option> integrator"),
            std::string::npos)
      << r.err;
}

}  // namespace
}  // namespace rigidtouch
