#include "contact/impulse_examples.h"
#include "draw.h"

#include <cmath>

namespace rigidtouch::contact {
namespace {

SolverBody MakeBody(double mass_kg, const Mat3& inv_inertia_W, const Vec3& v_W, const Vec3& w_W) {
  SolverBody body;
  body.inv_mass = 1.0 / mass_kg;
  body.inv_inertia_W = inv_inertia_W;
  body.v_W = v_W;
  body.w_W = w_W;
  return body;
}

SolverRow MakeRow(int body_a, int body_b, const Vec3& n_W, const Vec3& r_a_W, const Vec3& r_b_W) {
  SolverRow row;
  row.body_a = body_a;
  row.body_b = body_b;
  row.n_W = n_W;
  row.r_a_W = r_a_W;
  row.r_b_W = r_b_W;
  return row;
}

// four rows between the bottom face of box `upper` and the top face of `lower` (-1: the floor)
void AddFaceRows(ImpulseExample& example, int upper, int lower, double half_size_m) {
  const double h = half_size_m;
  for (const double sx : {-1.0, 1.0}) {
    for (const double sy : {-1.0, 1.0}) {
      const Vec3 corner_xy(sx * h, sy * h, 0.0);
      example.rows.push_back(MakeRow(upper, lower, Vec3::UnitZ(), corner_xy - h * Vec3::UnitZ(),
                                     corner_xy + h * Vec3::UnitZ()));
    }
  }
}

Vec3 UniformInBall(std::mt19937_64& rng, double radius) {
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (;;) {
    const Vec3 v = test::Draw3(unit, rng);
    if (v.squaredNorm() <= 1.0) return radius * v;
  }
}

Vec3 UnitVector(std::mt19937_64& rng) {
  std::normal_distribution<double> normal(0.0, 1.0);
  for (;;) {
    const Vec3 v = test::Draw3(normal, rng);
    if (v.norm() > 1e-6) return v.normalized();
  }
}

// uniform on SO(3): a normalised 4D Gaussian is a uniform unit quaternion
Mat3 RandomRotation(std::mt19937_64& rng) {
  std::normal_distribution<double> normal(0.0, 1.0);
  for (;;) {
    const double w = normal(rng);
    const double x = normal(rng);
    const double y = normal(rng);
    const double z = normal(rng);
    const Quat q(w, x, y, z);
    if (q.norm() > 1e-6) return q.normalized().toRotationMatrix();
  }
}

}  // namespace

Mat3 BoxInvInertia(double mass_kg, const Vec3& half_sizes_m) {
  const Vec3 h2 = half_sizes_m.cwiseAbs2();
  const Vec3 inertia(h2.y() + h2.z(), h2.x() + h2.z(), h2.x() + h2.y());
  return (mass_kg / 3.0 * inertia).cwiseInverse().asDiagonal();
}

Mat3 SphereInvInertia(double mass_kg, double radius_m) {
  return Mat3::Identity() / (0.4 * mass_kg * radius_m * radius_m);
}

ImpulseExample SpherePlane(double mass_kg, double radius_m, const Vec3& v_W) {
  ImpulseExample example;
  example.bodies.push_back(
      MakeBody(mass_kg, SphereInvInertia(mass_kg, radius_m), v_W, Vec3::Zero()));
  example.rows.push_back(MakeRow(0, -1, Vec3::UnitZ(), -radius_m * Vec3::UnitZ(), Vec3::Zero()));
  return example;
}

ImpulseExample BoxOnPlane(double half_size_m, double mass_kg, const Vec3& v_W, const Vec3& w_W) {
  ImpulseExample example;
  example.bodies.push_back(
      MakeBody(mass_kg, BoxInvInertia(mass_kg, Vec3::Constant(half_size_m)), v_W, w_W));
  AddFaceRows(example, 0, -1, half_size_m);
  // the floor's contact points are irrelevant (static), keep them at the contact
  for (SolverRow& row : example.rows) row.r_b_W = Vec3::Zero();
  return example;
}

ImpulseExample HeadOn(double m_a_kg, double v_a_mps, double m_b_kg, double v_b_mps) {
  constexpr double kRadius_m = 0.1;
  ImpulseExample example;
  example.bodies.push_back(
      MakeBody(m_a_kg, SphereInvInertia(m_a_kg, kRadius_m), v_a_mps * Vec3::UnitX(), Vec3::Zero()));
  example.bodies.push_back(
      MakeBody(m_b_kg, SphereInvInertia(m_b_kg, kRadius_m), v_b_mps * Vec3::UnitX(), Vec3::Zero()));
  example.rows.push_back(
      MakeRow(0, 1, Vec3::UnitX(), -kRadius_m * Vec3::UnitX(), kRadius_m * Vec3::UnitX()));
  return example;
}

ImpulseExample StackWithTool(int num_boxes, double half_size_m, double box_mass_kg,
                             double tool_mass_kg, double tool_vz_mps) {
  constexpr double kToolRadius_m = 0.01;
  ImpulseExample example;
  const Mat3 box_inv_inertia = BoxInvInertia(box_mass_kg, Vec3::Constant(half_size_m));
  for (int k = 0; k < num_boxes; ++k) {
    example.bodies.push_back(MakeBody(box_mass_kg, box_inv_inertia, Vec3::Zero(), Vec3::Zero()));
    AddFaceRows(example, k, k - 1, half_size_m);
  }
  const int tool = num_boxes;
  example.bodies.push_back(MakeBody(tool_mass_kg, SphereInvInertia(tool_mass_kg, kToolRadius_m),
                                    tool_vz_mps * Vec3::UnitZ(), Vec3::Zero()));
  example.rows.push_back(MakeRow(tool, num_boxes - 1, Vec3::UnitZ(), -kToolRadius_m * Vec3::UnitZ(),
                                 half_size_m * Vec3::UnitZ()));
  return example;
}

ImpulseExample BoxGrid(int nx, int ny, int nz, std::uint64_t seed) {
  constexpr double kHalf_m = 0.05;
  constexpr double kMass_kg = 1.0;
  constexpr double kToolMass_kg = 0.5;
  constexpr double kToolRadius_m = 0.01;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> vertical(-1.0, 0.2);
  std::uniform_real_distribution<double> horizontal(-0.2, 0.2);
  std::uniform_real_distribution<double> angular(-0.5, 0.5);
  const Mat3 inv_inertia = BoxInvInertia(kMass_kg, Vec3::Constant(kHalf_m));
  ImpulseExample example;
  auto index = [&](int ix, int iy, int iz) { return (ix * ny + iy) * nz + iz; };
  for (int ix = 0; ix < nx; ++ix) {
    for (int iy = 0; iy < ny; ++iy) {
      for (int iz = 0; iz < nz; ++iz) {
        Vec3 v_W = test::Draw2(horizontal, rng, 0.0);
        v_W.z() = vertical(rng);
        const Vec3 w_W = test::Draw3(angular, rng);
        example.bodies.push_back(MakeBody(kMass_kg, inv_inertia, v_W, w_W));
        AddFaceRows(example, index(ix, iy, iz), iz == 0 ? -1 : index(ix, iy, iz - 1), kHalf_m);
      }
    }
  }
  const int tool = static_cast<int>(example.bodies.size());
  example.bodies.push_back(MakeBody(kToolMass_kg, SphereInvInertia(kToolMass_kg, kToolRadius_m),
                                    -Vec3::UnitZ(), Vec3::Zero()));
  example.rows.push_back(MakeRow(tool, index(nx / 2, ny / 2, nz - 1), Vec3::UnitZ(),
                                 -kToolRadius_m * Vec3::UnitZ(), kHalf_m * Vec3::UnitZ()));
  return example;
}

ImpulseExample RandomGroup(std::mt19937_64& rng, const RandomGroupOptions& options) {
  std::uniform_int_distribution<int> num_bodies_dist(options.min_bodies, options.max_bodies);
  std::uniform_int_distribution<int> num_rows_dist(options.min_rows, options.max_rows);
  std::uniform_real_distribution<double> log_mass(std::log(options.min_mass_kg),
                                                  std::log(options.max_mass_kg));
  std::uniform_real_distribution<double> half_size(0.01, 0.25);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::uniform_real_distribution<double> chance(0.0, 1.0);

  ImpulseExample example;
  const int num_bodies = num_bodies_dist(rng);
  for (int k = 0; k < num_bodies; ++k) {
    const double mass_kg = std::exp(log_mass(rng));
    const Vec3 half_sizes_m = test::Draw3(half_size, rng);
    const Mat3 rotation = RandomRotation(rng);
    const Mat3 inv_inertia_W =
        rotation * BoxInvInertia(mass_kg, half_sizes_m) * rotation.transpose();
    const Vec3 v_W = test::Draw3(unit, rng);
    const Vec3 w_W = 3.0 * test::Draw3(unit, rng);
    example.bodies.push_back(
        MakeBody(mass_kg, 0.5 * (inv_inertia_W + inv_inertia_W.transpose()), v_W, w_W));
  }
  std::uniform_int_distribution<int> body_dist(0, num_bodies - 1);
  const int num_rows = num_rows_dist(rng);
  for (int j = 0; j < num_rows; ++j) {
    const int body_a = body_dist(rng);
    int body_b = -1;
    if (num_bodies > 1 && chance(rng) >= options.static_row_fraction) {
      do {
        body_b = body_dist(rng);
      } while (body_b == body_a);
    }
    const Vec3 normal = UnitVector(rng);
    const Vec3 r_a = UniformInBall(rng, 0.3);
    const Vec3 r_b = UniformInBall(rng, 0.3);
    example.rows.push_back(MakeRow(body_a, body_b, normal, r_a, r_b));
  }
  return example;
}

}  // namespace rigidtouch::contact
