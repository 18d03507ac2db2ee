// The simulator: IMU consistent with the ground truth, rendered images consistent
// with the written calibration and poses, masks consistent with the geometry.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "camera/camera_model.h"
#include "imu/preintegration.h"
#include "io/config.h"
#include "io/euroc_dataset.h"
#include "sim/renderer.h"
#include "sim/simulator.h"
#include "test_util.h"

namespace idyvins::sim {
namespace {

namespace fs = std::filesystem;
using Eigen::Vector2d;
using Eigen::Vector3d;

TEST(SimImu, NoiselessImuIntegratesToGroundTruthWithin1cmOver10s) {
  for (const char* scene : {"city", "parking_lot"}) {
    SimOptions o;
    o.scene.scene = scene;
    o.duration_s = 10.0;
    o.imu.scale = 0.0;
    std::vector<ImuSample> imu;
    std::vector<GroundTruthState> gt;
    synthesizeImu(Trajectory(scene, 3), o, imu, gt);
    ASSERT_EQ(imu.size(), 2001u);
    const ImuNoise noise{0.1, 0.01, 0.001, 0.0001, o.g_norm};
    const imu::Preintegration pre =
        imu::integrateBetween(imu, imu.front().t_ns, imu.back().t_ns, gt[0].ba, gt[0].bg, noise);
    imu::NavState s0{gt[0].q_w_b, gt[0].p_w_b, gt[0].v_w, gt[0].ba, gt[0].bg};
    const imu::NavState s1 = pre.predict(s0);
    const double err = (s1.p_w_b - gt.back().p_w_b).norm();
    std::printf("%s: position error after 10 s of noiseless IMU: %.2e m (path %.1f m)\n", scene, err,
                Trajectory(scene, 3).pathLength(10.0));
    EXPECT_LT(err, 0.01) << scene;
    EXPECT_LT(s1.q_w_b.angularDistance(gt.back().q_w_b), 1e-4) << scene;
  }
}

TEST(SimImu, TrajectoryIsDroneLike) {
  for (const char* scene : {"city", "parking_lot"}) {
    const Trajectory traj(scene, 1);
    double vmin = 1e9, vmax = 0, max_tilt = 0, max_yaw_rate = 0;
    for (double t = 0; t <= 60.0; t += 0.05) {
      const BodyState s = traj.at(t);
      vmin = std::min(vmin, s.v_w.norm());
      vmax = std::max(vmax, s.v_w.norm());
      max_tilt = std::max(max_tilt, std::acos((s.q_w_b * Vector3d::UnitZ()).z()));
      max_yaw_rate = std::max(max_yaw_rate, std::abs(s.omega_b.z()));
    }
    EXPECT_GE(vmin, 1.0) << scene;
    EXPECT_LE(vmax, 3.0) << scene;
    EXPECT_GT(max_tilt, 2.0 * M_PI / 180) << scene;      // some roll/pitch
    EXPECT_GT(max_yaw_rate, 10.0 * M_PI / 180) << scene;  // yaw turns
  }
}

/// A short dataset written once per test binary run.
class SimDataset : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = (fs::temp_directory_path() / ("idyvins_simds_" + std::to_string(::getpid()))).string();
    SimOptions o;
    o.scene.scene = "city";
    o.scene.level = Level::kMid;
    o.scene.seed = 2;
    o.duration_s = 1.0;
    result_ = simulate(o, dir_);
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }
  static std::string dir_;
  static SimResult result_;
};
std::string SimDataset::dir_;
SimResult SimDataset::result_;

TEST_F(SimDataset, ReadsBackThroughTheEurocReaderAndConfigReader) {
  const io::EurocDataset ds = io::readEurocDataset(dir_);
  EXPECT_EQ(ds.pairs.size(), 21u);
  EXPECT_EQ(ds.imu.size(), 201u);
  EXPECT_TRUE(ds.has_groundtruth);
  EXPECT_EQ(ds.groundtruth.size(), 201u);
  EXPECT_TRUE(ds.unmatched0.empty() && ds.unmatched1.empty());
  const Config c = loadConfig(dir_ + "/config/sim_stereo_imu_config.yaml");
  EXPECT_EQ(c.cams[0].width, 752);
  const cv::Mat img = io::loadGrayImage(ds.cam0[0], "cam0", 752, 480);
  EXPECT_EQ(img.type(), CV_8UC1);
}

TEST_F(SimDataset, ShippedSimConfigMatchesTheSimulatorsRig) {
  const Config shipped = loadConfig(std::string(IDYVINS_SOURCE_DIR) + "/config/sim/sim_stereo_imu_config.yaml");
  const Config written = loadConfig(dir_ + "/config/sim_stereo_imu_config.yaml");
  for (int i = 0; i < 2; ++i) {
    EXPECT_DOUBLE_EQ(shipped.cams[i].fx, written.cams[i].fx);
    EXPECT_DOUBLE_EQ(shipped.cams[i].dist[0], written.cams[i].dist[0]);
    EXPECT_TRUE(shipped.T_b_c[i].isApprox(written.T_b_c[i], 1e-12));
  }
  EXPECT_NEAR(shipped.imu.acc_n, written.imu.acc_n, 1e-6);
  EXPECT_NEAR(shipped.imu.gyr_w, written.imu.gyr_w, 1e-9);
}

