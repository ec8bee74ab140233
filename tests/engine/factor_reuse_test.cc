// The lagged factorisation in the tick (GroupSolverScratch::lagged.reuse_factor): on the
// benchmark's 10-box stack it solves almost every step once the stack rests, and the stack it
// simulates is the stack that factoring every step simulates, to a tolerance far below the scene's
// scale (the contacts compress by about 0.5 mm). ResetData forgets the kept factor, so a run
// repeats bit for bit.
#include <gtest/gtest.h>

#include <algorithm>
#include <string>

#include "engine/workspace.h"
#include "rigidtouch/rigidtouch.h"
#include "test_util.h"

namespace rigidtouch {
namespace {

Model StackModel() {
  return LoadModel(std::string(RIGIDTOUCH_SCENES) + "/stack.xml", LoadOptions{});
}

// MJCF of `columns` columns (0.1 m apart along x) of `boxes` boxes each, pressed 0.1 mm into each
// other and the floor, so that every contact of the first step is there from the start; the tool
// lies on the floor aside
std::string PressedColumnsXml(int columns, int boxes) {
  std::string xml =
      "<mujoco><option timestep=\"0.001\" gravity=\"0 0 -9.81\"/><worldbody>"
      "<geom name=\"floor\" type=\"plane\" size=\"1 1 0.1\"/>";
  for (int c = 0; c < columns; ++c) {
    for (int i = 0; i < boxes; ++i) {
      xml += "<body name=\"box_" + std::to_string(c) + "_" + std::to_string(i) + "\" pos=\"" +
             std::to_string(0.1 * c) + " 0 " + std::to_string(0.0249 + 0.0499 * i) +
             "\"><freejoint/><geom type=\"box\" size=\"0.025 0.025 0.025\" mass=\"0.1\"/></body>";
    }
  }
  xml +=
      "<body name=\"tool\" pos=\"-0.3 0 0.005\"><freejoint/>"
      "<geom type=\"sphere\" size=\"0.005\" mass=\"0.1\"/></body></worldbody></mujoco>";
  return xml;
}

// steps the stack with the benchmark's constant 2 N on the tool
void Step(const Model& m, Data& d, int steps) {
  TickInput in;
  in.tool_wrench.force_N = Vec3(0.0, 0.0, -2.0);
  for (int s = 0; s < steps; ++s) Tick(m, d, in);
}

TEST(FactorReuseTest, StackIsTheSameWithAndWithoutTheKeptFactor) {
  const Model m = StackModel();
  Data reused = MakeData(m);
  Data factored = MakeData(m);
  factored.workspace->velocity.group_solver.lagged.reuse_factor = false;
  const dynamics::GroupSolverScratch& s = reused.workspace->velocity.group_solver;
  // 2 s, as the benchmark's warm-up: the stack settles under the tool
  Step(m, reused, 2000);
  Step(m, factored, 2000);
  const long lagged_before = s.lagged.lagged_solves, factored_before = s.factorisations;
  Step(m, reused, 1000);
  Step(m, factored, 1000);
  // the settled stack: nearly every step by the kept factor (measured: every one)
  EXPECT_GE(s.lagged.lagged_solves - lagged_before, 950);
  EXPECT_LE(s.factorisations - factored_before, 50);
  EXPECT_EQ(factored.workspace->velocity.group_solver.lagged.lagged_solves, 0);
  // the same stack: every body within 1e-11 m and 1e-9 (quaternion components) after 3 s
  double dx = 0.0, dq = 0.0;
  for (std::size_t i = 0; i < m.bodies.size(); ++i) {
    dx = std::max(dx, (reused.bodies[i].x_W - factored.bodies[i].x_W).norm());
    dq = std::max(dq, (reused.bodies[i].q_WB.coeffs() - factored.bodies[i].q_WB.coeffs()).norm());
  }
  EXPECT_LE(dx, 1e-11);  // measured 2.6e-14 m
  EXPECT_LE(dq, 1e-9);   // measured 2.4e-12
  // and not trivially so: the top box sank under the contacts' compression (about 0.5 mm)
  const auto top = std::find_if(m.bodies.begin(), m.bodies.end(),
                                [](const BodyModel& b) { return b.name == "box_9"; });
  ASSERT_NE(top, m.bodies.end());
  const auto i = static_cast<std::size_t>(top - m.bodies.begin());
  EXPECT_LT(reused.bodies[i].x_W.z(), m.initial[i].x_W.z() - 1e-4);
}

TEST(FactorReuseTest, EveryColumnOfAPileKeepsItsOwnFactor) {
  // four columns of five pressed boxes (four groups, and the tool on the floor, a group without
  // implicit contacts), settling for 1 s: over the next 0.5 s nearly every solve of every column
  // is by its own kept factor, and the columns are those factoring every step simulates. (With
  // one kept factor for all groups each column met the last one's and every solve factored.)
  const Model m =
      LoadModel(test::WriteTempFile("four_columns.xml", PressedColumnsXml(4, 5)), LoadOptions{});
  Data reused = MakeData(m);
  Data factored = MakeData(m);
  factored.workspace->velocity.group_solver.lagged.reuse_factor = false;
  const dynamics::GroupSolverScratch& s = reused.workspace->velocity.group_solver;
  const TickInput in;
  for (int k = 0; k < 1000; ++k) {
    Tick(m, reused, in);
    Tick(m, factored, in);
  }
  const long lagged_before = s.lagged.lagged_solves, factored_before = s.factorisations;
  for (int k = 0; k < 500; ++k) {
    Tick(m, reused, in);
    Tick(m, factored, in);
    ASSERT_EQ(reused.workspace->contact.groups.ngroup, 5) << "step " << k;
  }
  // measured: every one (2000 lagged solves, no factorisation)
  EXPECT_GE(s.lagged.lagged_solves - lagged_before, 4 * 475);
  EXPECT_LE(s.factorisations - factored_before, 4 * 25);
  double dx = 0.0;
  for (std::size_t i = 0; i < m.bodies.size(); ++i) {
    dx = std::max(dx, (reused.bodies[i].x_W - factored.bodies[i].x_W).norm());
  }
  EXPECT_LE(dx, 1e-11);  // measured 2.9e-17 m
}

TEST(FactorReuseTest, ResetDataRepeatsARunBitForBit) {
  // three boxes that start pressed 0.1 mm into each other and the floor, so every contact of the
  // first step is there from the start (the tool lies on the floor aside): the factor kept at the
  // end of a run fits the first step of the next, and a reset that kept it would start the
  // second run differently
  const Model m =
      LoadModel(test::WriteTempFile("pressed_column.xml", PressedColumnsXml(1, 3)), LoadOptions{});
  Data d = MakeData(m);
  const dynamics::GroupSolverScratch& s = d.workspace->velocity.group_solver;
  Step(m, d, 300);
  ASSERT_GT(s.lagged.lagged_solves, 250);
  const std::vector<BodyState> first = d.bodies;
  ResetData(m, d);
  Step(m, d, 300);
  for (std::size_t i = 0; i < m.bodies.size(); ++i) {
    EXPECT_EQ(d.bodies[i].x_W, first[i].x_W) << "body " << i;
    EXPECT_EQ(d.bodies[i].q_WB.coeffs(), first[i].q_WB.coeffs()) << "body " << i;
    EXPECT_EQ(d.bodies[i].v_W, first[i].v_W) << "body " << i;
  }
}

}  // namespace
}  // namespace rigidtouch
