// Loading without MuJoCo's run-time sizes (issue 19): the file's nconmax, njmax and nstack do not
// reach any allocation; memory follows the scene.
#include "io/mjcf_compile.h"

#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <sstream>
#include <string>

#include "rigidtouch/rigidtouch.h"
#include "test_util.h"

namespace rigidtouch {
namespace {

// n boxes 60 mm apart in a row on the floor, the tool beside them; `size` is put in the file
std::string Row(int n, const std::string& size) {
  std::ostringstream xml;
  xml << "<mujoco>" << size << "<worldbody><geom name=\"floor\" type=\"plane\" size=\"0 0 1\"/>";
  for (int i = 0; i < n; ++i) {
    xml << "<body pos=\"" << 0.06 * i << " 0 0.025\"><freejoint/>"
        << "<geom type=\"box\" size=\"0.025 0.025 0.025\" mass=\"0.1\"/></body>";
  }
  xml << "<body name=\"tool\" pos=\"0 1 0.005\"><freejoint/>"
         "<geom type=\"sphere\" size=\"0.005\" mass=\"0.1\"/></body></worldbody></mujoco>";
  return xml.str();
}

// bytes of an mj_makeData on the model: its buffer and its stack
double MjDataBytes(const mjModel* m) {
  mjData* d = mj_makeData(m);
  const double bytes = static_cast<double>(d->nbuffer) + 8.0 * static_cast<double>(d->nstack);
  mj_deleteData(d);
  return bytes;
}

TEST(MjcfCompileTest, FindsTheRootEndTagOutsideCommentsAndCdata) {
  EXPECT_EQ(io::RootEndTag("<mujoco></mujoco>"), 8u);
  EXPECT_EQ(io::RootEndTag("<mujoco></mujoco >\n<!-- </mujoco> -->"), 8u);
  EXPECT_EQ(io::RootEndTag("<mujoco><!-- </mujoco> --></mujoco>"), 26u);
  EXPECT_EQ(io::RootEndTag("<mujoco><![CDATA[</mujoco>]]></mujoco>"), 29u);
  EXPECT_EQ(io::RootEndTag("<?xml version=\"1.0\"?><mujoco></mujoco>"), 29u);
  // not the root's end: another element whose name starts alike, or none at all
  EXPECT_EQ(io::RootEndTag("<mujoco></mujocox>"), std::string::npos);
  EXPECT_EQ(io::RootEndTag("<robot></robot>"), std::string::npos);
  EXPECT_EQ(io::RootEndTag("<mujoco><!-- </mujoco>"), std::string::npos);
  EXPECT_EQ(io::WithMinimalSolverSizes("<mujoco><size njmax=\"9\"/></mujoco>", 1234),
            "<mujoco><size njmax=\"9\"/><size nconmax=\"0\" njmax=\"0\" nstack=\"1234\"/>"
            "</mujoco>");
  EXPECT_EQ(io::WithMinimalSolverSizes("<robot/>", 1234), "");
}

TEST(MjcfCompileTest, HugeSolverSizesInTheFileDoNotReachAnyAllocation) {
  // MuJoCo 2.2 alone cannot create the mjData of this file (njmax^2 doubles: 8e14 bytes)
  const std::string path = test::WriteTempFile(
      "huge_sizes.xml", Row(3, "<size nconmax=\"10000000\" njmax=\"10000000\" nstack=\"2\"/>"));
  char error[1000] = "";
  mjModel* plain = mj_loadXML(path.c_str(), nullptr, error, sizeof(error));
  EXPECT_EQ(plain, nullptr);
  if (plain != nullptr) mj_deleteModel(plain);

  const Model m = LoadModel(path, {});
  EXPECT_EQ(m.bodies.size(), 4u);
  EXPECT_EQ(m.collision->nconmax, 0);
  EXPECT_EQ(m.collision->njmax, 0);
  EXPECT_LT(MjDataBytes(m.collision.get()), 1e6);
  Data d = MakeData(m);
  for (int i = 0; i < 100; ++i) Tick(m, d, TickInput{});
  EXPECT_GT(d.ncontact, 0);
  EXPECT_TRUE(d.bodies[0].x_W.allFinite());
}

TEST(MjcfCompileTest, MuJoCosDataGrowsLinearlyWithTheScene) {
  // without a <size> element MuJoCo's stack is 5 (500 + nv)^2 numbers: 1.3 GB at 1000 bodies
  const Model small = LoadModel(test::WriteTempFile("row100.xml", Row(100, "")), {});
  const Model large = LoadModel(test::WriteTempFile("row1000.xml", Row(1000, "")), {});
  const double b_small = MjDataBytes(small.collision.get());
  const double b_large = MjDataBytes(large.collision.get());
  // about 5 kB a body (the stack of the compiler's 12 numbers a degree of freedom, with room,
  // and the per-body arrays): ten times the bodies, at most about ten times the bytes
  EXPECT_LT(b_large, 20e3 * 1001);
  EXPECT_LT(b_large, 12.0 * b_small);
}

TEST(MjcfCompileTest, IncludedFilesAreFoundRelativeToTheScene) {
  test::WriteTempFile("included_boxes.xml",
                      "<mujoco><worldbody><body pos=\"0 0 0.025\">"
                      "<freejoint/><geom type=\"box\" size=\"0.025 0.025 "
                      "0.025\" mass=\"0.1\"/></body></worldbody></mujoco>");
  const std::string path = test::WriteTempFile(
      "includes.xml",
      "<mujoco><size njmax=\"100000000\"/><include file=\"included_boxes.xml\"/><worldbody>"
      "<geom type=\"plane\" size=\"0 0 1\"/><body name=\"tool\" pos=\"0 1 0.005\"><freejoint/>"
      "<geom type=\"sphere\" size=\"0.005\" mass=\"0.1\"/></body></worldbody></mujoco>");
  const Model m = LoadModel(path, {});
  EXPECT_EQ(m.bodies.size(), 2u);
  EXPECT_EQ(m.collision->njmax, 0);
}

TEST(MjcfCompileTest, AStackTooSmallForTheCompilerIsDoubledUntilItFits) {
  // one element that expands to 400 bodies with two slide joints each: the first stack (about
  // 100 numbers an element) is too small for the compiler's 12 numbers a degree of freedom;
  // once it compiles, rigidtouch refuses the joints, not MuJoCo the stack
  const std::string path = test::WriteTempFile(
      "composite.xml",
      "<mujoco><worldbody><geom type=\"plane\" size=\"0 0 1\"/>"
      "<composite type=\"grid\" count=\"20 20 1\" spacing=\"0.02\"><geom size=\"0.005\"/>"
      "</composite></worldbody></mujoco>");
  try {
    LoadModel(path, {});
    ADD_FAILURE() << "a scene of slide joints loaded";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.find("Stack overflow"), std::string::npos) << what;
    EXPECT_NE(what.find("joint"), std::string::npos) << what;
  }
}

TEST(MjcfCompileTest, LoadingAndTickingPrintNothingOnStandardOutput) {
  testing::internal::CaptureStdout();
  const Model m = LoadModel(test::WriteTempFile("quiet.xml", Row(5, "<size njmax=\"1\"/>")), {});
  Data d = MakeData(m);
  for (int i = 0; i < 10; ++i) Tick(m, d, TickInput{});
  EXPECT_EQ(testing::internal::GetCapturedStdout(), "");
}

}  // namespace
}  // namespace rigidtouch