/// Marker corners projected with the written calibration and ground truth, and
/// refined on the rendered images of both cameras.
TEST_F(SimDataset, MarkerCornersAppearWhereTheCalibrationPutsThemAndStereoDisparityMatchesDepth) {
  const io::EurocDataset ds = io::readEurocDataset(dir_);
  const Config c = loadConfig(dir_ + "/config/sim_stereo_imu_config.yaml");
  const auto cam0 = camera::makeCamera(c.cams[0]);
  const auto cam1 = camera::makeCamera(c.cams[1]);
  std::ifstream meta_in(dir_ + "/meta.json");
  const auto meta = nlohmann::json::parse(meta_in);
  std::vector<Vector3d> corners;
  for (const auto& p : meta["marker_corners_w"]) corners.emplace_back(p[0], p[1], p[2]);
  ASSERT_GE(corners.size(), 9u);
  const double baseline = (c.T_b_c[0].inverse() * c.T_b_c[1]).translation().norm();
  std::vector<double> errors, disparity_errors;
  for (const auto& pair : ds.pairs) {
    const auto& gt = *std::find_if(ds.groundtruth.begin(), ds.groundtruth.end(),
                                   [&](const GroundTruthState& s) { return s.t_ns == pair.t_ns; });
    Eigen::Isometry3d T_w_b = Eigen::Isometry3d::Identity();
    T_w_b.linear() = gt.q_w_b.toRotationMatrix();
    T_w_b.translation() = gt.p_w_b;
    const cv::Mat left = cv::imread(ds.cam0[pair.i0].path, cv::IMREAD_GRAYSCALE);
    const cv::Mat right = cv::imread(ds.cam1[pair.i1].path, cv::IMREAD_GRAYSCALE);
    for (std::size_t k = 0; k < corners.size(); ++k) {
      const Vector3d p0 = (T_w_b * c.T_b_c[0]).inverse() * corners[k];
      const Vector3d p1 = (T_w_b * c.T_b_c[1]).inverse() * corners[k];
      // Marker normal from its corner grid (3x3 per marker), must face the camera.
      const std::size_t m = k / 9 * 9;
      const Vector3d n = (corners[m + 3] - corners[m]).cross(corners[m + 1] - corners[m]).normalized();
      const Vector3d to_cam = ((T_w_b * c.T_b_c[0]).translation() - corners[k]).normalized();
      Vector2d uv0, uv1;
      if (p0.z() > 25.0 || std::abs(n.dot(to_cam)) < 0.5) continue;
      if (!cam0->project(p0, uv0) || !cam1->project(p1, uv1)) continue;
      const auto inside = [](const Vector2d& uv) { return uv.x() > 15 && uv.x() < 737 && uv.y() > 15 && uv.y() < 465; };
      if (!inside(uv0) || !inside(uv1)) continue;
      std::vector<cv::Point2f> pl{cv::Point2f(uv0.x() + 1.2, uv0.y() - 0.8)}, pr{cv::Point2f(uv1.x() - 0.9, uv1.y() + 1.1)};
      const cv::TermCriteria crit(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 50, 1e-4);
      cv::cornerSubPix(left, pl, cv::Size(4, 4), cv::Size(-1, -1), crit);
      cv::cornerSubPix(right, pr, cv::Size(4, 4), cv::Size(-1, -1), crit);
      errors.push_back((Vector2d(pl[0].x, pl[0].y) - uv0).norm());
      errors.push_back((Vector2d(pr[0].x, pr[0].y) - uv1).norm());
      Vector2d xl, xr;
      ASSERT_TRUE(cam0->liftToNormalized(Vector2d(pl[0].x, pl[0].y), xl));
      ASSERT_TRUE(cam1->liftToNormalized(Vector2d(pr[0].x, pr[0].y), xr));
      disparity_errors.push_back(std::abs(c.cams[0].fx * (xl.x() - xr.x()) - c.cams[0].fx * baseline / p0.z()));
    }
  }
  ASSERT_GE(errors.size(), 20u) << "too few marker corners in view";
  std::sort(errors.begin(), errors.end());
  std::sort(disparity_errors.begin(), disparity_errors.end());
  std::printf("marker corners: %zu observations, median error %.3f px, max %.3f px; disparity error max %.3f px\n",
              errors.size(), errors[errors.size() / 2], errors.back(), disparity_errors.back());
  EXPECT_LT(errors[errors.size() / 2], 0.15);
  EXPECT_LT(errors.back(), 0.5);
  EXPECT_LT(disparity_errors.back(), 0.5);
}

