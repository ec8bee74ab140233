// The implicit group solve (block Cholesky over body blocks, minimum-degree order, patch
// assembly from moments) against a dense reference: the same backward-Euler system assembled
// row by row with full matrices and solved by Eigen's LDLT. Tolerance: 1e-9 relative to the largest
// velocity (the systems are well conditioned: mass 0.1 kg against h c = 2e2 x 1e-3 per row).
#include "dynamics/group_dynamics.h"

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <random>
#include <vector>

#include "dynamics/rigid_body.h"
#include "rigidtouch/rigidtouch.h"
#include "test_util.h"

namespace rigidtouch::dynamics {
namespace {

constexpr double kTol = 1e-9;

struct Fixture {
  Model model;
  Data data;
  std::vector<int> bodies, slot;
  std::vector<Vec3> force, torque;
  GroupSolverScratch scratch;
};

// a pile model of nx x ny x nz boxes, the group = every box, random velocities and forces
Fixture MakeFixture(int nx, int ny, int nz, unsigned seed) {
  const std::string path = test::WriteTempFile("group_" + std::to_string(nx * ny * nz) + ".xml",
                                               test::PileXml(nx, ny, nz, 0.051, 0.5));
  Fixture f{LoadModel(path, LoadOptions{}), Data{}, {}, {}, {}, {}, {}};
  f.data = MakeData(f.model);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const int nbody = static_cast<int>(f.model.bodies.size());
  f.slot.assign(nbody, -1);
  f.force.assign(nbody, Vec3::Zero());
  f.torque.assign(nbody, Vec3::Zero());
  for (int i = 0; i < nbody; ++i) {
    if (i == f.model.tool) continue;
    BodyState& s = f.data.bodies[i];
    s.v_W = 1e-3 * Vec3(u(rng), u(rng), u(rng));  // slow: every contact row keeps pushing
    s.w_W = 1e-2 * Vec3(u(rng), u(rng), u(rng));
    s.q_WB = Quat(Eigen::AngleAxisd(u(rng), Vec3(u(rng), u(rng), 1.0).normalized()));
    f.force[i] = Vec3(0.1 * u(rng), 0.1 * u(rng), -1.0);
    f.torque[i] = 0.01 * Vec3(u(rng), u(rng), u(rng));
    f.slot[i] = static_cast<int>(f.bodies.size());
    f.bodies.push_back(i);
  }
  f.scratch.Reserve(static_cast<int>(f.bodies.size()), 3 * 4000);
  return f;
}

// one contact point p as the tick builds it: a normal row and, when sticking, a tangential force
// in the tangent plane (the dense reference turns it into two tangential rows)
void AddContact(std::vector<ImplicitContact>& contacts, int a, int b, const Vec3& n, const Vec3& p,
                double phi, bool stick) {
  ImplicitContact c;
  c.body_a = a;
  c.body_b = b;
  c.n_W = n;
  c.p_W = p;
  c.phi_n_N = phi;
  c.c_n_Ns_per_m = 300.0;
  c.stick = stick;
  c.phi_t_W = 0.3 * n.unitOrthogonal() - 0.2 * n.cross(n.unitOrthogonal());
  c.c_t_Ns_per_m = 150.0;
  contacts.push_back(c);
}

// four corner points of a's face towards -n, touching b (b = -1: the floor), one normal
void AddFace(const Fixture& f, std::vector<ImplicitContact>& contacts, int a, int b, const Vec3& n,
             bool stick, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const Vec3 t1 = n.unitOrthogonal(), t2 = n.cross(t1);
  for (int k = 0; k < 4; ++k) {
    const Vec3 corner = 0.025 * ((k & 1 ? 1.0 : -1.0) * t1 + (k & 2 ? 1.0 : -1.0) * t2);
    const Vec3 ra = -0.025 * n + corner + 1e-3 * Vec3(u(rng), u(rng), u(rng));
    AddContact(contacts, a, b, n, f.data.bodies[a].x_W + ra, 20.0 + u(rng), stick);
  }
}

// the contact point's offset from body i's centre of mass
Vec3 Offset(const Fixture& f, int i, const ImplicitContact& c) {
  return c.p_W - f.data.bodies[i].x_W;
}

// the rows of the active contacts: direction, force phi, coefficient c
struct Row {
  const ImplicitContact* contact;
  Vec3 d;
  double phi, c;
};
std::vector<Row> RowsOf(const std::vector<ImplicitContact>& contacts) {
  std::vector<Row> rows;
  for (const ImplicitContact& c : contacts) {
    if (!c.active) continue;
    rows.push_back(Row{&c, c.n_W, c.phi_n_N, c.c_n_Ns_per_m});
    if (!c.stick) continue;
    // any orthonormal tangent basis: one not aligned with the one phi_t was built in
    const Vec3 t1 =
        (c.n_W.unitOrthogonal() + 0.5 * c.n_W.cross(c.n_W.unitOrthogonal())).normalized();
    const Vec3 t2 = c.n_W.cross(t1);
    rows.push_back(Row{&c, t1, c.phi_t_W.dot(t1), c.c_t_Ns_per_m});
    rows.push_back(Row{&c, t2, c.phi_t_W.dot(t2), c.c_t_Ns_per_m});
  }
  return rows;
}

// dense reference: (M + h sum c j j^T) v = M v0 + h F + h sum phi j over the rows of the active
// contacts, each row assembled on its own
Eigen::VectorXd DenseSolve(const Fixture& f, const std::vector<ImplicitContact>& contacts) {
  const int n = 6 * static_cast<int>(f.bodies.size());
  const double h = f.model.timestep_s;
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(n, n);
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(n);
  for (std::size_t k = 0; k < f.bodies.size(); ++k) {
    const int i = f.bodies[k];
    const Mat3 I = WorldInertia(f.model.bodies[i], f.data.bodies[i]);
    H.block<3, 3>(6 * k, 6 * k) = f.model.bodies[i].mass_kg * Mat3::Identity();
    H.block<3, 3>(6 * k + 3, 6 * k + 3) = I;
    rhs.segment<3>(6 * k) = f.model.bodies[i].mass_kg * f.data.bodies[i].v_W + h * f.force[i];
    rhs.segment<3>(6 * k + 3) = I * f.data.bodies[i].w_W + h * f.torque[i];
  }
  for (const Row& r : RowsOf(contacts)) {
    const ImplicitContact& c = *r.contact;
    Eigen::VectorXd j = Eigen::VectorXd::Zero(n);
    if (c.body_a >= 0) {
      j.segment<3>(6 * f.slot[c.body_a]) += r.d;
      j.segment<3>(6 * f.slot[c.body_a] + 3) += Offset(f, c.body_a, c).cross(r.d);
    }
    if (c.body_b >= 0) {
      j.segment<3>(6 * f.slot[c.body_b]) -= r.d;
      j.segment<3>(6 * f.slot[c.body_b] + 3) -= Offset(f, c.body_b, c).cross(r.d);
    }
    H += h * r.c * j * j.transpose();
    rhs += h * r.phi * j;
  }
  return H.ldlt().solve(rhs);
}

Eigen::VectorXd Solved(const Fixture& f) {
  Eigen::VectorXd v(6 * f.bodies.size());
  for (std::size_t k = 0; k < f.bodies.size(); ++k) {
    v.segment<3>(6 * k) = f.data.bodies[f.bodies[k]].v_W;
    v.segment<3>(6 * k + 3) = f.data.bodies[f.bodies[k]].w_W;
  }
  return v;
}

void ExpectMatchesDense(Fixture& f, std::vector<ImplicitContact> contacts) {
  const Eigen::VectorXd expected = DenseSolve(f, contacts);
  ASSERT_TRUE(SolveGroupVelocities(f.model, f.data, f.bodies, f.slot, contacts, f.force, f.torque,
                                   f.scratch));
  for (const ImplicitContact& c : contacts) ASSERT_TRUE(c.active);  // none dropped: same system
  const Eigen::VectorXd v = Solved(f);
  EXPECT_LE((v - expected).lpNorm<Eigen::Infinity>(),
            kTol * std::max(1.0, expected.lpNorm<Eigen::Infinity>()));
}

TEST(GroupDynamics, ColumnOfFacesMatchesDenseSolve) {
  // a stack of 4: floor-box faces and box-box faces, sticking and slipping patches
  Fixture f = MakeFixture(1, 1, 4, 1);
  std::mt19937 rng(7);
  std::vector<ImplicitContact> contacts;
  AddFace(f, contacts, f.bodies[0], -1, Vec3::UnitZ(), true, rng);
  AddFace(f, contacts, f.bodies[1], f.bodies[0], Vec3::UnitZ(), true, rng);
  AddFace(f, contacts, f.bodies[2], f.bodies[1], Vec3(0.1, 0.0, 1.0).normalized(), false, rng);
  AddFace(f, contacts, f.bodies[1], f.bodies[3], -Vec3::UnitZ(), true, rng);  // b above a
  // the static world as body a: a ceiling pressing on the top box
  const Vec3 top = f.data.bodies[f.bodies[3]].x_W;
  AddContact(contacts, -1, f.bodies[3], Vec3::UnitZ(), top + Vec3(0.02, -0.01, 0.025), 5.0, true);
  AddContact(contacts, -1, f.bodies[3], Vec3::UnitZ(), top + Vec3(-0.02, 0.01, 0.025), 6.0, true);
  ExpectMatchesDense(f, contacts);
}

TEST(GroupDynamics, LatticeWithFillInMatchesDenseSolve) {
  // a 4 x 3 x 3 lattice: every box touches its neighbours along x, y and z, so the elimination
  // creates fill-in; single points, faces and random directions mixed
  Fixture f = MakeFixture(4, 3, 3, 2);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<ImplicitContact> contacts;
  auto id = [&](int x, int y, int z) { return f.bodies[x + 4 * y + 12 * z]; };
  for (int z = 0; z < 3; ++z) {
    for (int y = 0; y < 3; ++y) {
      for (int x = 0; x < 4; ++x) {
        const Vec3 x_W = f.data.bodies[id(x, y, z)].x_W;
        if (z == 0) AddFace(f, contacts, id(x, y, z), -1, Vec3::UnitZ(), (x + y) % 2 == 0, rng);
        if (z == 2 && x == 1) {  // a contact of a body with itself: J = J_a - J_b = 0, no effect
          AddContact(contacts, id(x, y, z), id(x, y, z), Vec3::UnitX(), x_W + Vec3(0.02, 0.0, 0.01),
                     20.0, y == 1);
        }
        if (z > 0) AddFace(f, contacts, id(x, y, z), id(x, y, z - 1), Vec3::UnitZ(), true, rng);
        if (x > 0) {
          const Vec3 n = Vec3(1.0, 0.05 * u(rng), 0.05 * u(rng)).normalized();
          AddContact(contacts, id(x, y, z), id(x - 1, y, z), n,
                     x_W + Vec3(-0.025, 0.01 * u(rng), 0.01 * u(rng)), 20.0, x % 2 == 0);
        }
        if (y > 0) {
          AddContact(contacts, id(x, y - 1, z), id(x, y, z), -Vec3::UnitY(),
                     x_W + Vec3(0.0, -0.025, 0.01 * u(rng)), 20.0, true);
        }
      }
    }
  }
  ExpectMatchesDense(f, contacts);
}

TEST(GroupDynamics, ReanalysesWhenTheStructureChanges) {
  // one scratch for three solves: two columns of two boxes, the same with the lower boxes also
  // touching side by side, the columns again. A stale ordering would leave out or misplace
  // couplings, so each must match the dense solve.
  Fixture f = MakeFixture(2, 2, 2, 8);
  std::mt19937 rng(9);
  const auto& b = f.bodies;  // b[x + 2 y + 4 z]
  std::vector<ImplicitContact> chain;
  for (int k = 0; k < 4; ++k) AddFace(f, chain, b[k], -1, Vec3::UnitZ(), true, rng);
  for (int k = 4; k < 8; ++k) AddFace(f, chain, b[k], b[k - 4], Vec3::UnitZ(), true, rng);
  std::vector<ImplicitContact> cross = chain;
  for (int k : {1, 3}) {
    const Vec3 x_W = f.data.bodies[b[k]].x_W;
    AddContact(cross, b[k], b[k - 1], Vec3::UnitX(), x_W + Vec3(-0.025, 0.01, 0.0), 20.0, true);
  }
  // each solve starts from the same velocities (a solve launches the boxes off their faces)
  const std::vector<BodyState> start = f.data.bodies;
  for (const auto* contacts : {&chain, &cross, &chain}) {
    f.data.bodies = start;
    ExpectMatchesDense(f, *contacts);
  }
}

TEST(GroupDynamics, PullingContactIsDroppedWithItsFriction) {
  // the face contacts between two boxes would pull: they drop out with their tangential rows,
  // and the result is the dense solve without them
  Fixture f = MakeFixture(1, 1, 2, 3);
  std::mt19937 rng(5);
  std::vector<ImplicitContact> contacts;
  AddFace(f, contacts, f.bodies[0], -1, Vec3::UnitZ(), true, rng);
  AddFace(f, contacts, f.bodies[1], f.bodies[0], Vec3::UnitZ(), true, rng);
  for (int i : f.bodies) {
    f.data.bodies[i].v_W.setZero();
    f.data.bodies[i].w_W.setZero();
    f.torque[i].setZero();
  }
  // pulled apart: at the first pass the pair moves as one (the floor still pushes) and the contacts
  // between them pull; without those contacts the lower box is pressed on the floor
  f.force[f.bodies[0]] = Vec3(0.0, 0.0, -5000.0);
  f.force[f.bodies[1]] = Vec3(0.0, 0.0, 5000.0);
  std::vector<ImplicitContact> expected_contacts = contacts;
  for (ImplicitContact& c : expected_contacts) c.active = c.body_b != f.bodies[0];
  const Eigen::VectorXd expected = DenseSolve(f, expected_contacts);
  ASSERT_TRUE(SolveGroupVelocities(f.model, f.data, f.bodies, f.slot, contacts, f.force, f.torque,
                                   f.scratch));
  EXPECT_LE((Solved(f) - expected).lpNorm<Eigen::Infinity>(),
            kTol * expected.lpNorm<Eigen::Infinity>());
  for (const ImplicitContact& c : contacts) {
    const bool upper = c.body_b == f.bodies[0];
    EXPECT_EQ(c.active, !upper);
    if (upper) {
      EXPECT_EQ(c.normal_force_N, 0.0);
      EXPECT_EQ(c.friction_force_W, Vec3::Zero());
    } else {
      EXPECT_GT(c.normal_force_N, 0.0);  // the floor still pushes
    }
  }
}

TEST(GroupDynamics, DroppedContactsBetweenKeptOnesReportNoForce) {
  // two columns of two boxes; the upper boxes are pulled off, so the faces between the boxes
  // drop out while the floor faces on either side of them in the list stay. Every kept contact
  // reports its forces at the solved velocities, every dropped one reports none, and the
  // velocities are the dense solve without the dropped contacts.
  Fixture f = MakeFixture(2, 1, 2, 10);
  std::mt19937 rng(4);
  const auto& b = f.bodies;  // b[x + 2 z]
  std::vector<ImplicitContact> contacts;
  AddFace(f, contacts, b[0], -1, Vec3::UnitZ(), true, rng);
  AddFace(f, contacts, b[2], b[0], Vec3::UnitZ(), true, rng);
  AddFace(f, contacts, b[1], -1, Vec3::UnitZ(), false, rng);
  AddFace(f, contacts, b[3], b[1], Vec3::UnitZ(), true, rng);
  AddFace(f, contacts, b[1], -1, Vec3(0.1, 0.0, 1.0).normalized(), true, rng);
  for (int i : b) {
    f.data.bodies[i].v_W.setZero();
    f.data.bodies[i].w_W.setZero();
    f.torque[i].setZero();
  }
  f.force[b[0]] = f.force[b[1]] = Vec3(0.0, 0.0, -5000.0);
  f.force[b[2]] = f.force[b[3]] = Vec3(0.0, 0.0, 5000.0);
  std::vector<ImplicitContact> kept = contacts;
  for (ImplicitContact& c : kept) c.active = c.body_b < 0;
  const Eigen::VectorXd expected = DenseSolve(f, kept);
  ASSERT_TRUE(SolveGroupVelocities(f.model, f.data, f.bodies, f.slot, contacts, f.force, f.torque,
                                   f.scratch));
  EXPECT_LE((Solved(f) - expected).lpNorm<Eigen::Infinity>(),
            kTol * expected.lpNorm<Eigen::Infinity>());
  for (const ImplicitContact& c : contacts) {
    ASSERT_EQ(c.active, c.body_b < 0);
    if (!c.active) {
      EXPECT_EQ(c.normal_force_N, 0.0);
      EXPECT_EQ(c.friction_force_W, Vec3::Zero());
      continue;
    }
    const Vec3 u = PointVelocity(f.data.bodies[c.body_a], Offset(f, c.body_a, c));
    EXPECT_NEAR(c.normal_force_N, c.phi_n_N - c.c_n_Ns_per_m * u.dot(c.n_W),
                1e-9 * std::abs(c.phi_n_N));
  }
}

TEST(GroupDynamics, ReportsContactForcesAtTheNewVelocities) {
  // a box on the floor, a box on it (spinning, so the lower face's points move differently on the
  // two boxes) and a ceiling point pressing the top box: each contact's reported forces are its
  // rows' forces at the relative velocity of its point on the two solved bodies
  Fixture f = MakeFixture(1, 1, 2, 4);
  std::mt19937 rng(3);
  std::vector<ImplicitContact> contacts;
  AddFace(f, contacts, f.bodies[0], -1, Vec3::UnitZ(), true, rng);
  AddFace(f, contacts, f.bodies[1], f.bodies[0], Vec3(0.1, 0.0, 1.0).normalized(), true, rng);
  const Vec3 top = f.data.bodies[f.bodies[1]].x_W;
  AddContact(contacts, -1, f.bodies[1], Vec3::UnitZ(), top + Vec3(0.01, 0.02, 0.025), 20.0, true);
  for (int i : f.bodies) f.data.bodies[i].w_W = Vec3(0.3, -0.2, 0.5);
  ASSERT_TRUE(SolveGroupVelocities(f.model, f.data, f.bodies, f.slot, contacts, f.force, f.torque,
                                   f.scratch));
  for (const ImplicitContact& c : contacts) {
    ASSERT_TRUE(c.active);
    Vec3 u = Vec3::Zero();
    if (c.body_a >= 0) u += PointVelocity(f.data.bodies[c.body_a], Offset(f, c.body_a, c));
    if (c.body_b >= 0) u -= PointVelocity(f.data.bodies[c.body_b], Offset(f, c.body_b, c));
    EXPECT_NEAR(c.normal_force_N, c.phi_n_N - c.c_n_Ns_per_m * u.dot(c.n_W), 1e-12 * c.phi_n_N);
    const Vec3 t1 = c.n_W.unitOrthogonal(), t2 = c.n_W.cross(t1);
    const Vec3 ft = (c.phi_t_W.dot(t1) - c.c_t_Ns_per_m * u.dot(t1)) * t1 +
                    (c.phi_t_W.dot(t2) - c.c_t_Ns_per_m * u.dot(t2)) * t2;
    EXPECT_LE((c.friction_force_W - ft).norm(), 1e-12 * c.phi_n_N);
  }
}

TEST(GroupDynamics, RefusesAGroupBeyondItsCapacity) {
  Fixture f = MakeFixture(2, 2, 1, 6);
  f.scratch.Reserve(3, 12);  // three bodies, twelve contacts: the four-body group does not fit
  std::mt19937 rng(1);
  std::vector<ImplicitContact> contacts;
  AddFace(f, contacts, f.bodies[0], -1, Vec3::UnitZ(), false, rng);
  const BodyState before = f.data.bodies[f.bodies[0]];
  EXPECT_FALSE(SolveGroupVelocities(f.model, f.data, f.bodies, f.slot, contacts, f.force, f.torque,
                                    f.scratch));
  EXPECT_EQ(f.data.bodies[f.bodies[0]].v_W, before.v_W);  // nothing written
}

}  // namespace
}  // namespace rigidtouch::dynamics
