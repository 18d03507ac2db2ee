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

CameraParams meiMynt() {  // VINS-Fusion's MYNT EYE left camera (config/mynteye/left_mei.yaml)
  CameraParams p;
  p.type = ModelType::kMei;
  p.name = "MeiMyntEye";
  p.width = 752;
  p.height = 480;
  p.xi = 1.4456544769803834;
  p.dist = {-0.34363053357673362, 0.062347376791548004, 1.2608078788285675e-03, -2.1374139252651483e-04};
  p.fx = 895.94371861807986, p.fy = 897.41581479032754, p.cx = 372.21680816143993, p.cy = 238.33534175557006;
  return p;
}

CameraParams meiEuroc() {  // VINS-Fusion's EuRoC cam0 as MEI (config/euroc/cam0_mei.yaml): ξ 3.6
  CameraParams p = meiMynt();
  p.name = "MeiEuroc";
  p.xi = 3.6313355285286337;
  p.dist = {1.1757726639872075, 15.491281051140213, -8.1237172954550494e-04, 6.7297684030310243e-04};
  p.fx = 2138.7619122017772, p.fy = 2131.5886210259278, p.cx = 361.19856633263799, p.cy = 248.27644773395667;
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

TEST_P(CameraModels, EveryPixelOfTheImageRoundTrips) {
  // Every 8th pixel of the whole image (corners included) lifted and projected back.
  const auto cam = makeCamera(GetParam());
  const int w = cam->params().width, h = cam->params().height;
  int lifted = 0, total = 0;
  double worst = 0;
  const auto grid = [](int n) {  // 0, 8, 16, ... and the last pixel
    std::vector<int> g;
    for (int i = 0; i < n - 1; i += 8) g.push_back(i);
    g.push_back(n - 1);
    return g;
  };
  for (const int v : grid(h))
    for (const int u : grid(w)) {
      ++total;
      Eigen::Vector2d xy, back;
      if (!cam->liftToNormalized(Eigen::Vector2d(u, v), xy)) continue;
      ++lifted;
      ASSERT_TRUE(cam->projectNormalized(xy, back)) << u << " " << v;
      worst = std::max(worst, (back - Eigen::Vector2d(u, v)).norm());
    }
  EXPECT_LT(worst, 1e-7);
  // A pinhole and these calibrations see their whole image in front of the camera; only the
  // 195° fisheye's corners look backwards.
  if (GetParam().type == ModelType::kKannalaBrandt) {
    EXPECT_GT(lifted, total * 3 / 4);
  } else {
    EXPECT_EQ(lifted, total);
  }
}

INSTANTIATE_TEST_SUITE_P(Models, CameraModels, ::testing::Values(eurocCam0(), fisheye(), meiMynt(), meiEuroc()),
                         [](const auto& info) {
                           if (info.param.type == ModelType::kMei) return info.param.name;
                           return std::string(info.param.type == ModelType::kPinhole ? "PinholeRadtan"
                                                                                     : "KannalaBrandt");
                         });

TEST(Mei, MatchesTheUnifiedModelFormula) {
  const CameraParams p = meiMynt();
  const auto cam = makeCamera(p);
  // p = (0.6, -0.4, 2): on the sphere, then through the point ξ behind its centre.
  const Eigen::Vector3d pt(0.6, -0.4, 2.0);
  const double zz = pt.z() + p.xi * pt.norm();
  const double x = pt.x() / zz, y = pt.y() / zz, r2 = x * x + y * y;
  const double rad = 1 + p.dist[0] * r2 + p.dist[1] * r2 * r2;
  const double xd = x * rad + 2 * p.dist[2] * x * y + p.dist[3] * (r2 + 2 * x * x);
  const double yd = y * rad + p.dist[2] * (r2 + 2 * y * y) + 2 * p.dist[3] * x * y;
  Eigen::Vector2d uv;
  ASSERT_TRUE(cam->project(pt, uv));
  EXPECT_NEAR(uv.x(), p.fx * xd + p.cx, 1e-9);
  EXPECT_NEAR(uv.y(), p.fy * yd + p.cy, 1e-9);
  // ξ = 0 without distortion is a pinhole of focal γ.
  CameraParams pin = p;
  pin.xi = 0;
  pin.dist = {0, 0, 0, 0};
  ASSERT_TRUE(makeCamera(pin)->project(pt, uv));
  EXPECT_NEAR(uv.x(), p.fx * 0.3 + p.cx, 1e-9);
  EXPECT_NEAR(uv.y(), p.fy * -0.2 + p.cy, 1e-9);
}

TEST(Mei, AWideLensSeesBehindItsPlaneOnTheSphereOnly) {
  // ξ = 1 (parabolic), γ small enough that the image holds rays beyond 90°.
  CameraParams p = meiMynt();
  p.xi = 1.0;
  p.dist = {0, 0, 0, 0};
  p.fx = p.fy = 150.0;
  const Mei cam(p);
  const double theta = 1.8;  // 103° from the axis
  const Eigen::Vector3d ray(std::sin(theta), 0.0, std::cos(theta));
  Eigen::Vector2d uv, xy;
  Eigen::Vector3d back;
  ASSERT_TRUE(cam.project(ray, uv));
  ASSERT_TRUE(cam.liftToSphere(uv, back));
  EXPECT_LT((back - ray).norm(), 1e-10);
  EXPECT_FALSE(cam.liftToNormalized(uv, xy)) << "a ray behind the image plane has no x/z";
  // Beyond the fold of ξ = 2 (z/|p| <= -1/2) two rays share a pixel: not imaged.
  p.xi = 2.0;
  EXPECT_FALSE(Mei(p).project(Eigen::Vector3d(std::sin(2.2), 0, std::cos(2.2)), uv));
  EXPECT_TRUE(Mei(p).project(Eigen::Vector3d(std::sin(1.9), 0, std::cos(1.9)), uv));
  // Its focal for pixel thresholds is γ / (1 + ξ), the scale at the principal point.
  EXPECT_NEAR(Mei(p).focal(), 150.0 / 3.0, 1e-12);
}

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

TEST(KannalaBrandt, RaysPast90DegreesLiftToTheirUnitRayAndRoundTrip) {
  // A 195° lens (the TUM-VI-like calibration above): every angle up to 110° round-trips
  // project -> liftToRay to 1e-10; the normalized plane ends at 90°.
  const auto cam = makeCamera(fisheye());
  for (double deg = 0.0; deg <= 110.0; deg += 2.5)
    for (double phi : {0.3, 2.0, -2.7}) {
      const double t = deg * M_PI / 180.0;
      const Eigen::Vector3d ray(std::sin(t) * std::cos(phi), std::sin(t) * std::sin(phi), std::cos(t));
      Eigen::Vector2d uv, xy;
      Eigen::Vector3d back;
      ASSERT_TRUE(cam->project(ray, uv)) << deg;
      ASSERT_TRUE(cam->liftToRay(uv, back)) << deg;
      EXPECT_LT((back - ray).norm(), 1e-10) << deg;
      EXPECT_NEAR(back.norm(), 1.0, 1e-12);
      EXPECT_EQ(cam->liftToNormalized(uv, xy), deg < 90.0) << deg;
    }
  // A pinhole's ray is its normalized point made unit.
  const auto pin = makeCamera(eurocCam0());
  Eigen::Vector2d xy;
  Eigen::Vector3d ray;
  ASSERT_TRUE(pin->liftToNormalized({100.0, 50.0}, xy));
  ASSERT_TRUE(pin->liftToRay({100.0, 50.0}, ray));
  EXPECT_LT((ray - Eigen::Vector3d(xy.x(), xy.y(), 1.0).normalized()).norm(), 1e-15);
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
