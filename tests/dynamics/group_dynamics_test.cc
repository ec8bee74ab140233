// The implicit group solve (block Cholesky over body blocks, minimum-degree order, patch
// assembly from moments) against a dense reference: the same backward-Euler system assembled
// row by row with full matrices and solved by Eigen's LDLT. Tolerance: 1e-9 relative to the largest
// velocity (the systems are well conditioned: mass 0.1 kg against h c = 2e2 x 1e-3 per row).
#include "dynamics/group_dynamics.h"

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <limits>
#include <random>
#include <vector>

#include "draw.h"
#include "dynamics/rigid_body.h"
#include "rigidtouch/rigidtouch.h"
#include "test_util.h"

namespace rigidtouch::dynamics {
namespace {

constexpr double kGroupSolveTol = 1e-9;

struct Fixture {
  Model model;
  Data data;
  std::vector<int> bodies, slot;
  std::vector<Vec3> force, torque;
  GroupSolverScratch scratch;
  KeptFactors kept;  // the factors f.scratch keeps, by body
};

// a pile model of nx x ny x nz boxes, the group = every box, random velocities and forces
Fixture MakeFixture(int nx, int ny, int nz, unsigned seed) {
  const std::string path = test::WriteTempFile("group_" + std::to_string(nx * ny * nz) + ".xml",
                                               test::PileXml(nx, ny, nz, 0.051, 0.5));
  Fixture f{LoadModel(path, LoadOptions{}), Data{}, {}, {}, {}, {}, {}, {}};
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
    s.v_W = 1e-3 * test::Draw3(u, rng);  // slow: every contact row keeps pushing
    s.w_W = 1e-2 * test::Draw3(u, rng);
    const double angle = u(rng);
    s.q_WB = Quat(Eigen::AngleAxisd(angle, test::Draw2(u, rng, 1.0).normalized()));
    f.force[i] = 0.1 * test::Draw2(u, rng, 0.0);
    f.force[i].z() = -1.0;
    f.torque[i] = 0.01 * test::Draw3(u, rng);
    f.slot[i] = static_cast<int>(f.bodies.size());
    f.bodies.push_back(i);
  }
  f.scratch.Reserve(static_cast<int>(f.bodies.size()), 3 * 4000);
  f.kept.Reserve(nbody);
  return f;
}

// one contact point p as the tick builds it: a normal row and a tangential force in the tangent
// plane, the anchor spring with damping c_t when sticking, kinetic friction when slipping (the
// dense reference turns it into two tangential rows)
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
    const Vec3 ra = -0.025 * n + corner + 1e-3 * test::Draw3(u, rng);
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
    // any orthonormal tangent basis: one not aligned with the one phi_t was built in; a slipping
    // contact's phi_t is its kinetic friction, a tangential force without velocity coefficient
    const Vec3 t1 =
        (c.n_W.unitOrthogonal() + 0.5 * c.n_W.cross(c.n_W.unitOrthogonal())).normalized();
    const Vec3 t2 = c.n_W.cross(t1);
    const double ct = c.stick ? c.c_t_Ns_per_m : 0.0;
    rows.push_back(Row{&c, t1, c.phi_t_W.dot(t1), ct});
    rows.push_back(Row{&c, t2, c.phi_t_W.dot(t2), ct});
  }
  return rows;
}

// every body of the group at rest and without torque (the forces are left to the test)
void StartAtRest(Fixture& f) {
  for (int i : f.bodies) {
    f.data.bodies[i].v_W.setZero();
    f.data.bodies[i].w_W.setZero();
    f.torque[i].setZero();
  }
}