TEST_F(SimDataset, MetaCoverageMatchesTheMasks) {
  const io::EurocDataset ds = io::readEurocDataset(dir_);
  std::ifstream meta_in(dir_ + "/meta.json");
  const auto meta = nlohmann::json::parse(meta_in);
  double sum = 0, mx = 0;
  for (const auto& pair : ds.pairs) {
    const fs::path img(ds.cam0[pair.i0].path);
    const cv::Mat mask = cv::imread((img.parent_path().parent_path() / "mask" / img.filename()).string(),
                                    cv::IMREAD_UNCHANGED);
    ASSERT_EQ(mask.type(), CV_8UC1);
    const double f = static_cast<double>(cv::countNonZero(mask)) / mask.total();
    sum += f;
    mx = std::max(mx, f);
  }
  EXPECT_NEAR(meta["moving_coverage_cam0"]["mean"].get<double>(), sum / ds.pairs.size(), 1e-12);
  EXPECT_NEAR(meta["moving_coverage_cam0"]["max"].get<double>(), mx, 1e-12);
  EXPECT_GT(mx, 0.0) << "mid level must show moving vehicles";
  EXPECT_EQ(meta["moving_objects"].size(), 8u);
}

TEST(SimDeterminism, SameArgumentsGiveByteIdenticalFiles) {
  test::TempDir dir;
  SimOptions o;
  o.scene.scene = "parking_lot";
  o.scene.level = Level::kHigh;
  o.duration_s = 0.3;
  simulate(o, dir / "a");
  o.threads = 1;  // a different thread count must not change a byte
  simulate(o, dir / "b");
  std::size_t files = 0;
  for (const auto& e : fs::recursive_directory_iterator(dir.path() / "a")) {
    if (!e.is_regular_file()) continue;
    const fs::path rel = fs::relative(e.path(), dir.path() / "a");
    EXPECT_EQ(test::readFile(e.path().string()), test::readFile((dir.path() / "b" / rel).string())) << rel;
    ++files;
  }
  EXPECT_GT(files, 20u);
}

/// Exact ray / box intersection (slab method), independent of the renderer.
double rayBox(const Vector3d& o, const Vector3d& d, const Vector3d& lo, const Vector3d& hi) {
  double t0 = 0, t1 = 1e30;
  for (int i = 0; i < 3; ++i) {
    const double inv = 1.0 / d[i];
    double a = (lo[i] - o[i]) * inv, b = (hi[i] - o[i]) * inv;
    if (a > b) std::swap(a, b);
    t0 = std::max(t0, a);
    t1 = std::min(t1, b);
  }
  return t0 <= t1 ? t0 : -1;
}

TEST(SimRenderer, MaskMatchesTheProjectedVehicleBox) {
  const TextureBank tex(1, 1, 8);
  const Config rig = rigConfig(SimOptions{});
  const Renderer renderer(rig.cams[0], tex);
  World w;
  Quad ground;
  ground.origin = Vector3d(-50, -50, 0);
  ground.u = Vector3d::UnitX();
  ground.v = Vector3d::UnitY();
  ground.width = ground.height = 100;
  w.statics.push_back(ground);
  Vehicle v;
  v.id = 7;
  v.size = Vector3d(4.5, 1.8, 1.5);
  v.lane_start = Vector3d(0, 1.0, 0);
  v.lane_dir = Vector3d(1, 0.3, 0).normalized();
  v.offset = 8.0;
  v.speed = 0;
  w.vehicles.push_back(v);
  // Camera 2 m up looking along +x, slightly down.
  Eigen::Isometry3d T_w_c = Eigen::Isometry3d::Identity();
  T_w_c.linear() = Eigen::AngleAxisd(-0.15, Vector3d::UnitY()).toRotationMatrix() * rig.T_b_c[0].linear();
  T_w_c.translation() = Vector3d(0, 0, 2.0);
  const RenderOutput r = renderer.render(w.quadsAt(0.0), T_w_c, false, 0.0, 0);
  // Expected silhouette: rays hitting the (rotated) box, computed in the box frame.
  const Vector3d f = v.lane_dir, l = Vector3d::UnitZ().cross(f);
  Eigen::Matrix3d R_w_v;
  R_w_v << f, l, Vector3d::UnitZ();
  const Vector3d centre = v.position(0.0) + Vector3d(0, 0, 0.75);
  const auto cam = camera::makeCamera(rig.cams[0]);
  int expected = 0, mismatched = 0;
  for (int y = 0; y < 480; ++y)
    for (int x = 0; x < 752; ++x) {
      Vector2d xy;
      ASSERT_TRUE(cam->liftToNormalized(Vector2d(x, y), xy));
      const Vector3d d_w = T_w_c.linear() * Vector3d(xy.x(), xy.y(), 1.0);
      const Vector3d o_v = R_w_v.transpose() * (T_w_c.translation() - centre);
      const Vector3d d_v = R_w_v.transpose() * d_w;
      const bool hit = rayBox(o_v, d_v, -0.5 * v.size, 0.5 * v.size) > 0;
      expected += hit;
      mismatched += hit != (r.mask.at<std::uint8_t>(y, x) == 7);
    }
  std::printf("vehicle silhouette: %d pixels, %d differ from the mask\n", expected, mismatched);
  ASSERT_GT(expected, 2000);
  EXPECT_LE(mismatched, expected / 1000);  // boundary pixels only
  EXPECT_EQ(cv::countNonZero(r.mask), cv::countNonZero(r.mask == 7));
}

}  // namespace
}  // namespace idyvins::sim
