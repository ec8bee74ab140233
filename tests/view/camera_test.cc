// The viewer's camera: the OpenGL matrix that places the shaded geoms maps every point to the
// pixel Project gives for it (where the overlays and the mouse are), and depth grows with distance
// from the near plane to the far one.
#include "view/camera.h"

#include <gtest/gtest.h>

#include <Eigen/Core>

namespace rigidtouch::view {
namespace {

void ExpectViewProjectionAgreesWithProject(const Camera& cam) {
  const double far_m = 1.0;
  const std::array<float, 16> m = cam.ViewProjection(far_m);
  const Eigen::Matrix4d M = Eigen::Map<const Eigen::Matrix4f>(m.data()).cast<double>();
  for (int k = 0; k < 50; ++k) {
    // points along a ray away from the eye, spread over the view
    const Vec3 dir = (cam.f + 0.3 * std::sin(k) * cam.r + 0.2 * std::cos(3 * k) * cam.u);
    const double t = 0.02 + 0.018 * k;  // 2 cm to 90 cm from the eye
    const Vec3 p = cam.eye + t * dir.normalized();
    double x = 0.0, y = 0.0;
    ASSERT_TRUE(cam.Project(p, x, y));
    const Eigen::Vector4d clip = M * Eigen::Vector4d(p.x(), p.y(), p.z(), 1.0);
    const double gx = 0.5 * cam.width_px * (1.0 + clip.x() / clip.w());
    const double gy = 0.5 * cam.height_px * (1.0 - clip.y() / clip.w());  // OpenGL's y runs up
    EXPECT_NEAR(gx, x, 0.01) << k;  // px; the matrix is single precision
    EXPECT_NEAR(gy, y, 0.01) << k;
    const double depth = clip.z() / clip.w();
    EXPECT_GT(depth, -1.0);
    EXPECT_LT(depth, 1.0);
    if (k % 10 == 0) {
      // farther along a ray, deeper (compare on one ray: the direction changes with k)
      const Vec3 q = cam.eye + (t + 0.01) * dir.normalized();
      const Eigen::Vector4d cq = M * Eigen::Vector4d(q.x(), q.y(), q.z(), 1.0);
      EXPECT_GT(cq.z() / cq.w(), depth);
    }
    // and the mouse's inverse: the point at that depth under that pixel
    EXPECT_LT((cam.Unproject(x, y, cam.Depth(p)) - p).norm(), 1e-12);
  }
}

TEST(ViewCamera, ViewProjectionAgreesWithProject) {
  ExpectViewProjectionAgreesWithProject(Camera(Vec3(0.05, 0.02, 0.03), 0.3, 1280, 720));
  // the target right of the panel: the principal point off the window's middle
  ExpectViewProjectionAgreesWithProject(Camera(Vec3(0.05, 0.02, 0.03), 0.3, 1280, 720, 490));
}

// the viewer frames the scene right of its panel when the window leaves room, else in the middle
TEST(ViewCamera, ViewerCameraFramesTheSceneRightOfThePanel) {
  SceneFrame frame;
  frame.centre = Vec3(0.1, -0.02, 0.05);
  frame.distance_m = 0.4;
  double x = 0.0, y = 0.0;
  ASSERT_TRUE(ViewerCamera(frame, 1280, 720).Project(frame.centre, x, y));
  EXPECT_NEAR(x, 0.5 * (kPanelRightPx + 1280), 1e-9);
  EXPECT_NEAR(y, 360.0, 1e-9);
  ASSERT_TRUE(ViewerCamera(frame, 800, 600).Project(frame.centre, x, y));
  EXPECT_NEAR(x, 400.0, 1e-9);  // narrower than two panels: the middle
}

TEST(ViewCamera, NearAndFarPlanesBoundDepth) {
  const Camera cam(Vec3::Zero(), 0.2, 800, 600);
  const std::array<float, 16> m = cam.ViewProjection(2.0);
  const Eigen::Matrix4d M = Eigen::Map<const Eigen::Matrix4f>(m.data()).cast<double>();
  const auto ndc_depth = [&](double t) {
    const Vec3 p = cam.eye + t * cam.f;
    const Eigen::Vector4d c = M * Eigen::Vector4d(p.x(), p.y(), p.z(), 1.0);
    return c.z() / c.w();
  };
  EXPECT_NEAR(ndc_depth(Camera::kNear), -1.0, 1e-5);
  EXPECT_NEAR(ndc_depth(2.0), 1.0, 1e-5);
  double x = 0.0, y = 0.0;
  EXPECT_FALSE(cam.Project(cam.eye + 0.5 * Camera::kNear * cam.f, x, y));  // before the near plane
}

}  // namespace
}  // namespace rigidtouch::view
