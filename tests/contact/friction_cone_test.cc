// The friction cone of the implicit solve's patches (dynamics::EnforceFrictionCones): a sticking
// patch beyond mu_s N (by more than rounding) slips with kinetic friction along its trial force,
// a slipping patch beyond mu_k N is scaled back, and nothing changes inside the cone.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "dynamics/group_assembly.h"

namespace rigidtouch::dynamics {
namespace {

// a face of four points (patch `patch`) with the forces a solve left: normal force n_i, trial
// tangential force along x
std::vector<ImplicitContact> Face(int patch, bool stick, double friction_N, double normal_N) {
  std::vector<ImplicitContact> face(4);
  for (int k = 0; k < 4; ++k) {
    ImplicitContact& c = face[k];
    c.body_a = 0;
    c.patch = patch;
    c.stick = stick;
    c.c_t_Ns_per_m = stick ? 75.0 : 0.0;
    c.phi_n_N = 0.5 + 0.1 * k;  // the spring part, k d
    c.mu_static = 0.5;
    c.mu_kinetic = 0.4;
    c.normal_force_N = normal_N * (0.7 + 0.2 * k);
    c.friction_force_N_W = Vec3(-friction_N * (1.0 + 0.1 * k), 0.0, 0.0);
    if (!stick) c.phi_t_W = c.friction_force_N_W;
  }
  return face;
}

double Sum(const std::vector<ImplicitContact>& cs, bool tangential) {
  double s = 0.0;
  for (const ImplicitContact& c : cs) {
    if (c.active) s += tangential ? c.friction_force_N_W.norm() : c.normal_force_N;
  }
  return s;
}

TEST(FrictionConeTest, InsideTheConeNothingChanges) {
  std::vector<ImplicitContact> cs = Face(0, true, 0.1, 1.0);  // 0.46 N against 0.5 * 4 N
  const std::vector<ImplicitContact> before = cs;
  EXPECT_EQ(EnforceFrictionCones(cs, false), kFrictionKept);
  for (std::size_t k = 0; k < cs.size(); ++k) {
    EXPECT_TRUE(cs[k].stick);
    EXPECT_EQ(cs[k].phi_t_W, before[k].phi_t_W);
  }
}

TEST(FrictionConeTest, AStickingPatchBeyondItsConeSlipsAlongItsTrialForce) {
  std::vector<ImplicitContact> cs = Face(0, true, 10.0, 1.0);
  EXPECT_EQ(EnforceFrictionCones(cs, false), kFrictionSlipped);
  for (const ImplicitContact& c : cs) {
    EXPECT_FALSE(c.stick);
    EXPECT_EQ(c.c_t_Ns_per_m, 0.0);
    // mu_k k d, against the motion the trial force opposed
    EXPECT_NEAR(c.phi_t_W.x(), -0.4 * c.phi_n_N, 1e-15);
    EXPECT_EQ(c.phi_t_W.y(), 0.0);
  }
}

TEST(FrictionConeTest, APointWithoutTrialForceSlipsAlongTheActivePointsResultant) {
  // active trial forces (-10, 0, 0) and (0, -10, 0) at points 0 and 1, none at point 2, and a
  // dropped point 3 whose stale (0, 30, 0) must not count: the resultant is (-10, -10, 0), so
  // point 2's kinetic friction mu_k k d points along (-1, -1, 0) / sqrt(2)
  std::vector<ImplicitContact> cs = Face(0, true, 10.0, 1.0);
  cs[0].friction_force_N_W = Vec3(-10.0, 0.0, 0.0);
  cs[1].friction_force_N_W = Vec3(0.0, -10.0, 0.0);
  cs[2].friction_force_N_W = Vec3::Zero();
  cs[3].active = false;
  cs[3].friction_force_N_W = Vec3(0.0, 30.0, 0.0);
  EXPECT_EQ(EnforceFrictionCones(cs, false), kFrictionSlipped);
  const double f = 0.4 * cs[2].phi_n_N / std::sqrt(2.0);
  EXPECT_NEAR(cs[2].phi_t_W.x(), -f, 1e-15);
  EXPECT_NEAR(cs[2].phi_t_W.y(), -f, 1e-15);
  EXPECT_EQ(cs[2].phi_t_W.z(), 0.0);
  // the points with a trial force slip along their own
  EXPECT_NEAR(cs[0].phi_t_W.x(), -0.4 * cs[0].phi_n_N, 1e-15);
  EXPECT_NEAR(cs[1].phi_t_W.y(), -0.4 * cs[1].phi_n_N, 1e-15);
}

TEST(FrictionConeTest, ATrialForceAtRoundingLevelDoesNotSlip) {
  // a sticking face whose solved normal force is zero (its points are about to be dropped for
  // pulling) and whose trial friction is rounding: the cone is exceeded by nothing but rounding,
  // so the face keeps sticking instead of slipping with mu_k k d (0.4 * 2.6 N in all) along a
  // direction that rounding chose. The line is 1e-10 of the face's penalty force, mu_s 1e-10
  // (0.5 + 0.6 + 0.7 + 0.8) N = 1.3e-10 N; the trial forces sum to 4.6 times `friction_N`.
  for (const double friction_N : {1e-19, 2.5e-11}) {
    std::vector<ImplicitContact> cs = Face(0, true, friction_N, 0.0);
    const std::vector<ImplicitContact> before = cs;
    EXPECT_EQ(EnforceFrictionCones(cs, false), kFrictionKept) << friction_N;
    for (std::size_t k = 0; k < cs.size(); ++k) {
      EXPECT_TRUE(cs[k].stick);
      EXPECT_EQ(cs[k].phi_t_W, before[k].phi_t_W);
    }
  }
  // just above the line (4.6 * 3e-11 = 1.38e-10 N) it slips, along its trial force
  std::vector<ImplicitContact> cs = Face(0, true, 3e-11, 0.0);
  EXPECT_EQ(EnforceFrictionCones(cs, false), kFrictionSlipped);
  for (const ImplicitContact& c : cs) EXPECT_NEAR(c.phi_t_W.x(), -0.4 * c.phi_n_N, 1e-15);
}

TEST(FrictionConeTest, ASlippingPatchIsKeptWithinMuKineticTimesItsNormalForce) {
  std::vector<ImplicitContact> cs = Face(0, false, 0.5, 1.0);  // 2.3 N against 0.4 * 4 N
  EXPECT_EQ(EnforceFrictionCones(cs, false), kFrictionScaled);
  double applied = 0.0;
  for (const ImplicitContact& c : cs) applied += c.phi_t_W.norm();
  EXPECT_LE(applied, 0.4 * Sum(cs, false));
  EXPECT_GE(applied, 0.999 * 0.4 * Sum(cs, false));
  // on the last solve it loses its friction instead
  std::vector<ImplicitContact> last = Face(0, false, 0.5, 1.0);
  EXPECT_EQ(EnforceFrictionCones(last, true), kFrictionScaled);
  for (const ImplicitContact& c : last) EXPECT_EQ(c.phi_t_W, Vec3::Zero());
}

TEST(FrictionConeTest, PatchesAreJudgedApartAndDroppedOrPullingContactsCountForNothing) {
  std::vector<ImplicitContact> cs = Face(0, true, 0.1, 1.0);
  const std::vector<ImplicitContact> second = Face(4, true, 0.1, 1.0);
  cs.insert(cs.end(), second.begin(), second.end());
  // the second face: two points dropped, one pulling with a trial friction of 1 N: 1.13 N of
  // friction against 0.5 * 1.3 N (the pulling point's normal force counts as 0), while the
  // first face (0.46 N against 0.5 * 4 N) keeps sticking
  cs[4].active = false;
  cs[5].active = false;
  cs[6].normal_force_N = -1.0;
  cs[6].friction_force_N_W = Vec3(-1.0, 0.0, 0.0);
  EXPECT_EQ(EnforceFrictionCones(cs, false), kFrictionSlipped);
  for (int k = 0; k < 4; ++k) EXPECT_TRUE(cs[k].stick);
  for (int k = 4; k < 8; ++k) EXPECT_FALSE(cs[k].stick);
  // without a cone (infinite mu, the default) nothing is limited
  std::vector<ImplicitContact> free = Face(0, true, 1e6, 1.0);
  for (ImplicitContact& c : free) {
    c.mu_static = ImplicitContact{}.mu_static;
    c.mu_kinetic = ImplicitContact{}.mu_kinetic;
  }
  EXPECT_EQ(EnforceFrictionCones(free, false), kFrictionKept);
}

}  // namespace
}  // namespace rigidtouch::dynamics
