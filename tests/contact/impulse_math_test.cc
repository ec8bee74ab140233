#include "contact/impulse_math.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <random>
#include <vector>

#include "contact/impulse_examples.h"

namespace rigidtouch::contact {
namespace {

// explicit dense Jc (c x 6b) and M^-1 (6b x 6b) built from Eq. 1-3, to check the packed helpers
struct DenseSystem {
  Eigen::MatrixXd jc;
  Eigen::MatrixXd m_inv;
  Eigen::VectorXd v;
};

DenseSystem BuildDense(const ImpulseExample& example) {
  const auto b = static_cast<Eigen::Index>(example.bodies.size());
  const auto c = static_cast<Eigen::Index>(example.rows.size());
  DenseSystem dense{Eigen::MatrixXd::Zero(c, 6 * b), Eigen::MatrixXd::Zero(6 * b, 6 * b),
                    Eigen::VectorXd::Zero(6 * b)};
  for (Eigen::Index k = 0; k < b; ++k) {
    const SolverBody& body = example.bodies[k];
    dense.m_inv.block<3, 3>(6 * k, 6 * k) = body.inv_mass * Mat3::Identity();
    dense.m_inv.block<3, 3>(6 * k + 3, 6 * k + 3) = body.inv_inertia_W;
    dense.v.segment<3>(6 * k) = body.v_W;
    dense.v.segment<3>(6 * k + 3) = body.w_W;
  }
  for (Eigen::Index j = 0; j < c; ++j) {
    const SolverRow& row = example.rows[j];
    // J_ij = [I3  -(r x)] (Eq. 1), row = n^T J_ij (Eq. 3), opposite signs for the two bodies
    auto block = [&](const Vec3& r_W) {
      Eigen::Matrix<double, 3, 6> jac;
      Mat3 r_cross;
      r_cross << 0, -r_W.z(), r_W.y(), r_W.z(), 0, -r_W.x(), -r_W.y(), r_W.x(), 0;
      jac << Mat3::Identity(), -r_cross;
      return Eigen::Matrix<double, 1, 6>(row.n_W.transpose() * jac);
    };
    if (row.body_a >= 0) dense.jc.block<1, 6>(j, 6 * row.body_a) += block(row.r_a_W);
    if (row.body_b >= 0) dense.jc.block<1, 6>(j, 6 * row.body_b) -= block(row.r_b_W);
  }
  return dense;
}

TEST(ImpulseMath, NormalVelocityOfSphereOnPlane) {
  const ImpulseExample example = SpherePlane(2.0, 0.1, Vec3(0.3, -0.4, -2.0));
  // only the normal component counts; exact arithmetic
  EXPECT_DOUBLE_EQ(NormalVelocity(example.problem(), 0), -2.0);
}

TEST(ImpulseMath, NormalVelocityIncludesRotationAndBodyB) {
  // box spinning about x at 2 rad/s: corner at y = +h moves by w x r = (2,0,0) x (h,h,-h)
  // = (0, 2h, 2h); z component 2h = +0.1 m/s at corners with y = +h, -0.1 at y = -h
  const ImpulseExample box = BoxOnPlane(0.05, 1.0, Vec3(0, 0, -1.0), Vec3(2.0, 0, 0));
  for (int j = 0; j < 4; ++j) {
    const double expected = -1.0 + 2.0 * box.rows[j].r_a_W.y();
    EXPECT_NEAR(NormalVelocity(box.problem(), j), expected, 1e-15);
  }
  // head-on: a at -1 m/s, b at +3 m/s along +x: relative normal velocity -4 m/s
  const ImpulseExample head_on = HeadOn(1.0, -1.0, 2.0, 3.0);
  EXPECT_DOUBLE_EQ(NormalVelocity(head_on.problem(), 0), -4.0);
}

TEST(ImpulseMath, KineticEnergyClosedForm) {
  std::vector<SolverBody> bodies(3);
  // translation only: 1/2 2 kg |(1,2,2)|^2 = 9 J; rotation: I = R diag(1,2,3) R^T, w = R (1,1,1)
  // gives 1/2 (1 + 2 + 3) = 3 J
  const Mat3 rotation = Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized()).toRotationMatrix();
  bodies[0].inv_mass = 0.5;
  bodies[0].v_W = Vec3(1, 2, 2);
  bodies[0].inv_inertia_W =
      rotation * Vec3(1.0, 0.5, 1.0 / 3.0).asDiagonal() * rotation.transpose();
  bodies[0].w_W = rotation * Vec3(1, 1, 1);
  // infinite mass and inertia: no energy whatever the velocity
  bodies[1].inv_mass = 0.0;
  bodies[1].v_W = Vec3(5, 5, 5);
  bodies[1].w_W = Vec3(1, 2, 3);
  // infinite inertia about y and z: only 1/2 I_x w_x^2 = 1/2 2 3^2 = 9 J
  bodies[2].inv_mass = 0.0;
  bodies[2].inv_inertia_W = Vec3(0.5, 0.0, 0.0).asDiagonal();
  bodies[2].w_W = Vec3(3, 4, 5);
  // tolerance: rounding of a 3x3 solve, 1e-12 relative
  EXPECT_NEAR(KineticEnergy(bodies), 9.0 + 3.0 + 9.0, 21.0 * 1e-12);
  EXPECT_NEAR(KineticEnergy(std::span(bodies).first(1)), 12.0, 12.0 * 1e-12);
  EXPECT_DOUBLE_EQ(KineticEnergy(std::span(bodies).subspan(1, 1)), 0.0);
}

TEST(ImpulseMath, ApplyImpulsesSphereClosedForm) {
  ImpulseExample example = SpherePlane(2.0, 0.1, Vec3(0.3, 0.0, -2.0));
  const double p[] = {3.0};
  ApplyImpulses(example.bodies, example.rows, p);
  // dv = p n / m = 1.5 m/s up; the lever r x n = (0,0,-0.1) x (0,0,1) = 0: no spin (exact)
  EXPECT_DOUBLE_EQ(example.bodies[0].v_W.z(), -0.5);
  EXPECT_DOUBLE_EQ(example.bodies[0].v_W.x(), 0.3);
  EXPECT_EQ(example.bodies[0].w_W, Vec3::Zero());
}

TEST(ImpulseMath, ApplyImpulsesConservesMomentaBetweenBodies) {
  // rows between two dynamic bodies at a common world point conserve linear and angular momentum
  std::mt19937_64 rng(7);
  RandomGroupOptions options;
  options.min_bodies = 2;
  options.static_row_fraction = 0.0;
  for (int trial = 0; trial < 50; ++trial) {
    ImpulseExample example = RandomGroup(rng, options);
    // put the bodies' centres where the rows' contact points agree: x_b = x_a + r_a - r_b only
    // holds for one row, so use one row per trial
    example.rows.resize(1);
    const SolverRow& row = example.rows[0];
    const Vec3 x_a_W = Vec3::Zero();
    const Vec3 x_b_W = x_a_W + row.r_a_W - row.r_b_W;
    auto momenta = [&](const std::vector<SolverBody>& bodies) {
      const SolverBody& a = bodies[row.body_a];
      const SolverBody& b = bodies[row.body_b];
      const Vec3 linear = a.v_W / a.inv_mass + b.v_W / b.inv_mass;
      const Vec3 angular = x_a_W.cross(a.v_W / a.inv_mass) + a.inv_inertia_W.inverse() * a.w_W +
                           x_b_W.cross(b.v_W / b.inv_mass) + b.inv_inertia_W.inverse() * b.w_W;
      return std::pair(linear, angular);
    };
    const auto [linear0, angular0] = momenta(example.bodies);
    const double p[] = {2.5};
    ApplyImpulses(example.bodies, example.rows, p);
    const auto [linear1, angular1] = momenta(example.bodies);
    // tolerance: rounding of momenta of order 10 kg m/s and of a 3x3 inverse, 1e-9 absolute
    EXPECT_LT((linear1 - linear0).norm(), 1e-9) << "trial " << trial;
    EXPECT_LT((angular1 - angular0).norm(), 1e-9) << "trial " << trial;
  }
}

TEST(ImpulseMath, DelassusAndJcVMatchExplicitMatrices) {
  std::mt19937_64 rng(11);
  for (int trial = 0; trial < 100; ++trial) {
    const ImpulseExample example = RandomGroup(rng);
    const DenseSystem dense = BuildDense(example);
    const auto c = static_cast<Eigen::Index>(example.rows.size());
    Eigen::MatrixXd A(c, c);
    Eigen::VectorXd b(c);
    DelassusDense(example.problem(), A);
    JcV(example.problem(), b);
    const Eigen::MatrixXd A_expected = dense.jc * dense.m_inv * dense.jc.transpose();
    const Eigen::VectorXd b_expected = dense.jc * dense.v;
    // tolerance: rounding, 1e-12 relative to the largest entry
    EXPECT_LE((A - A_expected).cwiseAbs().maxCoeff(), 1e-12 * A_expected.cwiseAbs().maxCoeff());
    EXPECT_LE((b - b_expected).cwiseAbs().maxCoeff(), 1e-12 * b_expected.cwiseAbs().maxCoeff());
    EXPECT_EQ(A, A.transpose());
  }
}

TEST(ImpulseMath, DelassusPredictsVelocityChange) {
  // Jc v+ = Jc v0 + A p for any p (Eq. 2 premultiplied by Jc M^-1)
  std::mt19937_64 rng(13);
  std::uniform_real_distribution<double> impulse(-1.0, 1.0);
  for (int trial = 0; trial < 100; ++trial) {
    ImpulseExample example = RandomGroup(rng);
    const auto c = static_cast<Eigen::Index>(example.rows.size());
    Eigen::MatrixXd A(c, c);
    Eigen::VectorXd b0(c), b1(c), p(c);
    for (Eigen::Index j = 0; j < c; ++j) p[j] = impulse(rng);
    DelassusDense(example.problem(), A);
    JcV(example.problem(), b0);
    ApplyImpulses(example.bodies, example.rows, std::span<const double>(p.data(), c));
    JcV(example.problem(), b1);
    const Eigen::VectorXd expected = b0 + A * p;
    // tolerance: rounding, 1e-11 relative to the largest velocity
    EXPECT_LE((b1 - expected).cwiseAbs().maxCoeff(), 1e-11 * expected.cwiseAbs().maxCoeff())
        << "trial " << trial;
  }
}

TEST(ImpulseMath, BoxOnPlaneDelassusHasRankThree) {
  const ImpulseExample box = BoxOnPlane(0.05, 1.0, -Vec3::UnitZ(), Vec3::Zero());
  Eigen::MatrixXd A(4, 4);
  DelassusDense(box.problem(), A);
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(A);
  const Eigen::VectorXd lambda = eigen.eigenvalues();  // ascending
  // one zero eigenvalue (the alternating corner pattern), three positive ones; tolerance 1e-12
  // relative to the largest
  EXPECT_LT(std::abs(lambda[0]), 1e-12 * lambda[3]);
  EXPECT_GT(lambda[1], 0.1 * lambda[3]);
  const Eigen::Vector4d alternating(1, -1, -1, 1);  // corners ordered (-,-), (-,+), (+,-), (+,+)
  EXPECT_LT((A * alternating).norm(), 1e-12 * lambda[3]);
}

}  // namespace
}  // namespace rigidtouch::contact