// dense reference: (M + h sum c j j^T) v = M v0 + h F + h sum phi j over the rows of the active
// contacts, each row assembled on its own
struct DenseSystem {
  Eigen::MatrixXd M, H;       // the mass matrix and the system's
  Eigen::VectorXd v0, hF, b;  // the velocities before the step, h F, and the right-hand side
};
DenseSystem DenseSystemOf(const Fixture& f, const std::vector<ImplicitContact>& contacts) {
  const int n = 6 * static_cast<int>(f.bodies.size());
  const double h = f.model.timestep_s;
  DenseSystem d{Eigen::MatrixXd::Zero(n, n), Eigen::MatrixXd::Zero(n, n), Eigen::VectorXd::Zero(n),
                Eigen::VectorXd::Zero(n), Eigen::VectorXd::Zero(n)};
  for (std::size_t k = 0; k < f.bodies.size(); ++k) {
    const int i = f.bodies[k];
    const Mat3 I = WorldInertia(f.model.bodies[i], f.data.bodies[i]);
    d.M.block<3, 3>(6 * k, 6 * k) = f.model.bodies[i].mass_kg * Mat3::Identity();
    d.M.block<3, 3>(6 * k + 3, 6 * k + 3) = I;
    d.v0.segment<3>(6 * k) = f.data.bodies[i].v_W;
    d.v0.segment<3>(6 * k + 3) = f.data.bodies[i].w_W;
    d.hF.segment<3>(6 * k) = h * f.force[i];
    d.hF.segment<3>(6 * k + 3) = h * f.torque[i];
  }
  d.H = d.M;
  d.b = d.M * d.v0 + d.hF;
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
    d.H += h * r.c * j * j.transpose();
    d.b += h * r.phi * j;
  }
  return d;
}

