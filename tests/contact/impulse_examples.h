// Canonical impulse problems with known answers, for the impulse solvers' tests: a sphere on a
// plane, a box landing flat, a head-on collision, a struck stack, a grid pile and random groups.
// World frame: z up, static geometry below z = 0 where there is a floor. Builders allocate; test
// fixtures (the rigidtouch_test_fixtures library), not part of the installed library.
#pragma once

#include <cstdint>
#include <random>
#include <vector>

#include "contact/impulse.h"

namespace rigidtouch::contact {

/// An impulse problem that owns its bodies and rows.
struct ImpulseExample {
  std::vector<SolverBody> bodies;
  std::vector<SolverRow> rows;
  /// A view of the bodies and rows, valid while this object lives and is not resized.
  ImpulseProblem problem() const { return {bodies, rows}; }
};

/// Inverse inertia (world frame, axis-aligned) of a solid box of mass `mass_kg` and half sizes
/// `half_sizes_m`: I = m/3 diag(hy^2 + hz^2, hx^2 + hz^2, hx^2 + hy^2).
Mat3 BoxInvInertia(double mass_kg, const Vec3& half_sizes_m);

/// Inverse inertia of a solid sphere, I = 2/5 m R^2.
Mat3 SphereInvInertia(double mass_kg, double radius_m);

/// Body 0, a sphere of mass `mass_kg` and radius `radius_m`, touching the static plane z = 0 at
/// its lowest point with linear velocity `v_W`; one row, normal +z.
ImpulseExample SpherePlane(double mass_kg, double radius_m, const Vec3& v_W);

/// Body 0, a box (half sizes `half_size_m` on every axis) resting flat on the static plane z = 0
/// with velocities v_W, w_W; four rows at the bottom corners, normal +z (rank 3).
ImpulseExample BoxOnPlane(double half_size_m, double mass_kg, const Vec3& v_W, const Vec3& w_W);

/// Two spheres of radius 0.1 m touching on the x axis: body 0 (mass m_a, x velocity v_a) on the
/// +x side, body 1 (mass m_b, x velocity v_b) on the -x side; one row, normal +x.
ImpulseExample HeadOn(double m_a_kg, double v_a_mps, double m_b_kg, double v_b_mps);

/// `num_boxes` cubes (half size `half_size_m`, mass `box_mass_kg`, at rest) stacked on the static
/// plane z = 0, four corner rows under each box, and a sphere tool (the last body, mass
/// `tool_mass_kg`) touching the centre of the top face with vertical velocity `tool_vz_mps`.
ImpulseExample StackWithTool(int num_boxes, double half_size_m, double box_mass_kg,
                             double tool_mass_kg, double tool_vz_mps);

/// A pile of nx * ny * nz cubes of half size 0.05 m and mass 1 kg in columns: each box has four
/// corner rows to the box below (the bottom layer to the static plane z = 0). Velocities are
/// random (seeded by `seed`): vertical in [-1, 0.2] m/s, horizontal and angular in +-0.2 m/s
/// and +-0.5 rad/s. A sphere tool (the last body, 0.5 kg) touches the top box of the column
/// (nx/2, ny/2) moving down at 1 m/s.
ImpulseExample BoxGrid(int nx, int ny, int nz, std::uint64_t seed);

/// Ranges of RandomGroup.
struct RandomGroupOptions {
  int min_bodies = 1;
  int max_bodies = 6;
  int min_rows = 1;
  int max_rows = 24;
  double min_mass_kg = 0.01;
  double max_mass_kg = 10.0;
  double static_row_fraction = 0.3;  ///< chance that a row's second side is static geometry
};

/// A random group: masses log-uniform in the range, inertias of random boxes (0.02 to 0.5 m
/// sides) in random orientations, contact points within 0.3 m of the centres, random unit
/// normals, velocities uniform in +-1 m/s and +-3 rad/s.
ImpulseExample RandomGroup(std::mt19937_64& rng, const RandomGroupOptions& options = {});

}  // namespace rigidtouch::contact
