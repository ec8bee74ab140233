#include "view/shapes.h"

#include <mujoco/mujoco.h>

#include <cmath>
#include <numbers>

namespace rigidtouch::view {
namespace {

// tessellation: fine enough that a 5 mm sphere seen from 0.2 m (20 px) looks round
constexpr int kSlices = 32;  // around the axis
constexpr int kStacks = 16;  // pole to pole

void Vertex(std::vector<float>& out, const Vec3& p, const Vec3& n) {
  for (int k = 0; k < 3; ++k) out.push_back(static_cast<float>(p[k]));
  for (int k = 0; k < 3; ++k) out.push_back(static_cast<float>(n[k]));
}

void Triangle(std::vector<float>& out, const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& n) {
  Vertex(out, a, n);
  Vertex(out, b, n);
  Vertex(out, c, n);
}

void BoxTriangles(const Vec3& half, std::vector<float>& out) {
  for (int axis = 0; axis < 3; ++axis) {
    for (const double side : {-1.0, 1.0}) {
      const int i = (axis + 1) % 3, j = (axis + 2) % 3;
      Vec3 n = Vec3::Zero();
      n[axis] = side;
      const auto corner = [&](double si, double sj) {
        Vec3 p = side * half[axis] * n.cwiseAbs();
        p[i] = si * half[i];
        p[j] = sj * half[j];
        return p;
      };
      Triangle(out, corner(-1, -1), corner(1, -1), corner(1, 1), n);
      Triangle(out, corner(-1, -1), corner(1, 1), corner(-1, 1), n);
    }
  }
}

// a unit direction at (stack, slice) of a sphere, stack 0 the south pole
Vec3 Direction(int stack, int slice) {
  const double theta = std::numbers::pi * stack / kStacks - 0.5 * std::numbers::pi;
  const double phi = 2.0 * std::numbers::pi * slice / kSlices;
  return Vec3(std::cos(theta) * std::cos(phi), std::cos(theta) * std::sin(phi), std::sin(theta));
}

// an ellipsoid with half-axes `half` (a sphere when they are equal), its two halves moved apart
// along z by +-shift (a capsule's hemispheres); normals of the ellipsoid's surface
void Ellipsoid(const Vec3& half, double shift, std::vector<float>& out) {
  const Vec3 inv2 = half.cwiseProduct(half).cwiseInverse();
  for (int i = 0; i < kStacks; ++i) {
    const double dz = i < kStacks / 2 ? -shift : shift;
    for (int j = 0; j < kSlices; ++j) {
      const Vec3 d[4] = {Direction(i, j), Direction(i, j + 1), Direction(i + 1, j + 1),
                         Direction(i + 1, j)};
      Vec3 p[4], n[4];
      for (int k = 0; k < 4; ++k) {
        p[k] = d[k].cwiseProduct(half) + Vec3(0.0, 0.0, dz);
        n[k] = d[k].cwiseProduct(half).cwiseProduct(inv2).normalized();
      }
      const int tri[2][3] = {{0, 1, 2}, {0, 2, 3}};
      for (const auto& t : tri) {
        for (const int k : t) Vertex(out, p[k], n[k]);
      }
    }
  }
}

// the side of a cylinder of radius r from z = z0 to z1, normals radial
void Side(double r, double z0, double z1, std::vector<float>& out) {
  for (int j = 0; j < kSlices; ++j) {
    const Vec3 a = Direction(kStacks / 2, j), b = Direction(kStacks / 2, j + 1);
    const Vec3 p[4] = {r * a + Vec3(0, 0, z0), r * b + Vec3(0, 0, z0), r * b + Vec3(0, 0, z1),
                       r * a + Vec3(0, 0, z1)};
    const Vec3 n[4] = {a, b, b, a};
    for (const int k : {0, 1, 2, 0, 2, 3}) Vertex(out, p[k], n[k]);
  }
}

void Cylinder(double r, double half_length, std::vector<float>& out) {
  Side(r, -half_length, half_length, out);
  for (const double s : {-1.0, 1.0}) {
    const Vec3 c(0.0, 0.0, s * half_length), n(0.0, 0.0, s);
    for (int j = 0; j < kSlices; ++j) {
      Triangle(out, c, c + r * Direction(kStacks / 2, j), c + r * Direction(kStacks / 2, j + 1), n);
    }
  }
}

void Capsule(double r, double half_length, std::vector<float>& out) {
  Side(r, -half_length, half_length, out);
  Ellipsoid(Vec3::Constant(r), half_length, out);
}

// the compiled model's mesh, flat-shaded: one normal per face, from its winding
void Mesh(const mjModel* m, int mj_geom, std::vector<float>& out) {
  if (m == nullptr || mj_geom < 0 || mj_geom >= m->ngeom) return;
  const int id = m->geom_dataid[mj_geom];
  if (id < 0 || id >= m->nmesh) return;
  const float* v = m->mesh_vert + 3 * static_cast<long>(m->mesh_vertadr[id]);
  const int* face = m->mesh_face + 3 * static_cast<long>(m->mesh_faceadr[id]);
  const auto vertex = [&](int k) { return Vec3(v[3 * k], v[3 * k + 1], v[3 * k + 2]); };
  for (int f = 0; f < m->mesh_facenum[id]; ++f) {
    const Vec3 a = vertex(face[3 * f]), b = vertex(face[3 * f + 1]), c = vertex(face[3 * f + 2]);
    const Vec3 n = (b - a).cross(c - a);
    if (!(n.norm() > 0.0)) continue;  // a degenerate face has no area to draw
    Triangle(out, a, b, c, n.normalized());
  }
}

}  // namespace

void AppendGeomTriangles(const Model& model, const GeomModel& g, std::vector<float>& out) {
  switch (g.type) {
    case GeomType::kPlane:
      return;
    case GeomType::kSphere:
      Ellipsoid(Vec3::Constant(g.size.x()), 0.0, out);
      return;
    case GeomType::kCapsule:
      Capsule(g.size.x(), g.size.y(), out);
      return;
    case GeomType::kBox:
      BoxTriangles(g.size, out);
      return;
    case GeomType::kMesh:
      // cylinders and ellipsoids collide as meshes (GeomModel::mj_type tells them apart)
      if (g.mj_type == mjGEOM_CYLINDER) {
        Cylinder(g.size.x(), g.size.y(), out);
      } else if (g.mj_type == mjGEOM_ELLIPSOID) {
        Ellipsoid(g.size, 0.0, out);
      } else {
        Mesh(model.collision.get(), g.mj_geom, out);
      }
      return;
  }
}

}  // namespace rigidtouch::view
