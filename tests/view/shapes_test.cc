// The triangles the viewer draws for each geom type: every vertex on the shape's surface with the
// surface's outward normal, and the surface areas within the tessellation's error of the closed
// forms; a mesh is drawn from the compiled model's faces (a prism given by its vertices: MuJoCo's
// hull, whose area is that of the prism).
#include "view/shapes.h"

#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <cmath>
#include <numbers>
#include <string>

#include "rigidtouch/rigidtouch.h"

namespace rigidtouch::view {
namespace {

struct Triangles {
  std::vector<Vec3> p, n;  // three per triangle
  double Area() const {
    double a = 0.0;
    for (std::size_t k = 0; k + 2 < p.size(); k += 3) {
      a += 0.5 * (p[k + 1] - p[k]).cross(p[k + 2] - p[k]).norm();
    }
    return a;
  }
};

Triangles Of(const Model& model, const GeomModel& g) {
  std::vector<float> v;
  AppendGeomTriangles(model, g, v);
  EXPECT_EQ(v.size() % (3 * kVertexFloats), 0u);
  Triangles t;
  for (std::size_t k = 0; k + kVertexFloats <= v.size(); k += kVertexFloats) {
    t.p.emplace_back(v[k], v[k + 1], v[k + 2]);
    t.n.emplace_back(v[k + 3], v[k + 4], v[k + 5]);
  }
  return t;
}

GeomModel Primitive(int mj_type, GeomType type, const Vec3& size) {
  GeomModel g;
  g.type = type;
  g.mj_type = mj_type;
  g.size = size;
  return g;
}

constexpr double kPi = std::numbers::pi;
// tessellation error: 32 segments around (a chord's area loses 1 - sin(x)/x, x = pi/32, about
// 0.16 %) and 16 stacks; 2 % covers both for every closed form below
constexpr double kAreaTol = 0.02;
constexpr double kOnSurface = 1e-6;  // m, float vertices of centimetre shapes

TEST(ViewShapes, SphereAndEllipsoid) {
  const Model model;
  const double r = 0.01;
  const Triangles s = Of(model, Primitive(mjGEOM_SPHERE, GeomType::kSphere, Vec3(r, 0, 0)));
  ASSERT_FALSE(s.p.empty());
  for (std::size_t k = 0; k < s.p.size(); ++k) {
    EXPECT_NEAR(s.p[k].norm(), r, kOnSurface);
    EXPECT_NEAR(s.n[k].norm(), 1.0, 1e-6);
    EXPECT_GT(s.n[k].dot(s.p[k].normalized()), 1.0 - 1e-6);  // radial, outward
  }
  EXPECT_NEAR(s.Area(), 4 * kPi * r * r, kAreaTol * 4 * kPi * r * r);
  // an ellipsoid: on x^2/a^2 + y^2/b^2 + z^2/c^2 = 1, normals along the gradient
  const Vec3 h(0.03, 0.008, 0.005);
  const Triangles e = Of(model, Primitive(mjGEOM_ELLIPSOID, GeomType::kMesh, h));
  ASSERT_FALSE(e.p.empty());
  for (std::size_t k = 0; k < e.p.size(); ++k) {
    EXPECT_NEAR(e.p[k].cwiseQuotient(h).norm(), 1.0, 1e-4);
    const Vec3 grad = e.p[k].cwiseQuotient(h.cwiseProduct(h)).normalized();
    EXPECT_GT(e.n[k].dot(grad), 1.0 - 1e-4);
  }
  double hi = 0.0;
  for (const Vec3& p : e.p) hi = std::max(hi, std::abs(p.x()));
  EXPECT_NEAR(hi, h.x(), kOnSurface);  // it reaches its long half-axis
}

TEST(ViewShapes, CylinderAndCapsule) {
  const Model model;
  const double r = 0.004, half = 0.04;
  const Triangles c = Of(model, Primitive(mjGEOM_CYLINDER, GeomType::kMesh, Vec3(r, half, 0)));
  ASSERT_FALSE(c.p.empty());
  for (std::size_t k = 0; k < c.p.size(); ++k) {
    const Vec3& p = c.p[k];
    const double radial = std::hypot(p.x(), p.y());
    const bool cap = std::abs(std::abs(p.z()) - half) < kOnSurface && std::abs(c.n[k].z()) > 0.5;
    if (cap) {
      EXPECT_LE(radial, r + kOnSurface);
      EXPECT_NEAR(c.n[k].z(), p.z() > 0 ? 1.0 : -1.0, 1e-6);
    } else {
      EXPECT_NEAR(radial, r, kOnSurface);
      EXPECT_LE(std::abs(p.z()), half + kOnSurface);
      EXPECT_NEAR(c.n[k].z(), 0.0, 1e-6);
      EXPECT_GT(c.n[k].dot(Vec3(p.x(), p.y(), 0).normalized()), 1.0 - 1e-6);
    }
  }
  const double cyl = 2 * kPi * r * 2 * half + 2 * kPi * r * r;
  EXPECT_NEAR(c.Area(), cyl, kAreaTol * cyl);
  // a capsule: every vertex r from its axis segment, normals away from the segment
  const Triangles cap = Of(model, Primitive(mjGEOM_CAPSULE, GeomType::kCapsule, Vec3(r, half, 0)));
  ASSERT_FALSE(cap.p.empty());
  for (std::size_t k = 0; k < cap.p.size(); ++k) {
    const Vec3 axis(0, 0, std::clamp(cap.p[k].z(), -half, half));
    EXPECT_NEAR((cap.p[k] - axis).norm(), r, kOnSurface);
    EXPECT_GT(cap.n[k].dot((cap.p[k] - axis).normalized()), 1.0 - 1e-5);
  }
  const double capsule = 2 * kPi * r * 2 * half + 4 * kPi * r * r;
  EXPECT_NEAR(cap.Area(), capsule, kAreaTol * capsule);
}

TEST(ViewShapes, Box) {
  const Model model;
  const Vec3 h(0.02, 0.005, 0.01);
  const Triangles b = Of(model, Primitive(mjGEOM_BOX, GeomType::kBox, h));
  ASSERT_EQ(b.p.size(), 36u);  // 6 faces, 2 triangles each
  for (std::size_t k = 0; k < b.p.size(); ++k) {
    EXPECT_LT((b.p[k].cwiseAbs() - h).norm(), kOnSurface);  // a corner
    // the face's normal points out of the face the vertex is on
    const int axis = static_cast<int>(std::lround(b.n[k].cwiseAbs().dot(Vec3(0, 1, 2))));
    EXPECT_NEAR(b.n[k][axis] * b.p[k][axis], h[axis], kOnSurface);
  }
  const double area = 8 * (h.x() * h.y() + h.y() * h.z() + h.z() * h.x());
  EXPECT_NEAR(b.Area(), area, 1e-9);
}

TEST(ViewShapes, MeshFromTheCompiledModel) {
  const Model model = LoadModel(
      std::string(RIGIDTOUCH_SOURCE_DIR) + "/tests/scenes/view_shapes.xml", LoadOptions{});
  const GeomModel* prism = nullptr;
  for (const GeomModel& g : model.geoms) {
    if (g.name == "prism") prism = &g;
  }
  ASSERT_NE(prism, nullptr);
  const Triangles t = Of(model, *prism);
  // the scene's prism: a triangle 6 cm wide, 3 cm high, 6 mm thick; its hull's surface is two
  // triangles, the base and two slopes
  const double slope = std::hypot(0.03, 0.03);
  const double area = 2 * 0.5 * 0.06 * 0.03 + 0.006 * (0.06 + 2 * slope);
  EXPECT_NEAR(t.Area(), area, 1e-6 * area);
  // in the world (the geom's pose), its vertices are the six the scene gives, at (0.05, 0, 0)
  const Mat3 R = prism->quat_B.toRotationMatrix();
  for (const Vec3& p : t.p) {
    const Vec3 w = prism->pos_B + R * p - Vec3(0.05, 0, 0);
    EXPECT_NEAR(std::abs(w.y()), 0.003, 1e-6);
    const bool base = std::abs(w.z() + 0.015) < 1e-6 && std::abs(std::abs(w.x()) - 0.03) < 1e-6;
    const bool apex = std::abs(w.z() - 0.015) < 1e-6 && std::abs(w.x()) < 1e-6;
    EXPECT_TRUE(base || apex) << w.transpose();
  }
  for (const Vec3& n : t.n) EXPECT_NEAR(n.norm(), 1.0, 1e-6);
}

TEST(ViewShapes, PlaneHasNoTriangles) {
  const Model model;
  EXPECT_TRUE(Of(model, Primitive(mjGEOM_PLANE, GeomType::kPlane, Vec3(0.5, 0.5, 0.1))).p.empty());
}

}  // namespace
}  // namespace rigidtouch::view