Eigen::VectorXd DenseSolve(const Fixture& f, const std::vector<ImplicitContact>& contacts) {
  const DenseSystem d = DenseSystemOf(f, contacts);
  return d.H.ldlt().solve(d.b);
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
                                   f.scratch, f.kept));
  for (const ImplicitContact& c : contacts) ASSERT_TRUE(c.active);  // none dropped: same system
  const Eigen::VectorXd v = Solved(f);
  EXPECT_LE((v - expected).lpNorm<Eigen::Infinity>(),
            kGroupSolveTol * std::max(1.0, expected.lpNorm<Eigen::Infinity>()));
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
          const double n_y = 0.05 * u(rng);
          const double n_z = 0.05 * u(rng);
          const Vec3 n = Vec3(1.0, n_y, n_z).normalized();
          const double r_y = 0.01 * u(rng);
          const double r_z = 0.01 * u(rng);
          AddContact(contacts, id(x, y, z), id(x - 1, y, z), n, x_W + Vec3(-0.025, r_y, r_z), 20.0,
                     x % 2 == 0);
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
  StartAtRest(f);
  // pulled apart: at the first pass the pair moves as one (the floor still pushes) and the contacts
  // between them pull; without those contacts the lower box is pressed on the floor
  f.force[f.bodies[0]] = Vec3(0.0, 0.0, -5000.0);
  f.force[f.bodies[1]] = Vec3(0.0, 0.0, 5000.0);
  std::vector<ImplicitContact> expected_contacts = contacts;
  for (ImplicitContact& c : expected_contacts) c.active = c.body_b != f.bodies[0];
  const Eigen::VectorXd expected = DenseSolve(f, expected_contacts);
  ASSERT_TRUE(SolveGroupVelocities(f.model, f.data, f.bodies, f.slot, contacts, f.force, f.torque,
                                   f.scratch, f.kept));
  EXPECT_LE((Solved(f) - expected).lpNorm<Eigen::Infinity>(),
            kGroupSolveTol * expected.lpNorm<Eigen::Infinity>());
  for (const ImplicitContact& c : contacts) {
    const bool upper = c.body_b == f.bodies[0];
    EXPECT_EQ(c.active, !upper);
    if (upper) {
      EXPECT_EQ(c.normal_force_N, 0.0);
      EXPECT_EQ(c.friction_force_N_W, Vec3::Zero());
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
  StartAtRest(f);
  f.force[b[0]] = f.force[b[1]] = Vec3(0.0, 0.0, -5000.0);
  f.force[b[2]] = f.force[b[3]] = Vec3(0.0, 0.0, 5000.0);
  std::vector<ImplicitContact> kept = contacts;
  for (ImplicitContact& c : kept) c.active = c.body_b < 0;
  const Eigen::VectorXd expected = DenseSolve(f, kept);
  ASSERT_TRUE(SolveGroupVelocities(f.model, f.data, f.bodies, f.slot, contacts, f.force, f.torque,
                                   f.scratch, f.kept));
  EXPECT_LE((Solved(f) - expected).lpNorm<Eigen::Infinity>(),
            kGroupSolveTol * expected.lpNorm<Eigen::Infinity>());
  for (const ImplicitContact& c : contacts) {
    ASSERT_EQ(c.active, c.body_b < 0);
    if (!c.active) {
      EXPECT_EQ(c.normal_force_N, 0.0);
      EXPECT_EQ(c.friction_force_N_W, Vec3::Zero());
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
                                   f.scratch, f.kept));
  for (const ImplicitContact& c : contacts) {
    ASSERT_TRUE(c.active);
    Vec3 u = Vec3::Zero();
    if (c.body_a >= 0) u += PointVelocity(f.data.bodies[c.body_a], Offset(f, c.body_a, c));
    if (c.body_b >= 0) u -= PointVelocity(f.data.bodies[c.body_b], Offset(f, c.body_b, c));
    EXPECT_NEAR(c.normal_force_N, c.phi_n_N - c.c_n_Ns_per_m * u.dot(c.n_W), 1e-12 * c.phi_n_N);
    const Vec3 t1 = c.n_W.unitOrthogonal(), t2 = c.n_W.cross(t1);
    const Vec3 ft = (c.phi_t_W.dot(t1) - c.c_t_Ns_per_m * u.dot(t1)) * t1 +
                    (c.phi_t_W.dot(t2) - c.c_t_Ns_per_m * u.dot(t2)) * t2;
    EXPECT_LE((c.friction_force_N_W - ft).norm(), 1e-12 * c.phi_n_N);
  }
}

// --- the lagged factorisation (GroupSolverScratch::lagged.reuse_factor) ---

// a column of four boxes on the floor: sticking and slipping faces, and a ceiling point
std::vector<ImplicitContact> ColumnContacts(const Fixture& f, std::mt19937& rng) {
  std::vector<ImplicitContact> contacts;
  AddFace(f, contacts, f.bodies[0], -1, Vec3::UnitZ(), true, rng);
  AddFace(f, contacts, f.bodies[1], f.bodies[0], Vec3::UnitZ(), true, rng);
  AddFace(f, contacts, f.bodies[2], f.bodies[1], Vec3(0.1, 0.0, 1.0).normalized(), false, rng);
  AddFace(f, contacts, f.bodies[3], f.bodies[2], Vec3::UnitZ(), true, rng);
  const Vec3 top = f.data.bodies[f.bodies[3]].x_W;
  AddContact(contacts, -1, f.bodies[3], Vec3::UnitZ(), top + Vec3(0.02, -0.01, 0.025), 5.0, true);
  return contacts;
}

// a scratch like the fixture's that factors every solve
GroupSolverScratch FreshScratch(const Fixture& f) {
  GroupSolverScratch s;
  s.Reserve(static_cast<int>(f.bodies.size()), 3 * 4000);
  s.lagged.reuse_factor = false;
  return s;
}

// solves with scratch s and returns the new velocities; the bodies are left as they were
Eigen::VectorXd SolveWith(Fixture& f, std::vector<ImplicitContact> contacts,
                          GroupSolverScratch& s) {
  const std::vector<BodyState> before = f.data.bodies;
  EXPECT_TRUE(SolveGroupVelocities(f.model, f.data, f.bodies, f.slot, contacts, f.force, f.torque,
                                   s, f.kept));
  const Eigen::VectorXd v = Solved(f);
  f.data.bodies = before;
  return v;
}

// the lagged solve's guarantee for velocities v of the system d: the error in the kinetic-energy
// norm, sqrt(e^T M e), is at most 1e-10 (|M v0| + |h F| + |b - H v0|), each in the M^-1 norm
// (plus 1e-13 of the solution for the dense reference's own rounding). Returns the error.
double ExpectWithinRefinementBound(const DenseSystem& d, const Eigen::VectorXd& v) {
  const Eigen::MatrixXd M_inv = d.M.inverse();
  auto norm_inv = [&](const Eigen::VectorXd& r) { return std::sqrt(r.dot(M_inv * r)); };
  const Eigen::VectorXd expected = d.H.ldlt().solve(d.b);
  const double scale =
      std::sqrt(d.v0.dot(d.M * d.v0)) + norm_inv(d.hF) + norm_inv(d.b - d.H * d.v0);
  const Eigen::VectorXd e = v - expected;
  const double error = std::sqrt(e.dot(d.M * e));
  EXPECT_LE(error, 1e-10 * scale + 1e-13 * std::sqrt(expected.dot(d.M * expected)));
  return error;
}

void SetVelocities(Fixture& f, const Eigen::VectorXd& v) {
  for (std::size_t k = 0; k < f.bodies.size(); ++k) {
    f.data.bodies[f.bodies[k]].v_W = v.segment<3>(6 * k);
    f.data.bodies[f.bodies[k]].w_W = v.segment<3>(6 * k + 3);
  }
}

// the next step of the same group: the bodies start at the velocities v just solved, every
// contact point moves by up to `move` and every body turns by up to move / (25 mm), the contacts'
// forces change by up to `change`; bodies, patches, stick states and coefficients stay
void NextStep(Fixture& f, std::vector<ImplicitContact>& contacts, const Eigen::VectorXd& v,
              double move, double change, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  SetVelocities(f, v);
  for (int i : f.bodies) {
    BodyState& st = f.data.bodies[i];
    const double angle = move / 0.025 * u(rng);
    st.q_WB = (Quat(Eigen::AngleAxisd(angle, test::Draw2(u, rng, 1.0).normalized())) * st.q_WB)
                  .normalized();
  }
  for (ImplicitContact& c : contacts) {
    c.p_W += move * test::Draw3(u, rng);
    c.phi_n_N *= 1.0 + change * u(rng);
    c.phi_t_W *= 1.0 + change * u(rng);
  }
}

TEST(GroupDynamics, KeptFactorSolvesTheNextStepsWithinItsBound) {
  // a column at rest under its contact forces (the same step repeated from its own answer until
  // the velocities stop changing), one factorisation, then five steps in which the contacts move
  // by up to 1 um and their forces change by up to 1e-4, solved by refinement: each within the
  // bound against the dense solve of its own system, every contact's forces at the returned
  // velocities
  Fixture f = MakeFixture(1, 1, 4, 12);
  std::mt19937 rng(21);
  std::vector<ImplicitContact> contacts = ColumnContacts(f, rng);
  GroupSolverScratch settle = FreshScratch(f);
  Eigen::VectorXd v = Solved(f);
  for (int k = 0; k < 200; ++k) {
    SetVelocities(f, v);
    v = SolveWith(f, contacts, settle);
  }
  SetVelocities(f, v);
  v = SolveWith(f, contacts, f.scratch);
  ASSERT_EQ(f.scratch.factorisations, 1);
  ASSERT_EQ(f.scratch.lagged.lagged_solves, 0);
  for (int step = 1; step <= 5; ++step) {
    NextStep(f, contacts, v, 1e-6, 1e-4, rng);
    const DenseSystem d = DenseSystemOf(f, contacts);
    std::vector<ImplicitContact> solved = contacts;
    ASSERT_TRUE(SolveGroupVelocities(f.model, f.data, f.bodies, f.slot, solved, f.force, f.torque,
                                     f.scratch, f.kept));
    v = Solved(f);
    EXPECT_EQ(f.scratch.factorisations, 1) << "step " << step;
    EXPECT_EQ(f.scratch.lagged.lagged_solves, step);
    const double error = ExpectWithinRefinementBound(d, v);
    // the step changed the velocities by far more than the error
    EXPECT_GT(std::sqrt((v - d.v0).dot(d.M * (v - d.v0))), 1e3 * error) << "step " << step;
    for (const ImplicitContact& c : solved) {
      ASSERT_TRUE(c.active);
      Vec3 u = Vec3::Zero();
      if (c.body_a >= 0) u += PointVelocity(f.data.bodies[c.body_a], Offset(f, c.body_a, c));
      if (c.body_b >= 0) u -= PointVelocity(f.data.bodies[c.body_b], Offset(f, c.body_b, c));
      EXPECT_NEAR(c.normal_force_N, c.phi_n_N - c.c_n_Ns_per_m * u.dot(c.n_W), 1e-12 * c.phi_n_N);
    }
  }
  EXPECT_GE(f.scratch.lagged.refinement_steps, 5);  // no step was solved by its old velocities
  EXPECT_EQ(f.scratch.lagged.lagged_failures, 0);
}

// the group of f reduced to every `stride`-th body from `first` (a column of a pile), numbered
// from 0
void Restrict(Fixture& f, int first, int stride) {
  std::vector<int> column;
  for (std::size_t k = first; k < f.bodies.size(); k += stride) column.push_back(f.bodies[k]);
  f.bodies = column;
  for (std::size_t k = 0; k < f.bodies.size(); ++k) f.slot[f.bodies[k]] = static_cast<int>(k);
}

// the velocities at which the group rests under these contacts: the same step repeated from its
// own answer, with a scratch that factors every solve, until they stop changing. A contact that
// pulls at rest (a corner of a random face may) is removed and the group settled again, so that
// every contact left pushes, as in a pile at rest.
Eigen::VectorXd Settle(Fixture& f, std::vector<ImplicitContact>& contacts) {
  GroupSolverScratch settle = FreshScratch(f);
  Eigen::VectorXd v = Solved(f);
  for (;;) {
    for (int k = 0; k < 200; ++k) {
      SetVelocities(f, v);
      v = SolveWith(f, contacts, settle);
    }
    const std::vector<BodyState> before = f.data.bodies;
    SetVelocities(f, v);
    std::vector<ImplicitContact> solved = contacts;
    EXPECT_TRUE(SolveGroupVelocities(f.model, f.data, f.bodies, f.slot, solved, f.force, f.torque,
                                     settle, f.kept));
    f.data.bodies = before;
    std::vector<ImplicitContact> pushing;
    for (std::size_t k = 0; k < contacts.size(); ++k) {
      if (solved[k].active) pushing.push_back(contacts[k]);
    }
    if (pushing.size() == contacts.size()) return v;
    contacts = pushing;
  }
}

TEST(GroupDynamics, EveryGroupKeepsItsOwnFactor) {
  // two columns of four boxes at rest, solved in turn as a tick solves its groups, by two
  // scratches in turn (as two threads may) sharing one KeptFactors: each column keeps its own
  // factor, and every solve after its first is a lagged solve within the bound. (With one kept
  // factor for all groups, each column would meet the other's and factor every step.)
  Fixture left = MakeFixture(2, 1, 4, 18), right = MakeFixture(2, 1, 4, 18);
  Restrict(left, 0, 2);
  Restrict(right, 1, 2);
  std::mt19937 rng(27);
  std::vector<ImplicitContact> lc = ColumnContacts(left, rng), rc = ColumnContacts(right, rng);
  Eigen::VectorXd lv = Settle(left, lc), rv = Settle(right, rc);
  GroupSolverScratch* scratches[2] = {&left.scratch, &right.scratch};
  KeptFactors& kept = left.kept;
  for (int step = 0; step < 6; ++step) {
    for (int column = 0; column < 2; ++column) {
      Fixture& f = column == 0 ? left : right;
      std::vector<ImplicitContact>& contacts = column == 0 ? lc : rc;
      Eigen::VectorXd& v = column == 0 ? lv : rv;
      if (step == 0) {
        SetVelocities(f, v);
      } else {
        NextStep(f, contacts, v, 1e-6, 1e-4, rng);
      }
      const DenseSystem d = DenseSystemOf(f, contacts);
      std::vector<ImplicitContact> solved = contacts;
      ASSERT_TRUE(SolveGroupVelocities(f.model, f.data, f.bodies, f.slot, solved, f.force, f.torque,
                                       *scratches[(step + column) % 2], kept));
      v = Solved(f);
      for (const ImplicitContact& c : solved) ASSERT_TRUE(c.active);  // the dense system's
      ExpectWithinRefinementBound(d, v);
    }
  }
  const long factorisations = left.scratch.factorisations + right.scratch.factorisations;
  const long lagged = left.scratch.lagged.lagged_solves + right.scratch.lagged.lagged_solves;
  EXPECT_EQ(factorisations, 2);  // the first solve of each column
  EXPECT_EQ(lagged, 10);
  EXPECT_GT(left.scratch.lagged.lagged_solves, 0);  // each scratch used a factor
  EXPECT_GT(right.scratch.lagged.lagged_solves, 0);
}

TEST(GroupDynamics, TriesTheKeptFactorEverMoreRarelyWhileTheGroupMoves) {
  // forty steps from the same velocities in which the contacts move by up to 1 mm and their
  // forces change by up to 10%: the kept factor never bounds the error in two corrections. It is
  // tried in solves 2, 4, 8, 16 and 32 (the back-off doubles), every solve factors once (no
  // contact pulls), and every answer is a fresh factorisation's, bit for bit.
  Fixture f = MakeFixture(1, 1, 4, 17);
  std::mt19937 rng(26);
  std::vector<ImplicitContact> contacts = ColumnContacts(f, rng);
  GroupSolverScratch fresh = FreshScratch(f);
  const Eigen::VectorXd v0 = Solved(f);
  for (int solve = 1; solve <= 40; ++solve) {
    NextStep(f, contacts, v0, 1e-3, 0.1, rng);
    const Eigen::VectorXd expected = SolveWith(f, contacts, fresh);
    ASSERT_EQ(SolveWith(f, contacts, f.scratch), expected) << "solve " << solve;
  }
  EXPECT_EQ(f.scratch.lagged.lagged_failures, 5);
  EXPECT_EQ(f.scratch.lagged.lagged_solves, 0);
  EXPECT_EQ(f.scratch.factorisations, 40);
}

TEST(GroupDynamics, KeptFactorIgnoresContactOrderAndReferenceBody) {
  // the same system listed differently: the patches in reverse order, and each box-box face with
  // its bodies swapped (normal and tangential force negated), as a manifold whose reference box
  // changed. Its factor fits, and the answer is the first one within the bound.
  Fixture f = MakeFixture(1, 1, 4, 13);
  std::mt19937 rng(22);
  const std::vector<ImplicitContact> contacts = ColumnContacts(f, rng);
  const DenseSystem d = DenseSystemOf(f, contacts);
  (void)SolveWith(f, contacts, f.scratch);
  std::vector<ImplicitContact> relisted(contacts.rbegin(), contacts.rend());
  for (ImplicitContact& c : relisted) {
    if (c.body_a < 0 || c.body_b < 0) continue;
    std::swap(c.body_a, c.body_b);
    c.n_W = -c.n_W;
    c.phi_t_W = -c.phi_t_W;
  }
  const Eigen::VectorXd v = SolveWith(f, relisted, f.scratch);
  EXPECT_EQ(f.scratch.factorisations, 1);
  EXPECT_EQ(f.scratch.lagged.lagged_solves, 1);
  ExpectWithinRefinementBound(d, v);
}

TEST(GroupDynamics, FactorsAfreshWhenAPatchChanges) {
  // a face that starts slipping, a face that loses a point, a contact law with another
  // stiffness: each is a different system, so the kept factor is not tried and the result is a
  // fresh factorisation's, bit for bit
  Fixture f = MakeFixture(1, 1, 4, 14);
  std::mt19937 rng(23);
  const std::vector<ImplicitContact> contacts = ColumnContacts(f, rng);
  std::vector<std::vector<ImplicitContact>> changed(3, contacts);
  for (int k = 4; k < 8; ++k) changed[0][k].stick = false;  // the second face
  changed[1].erase(changed[1].begin() + 4);
  for (int k = 8; k < 12; ++k) changed[2][k].c_n_Ns_per_m *= 2.0;  // the third face
  for (std::size_t i = 0; i < changed.size(); ++i) {
    (void)SolveWith(f, contacts, f.scratch);  // keeps the factor of the unchanged system
    const long factorisations = f.scratch.factorisations;
    const long lagged = f.scratch.lagged.lagged_solves;
    GroupSolverScratch fresh = FreshScratch(f);
    const Eigen::VectorXd expected = SolveWith(f, changed[i], fresh);
    EXPECT_EQ(SolveWith(f, changed[i], f.scratch), expected) << "change " << i;
    EXPECT_EQ(f.scratch.factorisations, factorisations + 1) << "change " << i;
    EXPECT_EQ(f.scratch.lagged.lagged_solves, lagged) << "change " << i;
    EXPECT_EQ(fresh.lagged.lagged_solves, 0);
  }
}

TEST(GroupDynamics, NeverTrustsAWrongFactor) {
  // the kept factor damaged (a scaled diagonal block, then a NaN): the refinement cannot bound
  // its error, and the solve factors afresh and returns that factorisation's answer bit for bit
  Fixture f = MakeFixture(1, 1, 4, 15);
  std::mt19937 rng(24);
  const std::vector<ImplicitContact> contacts = ColumnContacts(f, rng);
  for (int damage = 0; damage < 2; ++damage) {
    f.kept.Forget();
    (void)SolveWith(f, contacts, f.scratch);
    ASSERT_TRUE(f.kept.records[f.bodies[0]].valid);
    if (damage == 0) {
      f.kept.columns[f.bodies[1]].diag *= 3.0;
      f.kept.columns[f.bodies[1]].diag_inv /= 3.0;
    } else {
      f.kept.columns[f.bodies[2]].diag(4, 3) = std::numeric_limits<double>::quiet_NaN();
    }
    const long factorisations = f.scratch.factorisations;
    GroupSolverScratch fresh = FreshScratch(f);
    const Eigen::VectorXd expected = SolveWith(f, contacts, fresh);
    EXPECT_EQ(SolveWith(f, contacts, f.scratch), expected) << "damage " << damage;
    EXPECT_EQ(f.scratch.factorisations, factorisations + 1) << "damage " << damage;
  }
  EXPECT_EQ(f.scratch.lagged.lagged_solves, 0);
}

TEST(GroupDynamics, FactorsAfreshWhenTheLaggedAnswerWouldPull) {
  // the same system twice, so the kept factor is exact; the second time the upper boxes are
  // pulled off. The refinement converges, but to velocities at which the faces between the boxes
  // pull: the solve factors afresh and drops them, as a fresh scratch does.
  Fixture f = MakeFixture(1, 1, 2, 16);
  std::mt19937 rng(25);
  std::vector<ImplicitContact> contacts;
  AddFace(f, contacts, f.bodies[0], -1, Vec3::UnitZ(), true, rng);
  AddFace(f, contacts, f.bodies[1], f.bodies[0], Vec3::UnitZ(), true, rng);
  StartAtRest(f);
  // pressed together: reused, since nothing changed
  f.force[f.bodies[0]] = f.force[f.bodies[1]] = Vec3(0.0, 0.0, -1.0);
  (void)SolveWith(f, contacts, f.scratch);
  (void)SolveWith(f, contacts, f.scratch);
  ASSERT_EQ(f.scratch.factorisations, 1);
  ASSERT_EQ(f.scratch.lagged.lagged_solves, 1);
  // pulled apart
  f.force[f.bodies[0]] = Vec3(0.0, 0.0, -5000.0);
  f.force[f.bodies[1]] = Vec3(0.0, 0.0, 5000.0);
  GroupSolverScratch fresh = FreshScratch(f);
  const Eigen::VectorXd expected = SolveWith(f, contacts, fresh);
  std::vector<ImplicitContact> solved = contacts;
  ASSERT_TRUE(SolveGroupVelocities(f.model, f.data, f.bodies, f.slot, solved, f.force, f.torque,
                                   f.scratch, f.kept));
  EXPECT_EQ(Solved(f), expected);
  EXPECT_EQ(f.scratch.lagged.lagged_solves, 1);
  EXPECT_EQ(f.scratch.factorisations, 1 + fresh.factorisations);  // two passes: all, then kept
  for (const ImplicitContact& c : solved) EXPECT_EQ(c.active, c.body_b < 0);
}

TEST(GroupDynamics, RefusesAGroupBeyondItsCapacity) {
  Fixture f = MakeFixture(2, 2, 1, 6);
  f.scratch.Reserve(3, 12);  // three bodies, twelve contacts: the four-body group does not fit
  std::mt19937 rng(1);
  std::vector<ImplicitContact> contacts;
  AddFace(f, contacts, f.bodies[0], -1, Vec3::UnitZ(), false, rng);
  const BodyState before = f.data.bodies[f.bodies[0]];
  EXPECT_FALSE(SolveGroupVelocities(f.model, f.data, f.bodies, f.slot, contacts, f.force, f.torque,
                                    f.scratch, f.kept));
  EXPECT_EQ(f.data.bodies[f.bodies[0]].v_W, before.v_W);  // nothing written
}

}  // namespace
}  // namespace rigidtouch::dynamics
