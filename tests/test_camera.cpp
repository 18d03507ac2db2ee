#include <gtest/gtest.h>

#include <random>

#include "camera/camera_model.h"
#include "jacobian_check.h"

namespace idyvins::camera {
namespace {

CameraParams eurocCam0() {  // the real EuRoC cam0 calibration: strong barrel distortion
  CameraParams p;
  p.type = ModelType::kPinhole;
  p.width = 752;
  p.height = 480;
  p.fx = 458.654, p.fy = 457.296, p.cx = 367.215, p.cy = 248.375;
  p.dist = {-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05};
  return p;
}

CameraParams fisheye() {  // typical equidistant calibration (TUM-VI-like values)
  CameraParams p;
  p.type = ModelType::kKannalaBrandt;
  p.width = 512;
  p.height = 512;
  p.fx = 190.97847715128717, p.fy = 190.9733070521226, p.cx = 254.93170605935475, p.cy = 256.8974428996504;
  p.dist = {0.0034823894022493434, 0.0007150348452162257, -0.0020532361418706202, 0.00020293673591811182};
  return p;
}

/// Random points in front of the camera that land inside the image.
std::vector<Eigen::Vector3d> pointsInView(const CameraModel& cam, int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Eigen::Vector3d> pts;
  while (static_cast<int>(pts.size()) < n) {
    const Eigen::Vector2d px(u(rng) * cam.params().width, u(rng) * cam.params().height);
    Eigen::Vector2d xy;
    if (!cam.liftToNormalized(px, xy)) continue;
    const double depth = 0.5 + 20.0 * u(rng);
    pts.emplace_back(xy.x() * depth, xy.y() * depth, depth);
  }
  return pts;
}

class CameraModels : public ::testing::TestWithParam<CameraParams> {};

TEST_P(CameraModels, ProjectionJacobianMatchesNumeric) {
  const auto cam = makeCamera(GetParam());
  for (const auto& p : pointsInView(*cam, 200, 1)) {
    Eigen::Vector2d uv;
    Eigen::Matrix<double, 2, 3> J;
    ASSERT_TRUE(cam->project(p, uv, &J));
    const auto numeric = test::numericJacobian(
        [&](const Eigen::VectorXd& d) {
          Eigen::Vector2d out;
          cam->project(p + d, out);
          return Eigen::VectorXd(out);
        },
        3);
    test::expectJacobianNear(J, numeric, 1e-6);
  }
}

TEST_P(CameraModels, LiftInvertsProjectTo1e10) {
  const auto cam = makeCamera(GetParam());
  double worst = 0;
  for (const auto& p : pointsInView(*cam, 500, 2)) {
    Eigen::Vector2d uv, xy;
    ASSERT_TRUE(cam->project(p, uv));
    ASSERT_TRUE(cam->liftToNormalized(uv, xy));
    worst = std::max(worst, (xy - p.head<2>() / p.z()).norm());
  }
  EXPECT_LT(worst, 1e-10);
}

TEST(PinholeRadtan, ImageCornersRoundTrip) {
  const auto cam = makeCamera(eurocCam0());
  const double w = cam->params().width - 1, h = cam->params().height - 1;
  for (const Eigen::Vector2d& px : {Eigen::Vector2d(0, 0), Eigen::Vector2d(w, 0), Eigen::Vector2d(0, h),
                                    Eigen::Vector2d(w, h), Eigen::Vector2d(w / 2, h / 2)}) {
    Eigen::Vector2d xy, back;
    ASSERT_TRUE(cam->liftToNormalized(px, xy)) << px.transpose();
    ASSERT_TRUE(cam->projectNormalized(xy, back));
    EXPECT_LT((back - px).norm(), 1e-8) << px.transpose();
  }
}

INSTANTIATE_TEST_SUITE_P(Models, CameraModels, ::testing::Values(eurocCam0(), fisheye()), [](const auto& info) {
  return std::string(info.param.type == ModelType::kPinhole ? "PinholeRadtan" : "KannalaBrandt");
});

TEST(PinholeRadtan, MatchesTheDistortionFormula) {
  const auto cam = makeCamera(eurocCam0());
  // x = (0.3, -0.2): r² = 0.13; radial = 1 + k1 r² + k2 r⁴
  const double k1 = -0.28340811, k2 = 0.07395907, p1 = 0.00019359, p2 = 1.76187114e-05;
  const double x = 0.3, y = -0.2, r2 = 0.13, rad = 1 + k1 * r2 + k2 * r2 * r2;
  const double xd = x * rad + 2 * p1 * x * y + p2 * (r2 + 2 * x * x);
  const double yd = y * rad + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y;
  Eigen::Vector2d uv;
  ASSERT_TRUE(cam->project({0.6, -0.4, 2.0}, uv));
  EXPECT_NEAR(uv.x(), 458.654 * xd + 367.215, 1e-9);
  EXPECT_NEAR(uv.y(), 457.296 * yd + 248.375, 1e-9);
}

TEST(PinholeRadtan, BehindCameraIsRejected) {
  const auto cam = makeCamera(eurocCam0());
  Eigen::Vector2d uv;
  EXPECT_FALSE(cam->project({0.1, 0.1, -1.0}, uv));
  EXPECT_FALSE(cam->project({0.1, 0.1, 0.0}, uv));
}

TEST(KannalaBrandt, RaysBeyond90DegreesHaveNoNormalizedCoordinates) {
  const auto cam = makeCamera(fisheye());
  Eigen::Vector2d xy;
  // A 195° lens images the corner of its 512x512 sensor at θ > 90°.
  EXPECT_FALSE(cam->liftToNormalized({0.0, 0.0}, xy));
  EXPECT_TRUE(cam->liftToNormalized({400.0, 300.0}, xy));
}

TEST(KannalaBrandt, EquidistantWithoutCoefficients) {
  CameraParams p = fisheye();
  p.dist = {0, 0, 0, 0};
  const auto cam = makeCamera(p);
  // Pure equidistant: pixel radius = f θ.
  const double theta = 1.2;  // 69°, beyond a pinhole's reach
  Eigen::Vector2d uv;
  ASSERT_TRUE(cam->project({std::sin(theta), 0.0, std::cos(theta)}, uv));
  EXPECT_NEAR(uv.x() - p.cx, p.fx * theta, 1e-9);
  EXPECT_NEAR(uv.y(), p.cy, 1e-12);
}

}  // namespace
}  // namespace idyvins::camera
