// The simulator: IMU consistent with the ground truth, rendered images consistent
// with the written calibration and poses, masks consistent with the geometry.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "camera/camera_model.h"
#include "config/config.h"
#include "eval/image_stats.h"
#include "imu/preintegration.h"
#include "io/euroc_dataset.h"
#include "sim/camera_effects.h"
#include "sim/renderer.h"
#include "sim/simulator.h"
#include "sim_imu.h"
#include "test_util.h"

namespace idyvins::sim {
namespace {

namespace fs = std::filesystem;
using Eigen::Vector2d;
using Eigen::Vector3d;

TEST(SimImu, NoiselessImuIntegratesToGroundTruthWithin1cmOver10s) {
  for (const char* scene : {"city", "parking_lot"}) {
    const test::NoiselessEnd end = test::integrateNoiseless(scene, Trajectory(scene, 3));
    ASSERT_EQ(end.samples, 2001u);
    const imu::NavState& s1 = end.predicted;
    const GroundTruthState& truth = end.truth;
    const double err = (s1.p_w_b - truth.p_w_b).norm();
    std::printf("%s: position error after 10 s of noiseless IMU: %.2e m (path %.1f m)\n", scene, err,
                Trajectory(scene, 3).pathLength(10.0));
    EXPECT_LT(err, 0.01) << scene;
    EXPECT_LT(s1.q_w_b.angularDistance(truth.q_w_b), 1e-4) << scene;
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
    EXPECT_GT(max_tilt, 2.0 * M_PI / 180) << scene;       // some roll/pitch
    EXPECT_GT(max_yaw_rate, 10.0 * M_PI / 180) << scene;  // yaw turns
  }
}

TEST(SimImu, HandheldImuIntegratesToGroundTruthAndWalks) {
  for (const char* scene : {"city", "parking_lot"}) {
    const Trajectory traj(scene, 3, SimOptions{}.g_norm, TrajectoryStyle::kHandheld);
    const test::NoiselessEnd end = test::integrateNoiseless(scene, traj);
    // Measured 0.017 m (the 1.8 Hz gait integrated with 200 Hz midpoint steps).
    EXPECT_LT((end.predicted.p_w_b - end.truth.p_w_b).norm(), 0.03) << scene;
    EXPECT_LT(end.predicted.q_w_b.angularDistance(end.truth.q_w_b), 1e-4) << scene;
    // A brisk walk: 0.8-3 m/s at about 1.7 m, a gait bob (vertical acceleration at the step
    // rate), a few degrees of roll/pitch, and not the drone's path.
    double vmin = 1e9, vmax = 0, max_tilt = 0, max_az = 0, zmin = 1e9, zmax = -1e9, apart = 0;
    const Trajectory drone(scene, 3);
    for (double t = 0; t <= 60.0; t += 0.01) {
      const BodyState b = traj.at(t);
      vmin = std::min(vmin, b.v_w.norm());
      vmax = std::max(vmax, b.v_w.norm());
      max_tilt = std::max(max_tilt, std::acos((b.q_w_b * Vector3d::UnitZ()).z()));
      max_az = std::max(max_az, std::abs(b.a_w.z()));
      zmin = std::min(zmin, b.p_w_b.z());
      zmax = std::max(zmax, b.p_w_b.z());
      apart = std::max(apart, (b.p_w_b - drone.position(t)).norm());
    }
    EXPECT_GE(vmin, 0.8) << scene;
    EXPECT_LE(vmax, 3.0) << scene;
    EXPECT_GT(max_tilt, 3.0 * M_PI / 180) << scene;
    EXPECT_LT(max_tilt, 15.0 * M_PI / 180) << scene;
    EXPECT_GT(max_az, 2.0) << scene;
    EXPECT_GT(zmin, 1.4) << scene;
    EXPECT_LT(zmax, 2.0) << scene;
    EXPECT_GT(apart, 5.0) << scene;
  }
}

TEST(SimImu, BlockRouteLapsTheCityBlockAndItsImuIntegrates) {
  const Trajectory traj("city", 2, SimOptions{}.g_norm, TrajectoryStyle::kDrone, /*block=*/true);
  const test::NoiselessEnd end = test::integrateNoiseless("city", traj);
  EXPECT_LT((end.predicted.p_w_b - end.truth.p_w_b).norm(), 0.01);
  EXPECT_LT(end.predicted.q_w_b.angularDistance(end.truth.q_w_b), 1e-4);
  // On the streets around the block x in [60, 130], y in [-40, 0] (within the waves), all four
  // sides visited, at drone speed and tilt, above the trucks; the same places again a lap later.
  double vmin = 1e9, vmax = 0, max_tilt = 0, max_off = 0, zmin = 1e9, revisit = 1e9;
  int sides[4] = {0, 0, 0, 0};
  std::vector<Vector3d> path;
  for (double t = 0; t <= 180.0; t += 0.05) {
    const BodyState b = traj.at(t);
    const Vector3d& p = b.p_w_b;
    vmin = std::min(vmin, b.v_w.norm());
    vmax = std::max(vmax, b.v_w.norm());
    max_tilt = std::max(max_tilt, std::acos((b.q_w_b * Vector3d::UnitZ()).z()));
    zmin = std::min(zmin, p.z());
    const double d[4] = {std::abs(p.y()), std::abs(p.x() - 130), std::abs(p.y() + 40), std::abs(p.x() - 60)};
    const int k = static_cast<int>(std::min_element(d, d + 4) - d);
    if (d[k] < 0.5) ++sides[k];
    // Inside a turn the path cuts the corner; elsewhere it is on a street's centre line.
    const bool in_corner = (p.x() < 72 || p.x() > 118) && (p.y() > -12 || p.y() < -28);
    if (!in_corner) max_off = std::max(max_off, d[k]);
    path.push_back(p);
  }
  for (std::size_t i = 0; i < path.size(); ++i)  // a point 60-90 s later passes within reach
    if (i * 0.05 >= 90.0 && i * 0.05 < 100.0) {
      double best = 1e9;
      for (std::size_t j = 0; j + 1200 <= i; ++j) best = std::min(best, (path[i] - path[j]).norm());
      revisit = std::min(revisit, best);
    }
  EXPECT_GE(vmin, 1.5);
  EXPECT_LE(vmax, 3.0);
  EXPECT_LT(max_tilt, 15.0 * M_PI / 180);
  EXPECT_GT(max_tilt, 3.0 * M_PI / 180);
  EXPECT_GT(zmin, 3.4);  // trucks are 3.2 m tall
  EXPECT_LT(max_off, 0.5);
  for (int k = 0; k < 4; ++k) EXPECT_GT(sides[k], 100) << "side " << k;
  EXPECT_LT(revisit, 1.0);
}

TEST(SimScene, TrafficSeedKeepsThePlaceAndChangesTheRun) {
  const TextureBank tex(1, 3, 7);
  auto world = [&](std::uint64_t traffic_seed, int parked, const std::string& scene) {
    SceneOptions o;
    o.scene = scene;
    o.level = Level::kHigh;
    o.seed = 1;
    o.traffic_seed = traffic_seed;
    o.parked = parked;
    return buildWorld(o, tex);
  };
  auto sameQuads = [](const std::vector<Quad>& a, const std::vector<Quad>& b) {
    if (a.size() != b.size()) return false;
    for (std::size_t i = 0; i < a.size(); ++i)
      if (!a[i].origin.isApprox(b[i].origin) || a[i].texture != b[i].texture) return false;
    return true;
  };
  for (const char* scene : {"city", "parking_lot"}) {
    const World w0 = world(0, 0, scene), w1 = world(1, 0, scene), w2 = world(2, 0, scene);
    // traffic seed = seed is the single-seed run
    EXPECT_TRUE(sameQuads(w0.statics, w1.statics)) << scene;
    ASSERT_EQ(w0.vehicles.size(), w1.vehicles.size());
    for (std::size_t i = 0; i < w0.vehicles.size(); ++i) EXPECT_EQ(w0.vehicles[i].offset, w1.vehicles[i].offset);
    // another traffic seed: the same place, other traffic
    EXPECT_TRUE(sameQuads(w0.statics, w2.statics)) << scene;
    ASSERT_FALSE(w2.vehicles.empty());
    EXPECT_NE(w0.vehicles[0].offset, w2.vehicles[0].offset) << scene;
    // parked cars: static boxes (object id 0) in slots chosen by the traffic seed
    const World p5 = world(5, 4, scene), p6 = world(6, 4, scene);
    ASSERT_EQ(p5.parked.size(), 4u);
    EXPECT_EQ(p5.statics.size(), w0.statics.size() + 4 * 5);
    for (std::size_t i = w0.statics.size(); i < p5.statics.size(); ++i) EXPECT_EQ(p5.statics[i].object_id, 0);
    bool moved = false;
    for (std::size_t i = 0; i < 4; ++i) moved |= !p5.parked[i].first.isApprox(p6.parked[i].first);
    EXPECT_TRUE(moved) << scene;
    // distinct slots
    for (std::size_t i = 0; i < 4; ++i)
      for (std::size_t j = i + 1; j < 4; ++j) EXPECT_GT((p5.parked[i].first - p5.parked[j].first).norm(), 2.0) << scene;
  }
  SceneOptions garage_block;
  garage_block.scene = "parking_lot";
  garage_block.route = Route::kBlock;
  EXPECT_THROW(buildWorld(garage_block, tex), std::invalid_argument);
}

TEST(SimValidation, RigAndConfigAreEurocsAndTheImagesDiffer) {
  SimOptions standard, validation;
  standard.duration_s = validation.duration_s = 1.0;
  validation.family = Family::kValidation;
  Family parsed;
  ASSERT_TRUE(parseFamily("validation", parsed));
  EXPECT_EQ(parsed, Family::kValidation);
  EXPECT_FALSE(parseFamily("tuning", parsed));
  const Config rig = rigConfig(validation);
  EXPECT_DOUBLE_EQ(rig.cams[0].fx, 458.654);
  EXPECT_DOUBLE_EQ(rig.cams[1].cx, 379.999);
  for (const auto& cam : rig.cams)
    for (double d : cam.dist) EXPECT_EQ(d, 0.0);
  EXPECT_NEAR((rig.T_b_c[0].translation() - rig.T_b_c[1].translation()).norm(), 0.11, 1e-9);
  EXPECT_GT(Eigen::AngleAxisd(rig.T_b_c[0].linear().transpose() * rig.T_b_c[1].linear()).angle(), 1e-3);
  EXPECT_DOUBLE_EQ(rig.imu.noise.acc_n, 0.1);
  EXPECT_DOUBLE_EQ(rig.imu.noise.gyr_w, 0.0001);
  // The standard family's rig is unchanged.
  EXPECT_DOUBLE_EQ(rigConfig(standard).cams[0].fx, 380.0);
  // Written and read back as a VINS-Fusion config.
  const test::TempDir dir;
  writeVinsConfig(rig, dir.path().string(), "v.yaml");
  const Config back = loadConfig(dir / "v.yaml");
  EXPECT_DOUBLE_EQ(back.cams[1].fy, 456.134);
  EXPECT_DOUBLE_EQ(back.imu.noise.acc_w, 0.001);
  EXPECT_TRUE(back.T_b_c[1].isApprox(rig.T_b_c[1], 1e-9));
  // Other materials: the same scene looks different, with texture everywhere.
  const Scene a(standard), b(validation);
  const cv::Mat ia = a.renderFrame(0).cam[0].image, ib = b.renderFrame(0).cam[0].image;
  EXPECT_GT(cv::norm(ia, ib, cv::NORM_L1) / ia.total(), 10.0);
  cv::Scalar mean, stddev;
  cv::meanStdDev(ib, mean, stddev);
  EXPECT_GT(stddev[0], 20.0);
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
  EXPECT_NEAR(shipped.imu.noise.acc_n, written.imu.noise.acc_n, 1e-6);
  EXPECT_NEAR(shipped.imu.noise.gyr_w, written.imu.noise.gyr_w, 1e-9);
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
      std::vector<cv::Point2f> pl{cv::Point2f(uv0.x() + 1.2, uv0.y() - 0.8)},
          pr{cv::Point2f(uv1.x() - 0.9, uv1.y() + 1.1)};
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
    const cv::Mat mask =
        cv::imread((img.parent_path().parent_path() / "mask" / img.filename()).string(), cv::IMREAD_UNCHANGED);
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

TEST(SimConfig, RealismConfigsRefineRightMatchesAndRaiseTheRemovalBarCleanOnesLeaveTheDefaults) {
  test::TempDir dir;
  SimOptions o;
  const Config clean = rigConfig(o);
  EXPECT_FALSE(clean.tracker.stereo_refine);
  o.realism = realismPreset("euroc");
  const Config real = rigConfig(o);
  EXPECT_TRUE(real.tracker.stereo_refine);
  EXPECT_EQ(clean.idy.stereo.remove_chi2, 0.0) << "clean images: every repeated failure removes";
  EXPECT_EQ(real.idy.stereo.remove_chi2, 80.0);
  EXPECT_EQ(real.idy.stereo.persistent_strikes, 3);
  writeVinsConfig(clean, dir / "clean", "c.yaml");
  writeVinsConfig(real, dir / "real", "c.yaml");
  const Config clean_read = loadConfig(dir / "clean/c.yaml");
  const Config real_read = loadConfig(dir / "real/c.yaml");
  EXPECT_FALSE(clean_read.tracker.stereo_refine);
  EXPECT_TRUE(real_read.tracker.stereo_refine);
  EXPECT_EQ(clean_read.idy.stereo.remove_chi2, 0.0);
  EXPECT_EQ(real_read.idy.stereo.remove_chi2, 80.0);
  EXPECT_EQ(real_read.idy.stereo.persistent_strikes, 3);
  std::ifstream in(dir / "clean/c.yaml");
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(text.find("stereo_refine:"), std::string::npos) << "clean configs leave the defaults to the code";
  std::ifstream in_real(dir / "real/c.yaml");
  const std::string real_text((std::istreambuf_iterator<char>(in_real)), std::istreambuf_iterator<char>());
  EXPECT_NE(real_text.find("\nstereo_refine: 1\n"), std::string::npos);
  EXPECT_EQ(text.find("stereo_motion_remove_chi2:"), std::string::npos);
  EXPECT_NE(real_text.find("\nstereo_motion_remove_chi2: 80\n"), std::string::npos);
}

TEST(SimDepth, DepthImagesHoldTheRenderersDepthAndLeaveTheImagesAlone) {
  test::TempDir dir;
  SimOptions o;
  o.scene.scene = "city";
  o.duration_s = 0.1;
  simulate(o, dir / "plain");
  o.write_depth = true;
  simulate(o, dir / "depth");
  EXPECT_FALSE(fs::exists(dir.path() / "plain/mav0/cam0/depth"));
  const SceneFrame truth = Scene(o).renderFrame(0);
  const std::string stamp = std::to_string(o.t0_ns);
  for (int c = 0; c < 2; ++c) {
    const fs::path cam = fs::path("mav0") / ("cam" + std::to_string(c));
    const cv::Mat depth =
        cv::imread((dir.path() / "depth" / cam / "depth" / (stamp + ".tiff")).string(), cv::IMREAD_UNCHANGED);
    ASSERT_EQ(depth.type(), CV_32FC1) << cam;
    EXPECT_EQ(cv::norm(depth, truth.cam[c].depth, cv::NORM_INF), 0.0) << cam;
    double lo = 0, hi = 0;
    cv::minMaxLoc(depth, &lo, &hi);
    EXPECT_EQ(lo, 0.0) << "the city's sky";
    EXPECT_GT(hi, 5.0);
    const fs::path image = cam / "data" / (stamp + ".png");
    EXPECT_EQ(test::readFile((dir.path() / "plain" / image).string()),
              test::readFile((dir.path() / "depth" / image).string()));
  }
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

/// The vehicle's rendered mask against the rays that hit its box, through the rig's lens.
void expectMaskMatchesTheProjectedVehicleBox(Lens lens) {
  const TextureBank tex(1, 1, 8);
  SimOptions o;
  o.lens = lens;
  const Config rig = rigConfig(o);
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

TEST(SimRenderer, MaskMatchesTheProjectedVehicleBox) { expectMaskMatchesTheProjectedVehicleBox(Lens::kPinhole); }

TEST(SimRenderer, FisheyeMasksMatchTheProjectedVehicleBoxThroughTheirLens) {
  expectMaskMatchesTheProjectedVehicleBox(Lens::kKannalaBrandt);
  expectMaskMatchesTheProjectedVehicleBox(Lens::kMei);
}

TEST(SimRenderer, FisheyeLensesSee150DegreesAcrossTheDiagonal) {
  for (const Lens lens : {Lens::kKannalaBrandt, Lens::kMei}) {
    SimOptions o;
    o.lens = lens;
    const Config rig = rigConfig(o);
    for (int i = 0; i < 2; ++i) {
      const auto cam = camera::makeCamera(rig.cams[i]);
      EXPECT_EQ(rig.cams[i].type, lens == Lens::kMei ? camera::ModelType::kMei : camera::ModelType::kKannalaBrandt);
      // The image corner's ray is 75 degrees off the axis (the principal point is the centre).
      Vector2d xy;
      ASSERT_TRUE(cam->liftToNormalized(
          Vector2d(rig.cams[i].cx, rig.cams[i].cy) + 0.5 * Vector2d(752, 480).norm() * Vector2d(1, 0), xy));
      EXPECT_NEAR(std::atan(xy.norm()) * 180 / M_PI, 0.5 * kFisheyeDiagonalFovDeg, 1e-6);
      EXPECT_NE(rig.cam_paths[i].find(toString(lens)), std::string::npos);
    }
  }
}

constexpr std::uint64_t kTodayLeftHash = 8175068048370894342ull, kTodayRightHash = 14836506294586362930ull;

/// FNV-1a over an image's bytes.
std::uint64_t imageHash(const cv::Mat& m) {
  std::uint64_t h = 1469598103934665603ull;
  for (int y = 0; y < m.rows; ++y)
    for (int x = 0; x < m.cols * static_cast<int>(m.elemSize()); ++x)
      h = (h ^ m.ptr<std::uint8_t>(y)[x]) * 1099511628211ull;
  return h;
}

TEST(SimRealism, NoneRendersTodaysImagesByteForByte) {
  // Hashes of city high seed 2, frame 3, taken before camera realism existed (the images
  // of 37ab0b1 and earlier); realism none must keep them.
  SimOptions o;
  o.scene.scene = "city";
  o.scene.level = Level::kHigh;
  o.scene.seed = 2;
  o.duration_s = 1.0;
  o.realism = realismPreset("none");
  const Scene scene(o);
  const SceneFrame f = scene.renderFrame(3);
  EXPECT_EQ(imageHash(f.cam[0].image), kTodayLeftHash) << std::hex << imageHash(f.cam[0].image);
  EXPECT_EQ(imageHash(f.cam[1].image), kTodayRightHash) << std::hex << imageHash(f.cam[1].image);
}

TEST(SimRealism, VignettingOfAFlatFieldEqualsTheModel) {
  RealismOptions o;
  o.enabled = true;
  o.vignetting_k1 = -0.35;
  o.vignetting_k2 = 0.05;
  const int W = 752, H = 480;
  const cv::Mat v = vignettingProfile(W, H, 0.5 * (W - 1), 0.5 * (H - 1), o.vignetting_k1, o.vignetting_k2);
  const cv::Mat flat(H, W, CV_32F, cv::Scalar(200.0));
  const cv::Mat img = applySensor(flat, v, 1.0, 0, o, 1);
  // Pixel by pixel: 200 V(r), rounded.
  for (const auto& [x, y] : std::vector<std::pair<int, int>>{{375, 239}, {0, 0}, {751, 479}, {100, 300}, {600, 50}}) {
    const double r2 = ((x - 375.5) * (x - 375.5) + (y - 239.5) * (y - 239.5)) / (0.25 * (W * W + H * H));
    EXPECT_NEAR(img.at<std::uint8_t>(y, x), 200.0 * (1 + o.vignetting_k1 * r2 + o.vignetting_k2 * r2 * r2), 0.5001)
        << x << "," << y;
  }
  // The ring profile the image statistics measure, against the model's ring means.
  const eval::ImageFigures fig = eval::imageFigures(img, 30);
  for (int ring = 1; ring < eval::kVignettingRings; ++ring) {
    double model = 0;
    int n = 0;
    for (int y = 0; y < H; ++y)
      for (int x = 0; x < W; ++x) {
        const double r = std::hypot(x - 375.5, y - 239.5) / (0.5 * std::hypot(W, H));
        if (std::min(eval::kVignettingRings - 1, static_cast<int>(r * eval::kVignettingRings)) != ring) continue;
        model += 1 + o.vignetting_k1 * r * r + o.vignetting_k2 * r * r * r * r;
        ++n;
      }
    double centre = 0;
    int nc = 0;
    for (int y = 0; y < H; ++y)
      for (int x = 0; x < W; ++x) {
        const double r = std::hypot(x - 375.5, y - 239.5) / (0.5 * std::hypot(W, H));
        if (r * eval::kVignettingRings >= 1) continue;
        centre += 1 + o.vignetting_k1 * r * r + o.vignetting_k2 * r * r * r * r;
        ++nc;
      }
    EXPECT_NEAR(fig.ring_mean[ring] / fig.ring_mean[0], (model / n) / (centre / nc), 0.005) << "ring " << ring;
  }
}

TEST(SimRealism, LeftRightGainRatioIsTheConfiguredOne) {
  RealismOptions o;
  o.enabled = true;
  o.gain[1] = 0.8;
  cv::Mat radiance(120, 160, CV_32F);
  cv::RNG rng(5);
  rng.fill(radiance, cv::RNG::UNIFORM, 30.0, 220.0);
  const cv::Mat left = applySensor(radiance, {}, 1.0, 0, o, 1), right = applySensor(radiance, {}, 1.0, 1, o, 2);
  EXPECT_NEAR(cv::mean(right)[0] / cv::mean(left)[0], 0.8, 0.002);
  // With shot and read noise the means keep the ratio (noise is zero-mean).
  o.full_well = 6000;
  o.read_noise = 1.5;
  const cv::Mat nl = applySensor(radiance, {}, 1.0, 0, o, 3), nr = applySensor(radiance, {}, 1.0, 1, o, 4);
  EXPECT_NEAR(cv::mean(nr)[0] / cv::mean(nl)[0], 0.8, 0.005);
  // The noise has the configured variance: shot σ² = I·255/full_well plus read σ².
  cv::Mat diff;
  cv::Mat(nl).convertTo(diff, CV_32F);
  cv::Mat clean;
  left.convertTo(clean, CV_32F);
  diff -= clean;
  cv::Scalar mean_d, std_d;
  cv::meanStdDev(diff, mean_d, std_d);
  const double expected = std::sqrt(cv::mean(radiance)[0] * 255.0 / 6000 + 1.5 * 1.5 + 1.0 / 6.0);  // + rounding
  EXPECT_NEAR(std_d[0], expected, 0.1 * expected);
}

TEST(SimRealism, AutoExposureMovesTowardTheTargetAndStaysWithinItsLimits) {
  RealismOptions o;
  o.auto_exposure = true;
  o.ae_target = 128;
  o.ae_rate = 0.5;
  std::vector<double> meter(40, 64.0);  // a dark scene, then a bright one
  for (std::size_t k = 20; k < meter.size(); ++k) meter[k] = 256.0;
  const std::vector<double> e = autoExposureSequence(meter, o);
  EXPECT_NEAR(e[0], 2.0, 1e-12) << "starts converged";
  EXPECT_NEAR(e[19], 2.0, 1e-12);
  EXPECT_LT(e[21], 2.0);
  EXPECT_GT(e[21], 0.5) << "moves part of the way only";
  EXPECT_NEAR(e.back(), 0.5, 1e-3) << "converged on the bright scene";
  for (double x : e) EXPECT_TRUE(x >= o.ae_min && x <= o.ae_max);
  o.ae_max = 1.5;
  EXPECT_NEAR(autoExposureSequence(meter, o)[0], 1.5, 1e-12) << "clamped";
}

TEST(SimRealism, MotionBlurLengthIsImageSpeedTimesExposure) {
  SimOptions o;
  o.scene.scene = "city";
  o.scene.level = Level::kNone;
  o.scene.seed = 1;
  o.duration_s = 2.0;
  o.image_noise_sigma = 0;
  o.realism.enabled = true;
  o.realism.exposure_time_s = 0.1;
  o.realism.blur_samples = 41;
  const std::size_t k = 20;
  const double t = 1.0;
  const Trajectory traj(o.scene.scene, o.scene.seed, o.g_norm);
  const Config rig = rigConfig(o);
  auto T_w_c = [&](double time) {
    const BodyState b = traj.at(time);
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = b.q_w_b.toRotationMatrix();
    T.translation() = b.p_w_b;
    return T * rig.T_b_c[0];
  };
  // One small bright square 5 m in front of the left camera at the frame's time, nothing else.
  const Eigen::Isometry3d T0 = T_w_c(t);
  const double side = 0.05;
  auto scene_with_dot = [&](const SimOptions& opts) {
    return std::make_unique<Scene>(opts, [&](World& w, const TextureBank& tex) {
      w.statics.clear();
      w.markers.clear();
      w.vehicles.clear();
      w.sky = false;
      Quad q;
      q.origin = T0 * Vector3d(-side / 2, -side / 2, 5.0);
      q.u = T0.linear() * Vector3d::UnitX();
      q.v = T0.linear() * Vector3d::UnitY();
      q.width = q.height = side;
      q.texture = tex.index(TextureKind::kChecker, 0);
      q.tex_offset_s = tex.checkerSquare() * 1.25;  // inside a bright square
      q.tex_offset_t = tex.checkerSquare() * 0.25;
      q.two_sided = true;
      w.statics.push_back(q);
    });
  };
  auto extent = [](const cv::Mat& img) {
    cv::Mat bright = img > 25;  // background 20
    std::vector<cv::Point> pts;
    cv::findNonZero(bright, pts);
    return cv::boundingRect(pts);
  };
  SimOptions sharp_opts = o;
  sharp_opts.realism.exposure_time_s = 0;
  const cv::Rect sharp = extent(scene_with_dot(sharp_opts)->renderFrame(k).cam[0].image);
  const cv::Rect blurred = extent(scene_with_dot(o)->renderFrame(k).cam[0].image);
  // Where the square's centre projects at the start and the end of the exposure.
  const auto cam = camera::makeCamera(rig.cams[0]);
  const Vector3d centre_w = T0 * Vector3d(0, 0, 5.0);
  Vector2d uv_start, uv_end;
  ASSERT_TRUE(cam->project(T_w_c(t - 0.05).inverse() * centre_w, uv_start));
  ASSERT_TRUE(cam->project(T_w_c(t + 0.05).inverse() * centre_w, uv_end));
  const Vector2d streak = uv_end - uv_start;
  ASSERT_GT(streak.norm(), 8.0) << "the test needs a clearly visible streak";
  std::printf("streak %.1f x %.1f px; sharp %dx%d, blurred %dx%d\n", streak.x(), streak.y(), sharp.width, sharp.height,
              blurred.width, blurred.height);
  EXPECT_NEAR(blurred.width - sharp.width, std::abs(streak.x()), 1.5);
  EXPECT_NEAR(blurred.height - sharp.height, std::abs(streak.y()), 1.5);
}

}  // namespace
}  // namespace idyvins::sim
