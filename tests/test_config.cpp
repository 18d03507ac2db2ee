#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <regex>

#include "config/config.h"
#include "core/error.h"
#include "test_util.h"

namespace idyvins {
namespace {

using test::expectError;
using test::readFile;
using test::sharedData;
using test::TempDir;
using test::writeFile;

std::string configPath(const std::string& rel) { return std::string(IDYVINS_SOURCE_DIR) + "/config/" + rel; }

TEST(Config, ReadsViodePublishedCalibration) {
  const Config c = loadConfig(sharedData("viode_calibration/calibration.yaml"));
  EXPECT_TRUE(c.use_imu);
  EXPECT_EQ(c.num_cam, 2);
  EXPECT_EQ(c.image_width, 752);
  EXPECT_EQ(c.image_height, 480);
  ASSERT_EQ(c.cams.size(), 2u);
  EXPECT_EQ(c.cams[0].type, camera::ModelType::kPinhole);
  EXPECT_DOUBLE_EQ(c.cams[0].fx, 376.0);
  EXPECT_DOUBLE_EQ(c.cams[0].cy, 240.0);
  Eigen::Matrix3d r_expected;
  r_expected << 0, 0, 1, 1, 0, 0, 0, 1, 0;
  EXPECT_TRUE(c.T_b_c[0].linear().isApprox(r_expected));
  EXPECT_NEAR((c.T_b_c[1].translation() - c.T_b_c[0].translation()).norm(), 0.05, 1e-12);
  EXPECT_DOUBLE_EQ(c.imu.noise.acc_n, 0.2);
  EXPECT_DOUBLE_EQ(c.imu.noise.gyr_w, 4.0e-5);
  EXPECT_DOUBLE_EQ(c.imu.noise.g_norm, 9.81007);
  EXPECT_EQ(c.tracker.max_cnt, 120);
  EXPECT_TRUE(c.tracker.flow_back);
  EXPECT_EQ(c.estimator.max_num_iterations, 8);
  // IDY keys are absent in VIODE's file: defaults apply.
  EXPECT_EQ(c.mode, Mode::kIdy);
  EXPECT_DOUBLE_EQ(c.idy.lambda_dy, 4.0);
  EXPECT_DOUBLE_EQ(c.idy.lambda_dy_c, 1.0);
}

TEST(Config, ShippedConfigsLoad) {
  for (const char* rel :
       {"euroc/euroc_stereo_imu_config.yaml", "viode/viode_stereo_imu_config.yaml", "sim/sim_stereo_imu_config.yaml"}) {
    SCOPED_TRACE(rel);
    const Config c = loadConfig(configPath(rel));
    EXPECT_EQ(c.num_cam, 2);
    EXPECT_EQ(c.cams.size(), 2u);
    EXPECT_FALSE(describe(c).empty());
  }
}

/// The shipped configs and VIODE's published one.
std::vector<std::string> knownConfigs() {
  return {configPath("euroc/euroc_stereo_imu_config.yaml"), configPath("viode/viode_stereo_imu_config.yaml"),
          configPath("sim/sim_stereo_imu_config.yaml"), sharedData("viode_calibration/calibration.yaml")};
}

/// Every parameter of two configs equal, exactly (paths aside).
void expectSameParameters(const Config& a, const Config& b) {
  ASSERT_EQ(a.cams.size(), b.cams.size());
  for (std::size_t i = 0; i < a.cams.size(); ++i) {
    const auto &x = a.cams[i], &y = b.cams[i];
    EXPECT_TRUE(x.type == y.type && x.width == y.width && x.height == y.height && x.fx == y.fx && x.fy == y.fy &&
                x.cx == y.cx && x.cy == y.cy && x.dist == y.dist)
        << "camera " << i;
    EXPECT_TRUE(a.T_b_c[i].matrix() == b.T_b_c[i].matrix()) << "body_T_cam" << i;
  }
  // The listing names every other key with its value (shortest exact text), so equal
  // listings (first line and camera file paths aside) mean equal parameters.
  auto keys = [](const Config& c) {
    std::string d = describe(c);
    d = d.substr(d.find('\n') + 1);
    return std::regex_replace(d, std::regex("cam[01]_calib: [^ ]+"), "camX_calib");
  };
  EXPECT_EQ(keys(a), keys(b));
  EXPECT_EQ(a.estimator.estimate_td, b.estimator.estimate_td);
  EXPECT_EQ(a.estimator.td_s, b.estimator.td_s);
  EXPECT_EQ(a.imu.noise.acc_n, b.imu.noise.acc_n);
  EXPECT_EQ(a.idy.stereo.min_disparity_px, b.idy.stereo.min_disparity_px);
}

TEST(Config, SaveThenLoadGivesTheSameParametersForEveryKnownConfig) {
  test::TempDir dir;
  int n = 0;
  for (const std::string& path : knownConfigs()) {
    SCOPED_TRACE(path);
    const Config original = loadConfig(path);
    const std::string saved = dir / ("c" + std::to_string(n++) + "/config.yaml");
    std::filesystem::create_directories(std::filesystem::path(saved).parent_path());
    saveConfig(original, saved);
    const Config reloaded = loadConfig(saved);
    expectSameParameters(original, reloaded);
  }
}

/// Moves every numeric and 0/1 key to another valid value.
class MoveAwayFromDefaults final : public ParamVisitor {
 public:
  void section(const char*) override {}
  void param(const ParamKey& k, double& v) override {
    switch (k.rule) {
      case ParamRule::kOpenUnit:
        v = v == 0.5 ? 0.3 : 0.5;
        break;
      case ParamRule::kFraction:
        v = v == 0.5 ? 0.7 : 0.5;
        break;
      case ParamRule::kCorrelation:
        v = v == 0.3 ? 0.4 : 0.3;
        break;
      case ParamRule::kImuNoise:
        v = v == 0.5 ? 0.7 : 0.5;
        break;
      case ParamRule::kGravity:
        v = v == 9.8 ? 9.79 : 9.8;
        break;
      case ParamRule::kTimeOffset:
        v = v == 0.01 ? 0.02 : 0.01;
        break;
      default:
        v += 1.5;
    }
  }
  void param(const ParamKey&, int& v) override { v += 1; }
  void param(const ParamKey&, bool& v) override { v = !v; }
  void param(const ParamKey&, std::string&) override {}
};

TEST(Config, EveryKeyLoadReadsIsPrintedAndSaved) {
  test::TempDir dir;
  // A config with every key set away from its default.
  Config c = loadConfig(configPath("viode/viode_stereo_imu_config.yaml"));
  MoveAwayFromDefaults away;
  declareParams(away, c);
  c.estimator.estimate_anchor_ray = false;  // refused with estimate_td (EstimatedAnchorRaysNeedAFixedTimeOffset)
  c.mode = Mode::kIdyBa;
  c.groundtruth_topic = "/odometry";
  c.segmentation_topic = "/cam0/segmentation";
  c.segmentation_rgb_ids = configPath("viode/rgb_ids.txt");
  c.segmentation_vehicle_ids = configPath("viode/vehicle_ids_city_day.txt");
  saveConfig(c, dir / "all.yaml");
  std::vector<std::string> read;
  const Config loaded = loadConfig(dir / "all.yaml", &read);
  expectSameParameters(c, loaded);
  EXPECT_NE(describe(loaded), describe(loadConfig(configPath("viode/viode_stereo_imu_config.yaml"))));
  EXPECT_EQ(loaded.tracker.klt_window, frontend::TrackerParams{}.klt_window + 1);  // a value read, not a default
  EXPECT_EQ(loaded.estimator.sigma_px, backend::EstimatorOptions{}.sigma_px + 1.5);
  EXPECT_EQ(loaded.idy.stereo.noise_quantile, 0.5);
  const std::vector<std::string> declared = declaredKeyNames();
  EXPECT_GE(declared.size(), 65u);
  const std::string listing = describe(loaded), file = test::readFile(dir / "all.yaml");
  for (const std::string& key : declared) {
    EXPECT_NE(std::find(read.begin(), read.end(), key), read.end()) << key << " is declared but not read";
    EXPECT_NE(listing.find("  " + key + ":"), std::string::npos) << key << " is declared but not printed";
    EXPECT_NE(file.find("\n" + key + ":"), std::string::npos) << key << " is declared but not saved";
  }
  for (const std::string& key : read) {
    EXPECT_NE(listing.find(key + ":"), std::string::npos) << key << " is read but not printed";
    EXPECT_NE(file.find(key + ":"), std::string::npos) << key << " is read but not saved";
  }
}

TEST(Config, SavingOnlyChangedKeysLeavesDefaultsToTheCode) {
  // The simulator writes its configs this way, so that a default changed later reaches a
  // dataset rendered before (one home per parameter): the required keys and the changed ones.
  test::TempDir dir;
  Config c = loadConfig(configPath("sim/sim_stereo_imu_config.yaml"));
  c.tracker.stereo_refine = frontend::TrackerParams{}.stereo_refine == 0 ? 2 : 0;
  saveConfig(c, dir / "changed.yaml", SavedKeys::kChanged);
  const std::string file = test::readFile(dir / "changed.yaml");
  EXPECT_NE(file.find("\nstereo_refine: "), std::string::npos);
  EXPECT_NE(file.find("\nacc_w: "), std::string::npos);               // required with an IMU
  EXPECT_NE(file.find("\nmax_num_iterations: "), std::string::npos);  // required (VINS-Fusion's)
  EXPECT_EQ(file.find("\nprojection_sigma_px: "), std::string::npos);
  EXPECT_EQ(file.find("\nprior_landmark_share: "), std::string::npos);
  expectSameParameters(c, loadConfig(dir / "changed.yaml"));
  saveConfig(c, dir / "all.yaml");
  EXPECT_NE(test::readFile(dir / "all.yaml").find("\nprojection_sigma_px: "), std::string::npos);
  EXPECT_TRUE(savedWithChangedKeysOnly(dir / "changed.yaml"));
  EXPECT_FALSE(savedWithChangedKeysOnly(dir / "all.yaml"));
}

TEST(Config, DocsListEveryKeyWithItsDefault) {
  // docs/cli.md carries keyTable() verbatim: every key, its default and unit, as the code
  // declares them. On a difference the table to paste is written beside the test binary.
  const std::string table = keyTable();
  const std::string docs = readFile(std::string(IDYVINS_SOURCE_DIR) + "/docs/cli.md");
  if (docs.find(table) == std::string::npos) {
    writeFile((std::filesystem::current_path() / "config_keys.md").string(), table);
    ADD_FAILURE() << "docs/cli.md does not hold the key table; the current one is in build/tests/config_keys.md";
  }
  EXPECT_NE(table.find("| `lambda_dy` | 4 | px^2"), std::string::npos);
  EXPECT_NE(table.find("| `max_cnt` | required |"), std::string::npos);
}

TEST(Config, EurocConfigMatchesTheDatasetsOwnCalibration) {
  // The shipped EuRoC config must carry the same intrinsics and extrinsics as the
  // sensor.yaml files of the real dataset.
  const Config c = loadConfig(configPath("euroc/euroc_stereo_imu_config.yaml"));
  EXPECT_DOUBLE_EQ(c.cams[0].fx, 458.654);
  EXPECT_DOUBLE_EQ(c.cams[0].cy, 248.375);
  EXPECT_DOUBLE_EQ(c.cams[0].dist[0], -0.28340811);
  EXPECT_NEAR(c.T_b_c[0].translation().x(), -0.0216401454975, 1e-12);
  const std::string s = readFile(sharedData("euroc_v101_micro/mav0/cam1/sensor.yaml"));
  EXPECT_NE(s.find("457.587"), std::string::npos);
  EXPECT_DOUBLE_EQ(c.cams[1].fx, 457.587);
  const double baseline = (c.T_b_c[0].inverse() * c.T_b_c[1]).translation().norm();
  EXPECT_NEAR(baseline, 0.110, 0.002);
}

/// A minimal valid config + camera in a temp folder; `mutate` edits the config text.
std::string writeConfig(const TempDir& dir, const std::string& config_text, const std::string& camera_text) {
  writeFile(dir / "cam.yaml", camera_text);
  writeFile(dir / "cfg.yaml", config_text);
  return dir / "cfg.yaml";
}

const char* kCamera =
    "%YAML:1.0\n---\nmodel_type: PINHOLE\ncamera_name: c\nimage_width: 64\nimage_height: 48\n"
    "distortion_parameters:\n   k1: 0.1\n   k2: 0.0\n   p1: 0.0\n   p2: 0.0\n"
    "projection_parameters:\n   fx: 50.0\n   fy: 50.0\n   cx: 32.0\n   cy: 24.0\n";

const char* kConfig =
    "%YAML:1.0\nimu: 1\nnum_of_cam: 1\ncam0_calib: \"cam.yaml\"\nimage_width: 64\n"
    "image_height: 48\nbody_T_cam0: !!opencv-matrix\n   rows: 4\n   cols: 4\n   dt: d\n"
    "   data: [1, 0, 0, 0.1,  0, 1, 0, 0,  0, 0, 1, 0,  0, 0, 0, 1]\n"
    "acc_n: 0.1\ngyr_n: 0.01\nacc_w: 0.001\ngyr_w: 0.0001\ng_norm: 9.81\n"
    "max_cnt: 150\nmin_dist: 30\nF_threshold: 1.0\nflow_back: 1\n"
    "max_solver_time: 0.04\nmax_num_iterations: 8\nkeyframe_parallax: 10.0\n"
    "mode: ransac\nlambda_dy: 5\n";

/// Loads kConfig with `extra_keys` appended (and kCamera) from `dir`.
Config loadWith(const TempDir& dir, const std::string& extra_keys) {
  return loadConfig(writeConfig(dir, std::string(kConfig) + extra_keys, kCamera));
}

std::string replace(std::string s, const std::string& from, const std::string& to) {
  const auto pos = s.find(from);
  EXPECT_NE(pos, std::string::npos) << from;
  return s.replace(pos, from.size(), to);
}

TEST(Config, MinimalConfigWithRelativeCameraPath) {
  TempDir dir;
  const Config c = loadConfig(writeConfig(dir, kConfig, kCamera));
  EXPECT_EQ(c.num_cam, 1);
  EXPECT_DOUBLE_EQ(c.cams[0].dist[0], 0.1);
  EXPECT_DOUBLE_EQ(c.T_b_c[0].translation().x(), 0.1);
  EXPECT_EQ(c.mode, Mode::kRansac);
  EXPECT_DOUBLE_EQ(c.idy.lambda_dy, 5.0);
  EXPECT_TRUE(c.estimator.confirm_outliers);  // default
  EXPECT_FALSE(loadWith(dir, "confirm_outliers_dynamic: 0\n").estimator.confirm_outliers);
  EXPECT_TRUE(c.tracker.lost_track_test);  // default
  EXPECT_FALSE(loadWith(dir, "lost_track_test: 0\n").tracker.lost_track_test);
  expectError([&] { loadWith(dir, "lost_track_test: yes\n"); }, "lost_track_test");
  EXPECT_TRUE(c.tracker.follow_eliminated);  // default
  EXPECT_FALSE(loadWith(dir, "follow_eliminated: 0\n").tracker.follow_eliminated);
  EXPECT_FALSE(c.estimator.estimate_td);
  EXPECT_DOUBLE_EQ(c.estimator.td_s, 0.0);
  EXPECT_TRUE(c.idy.stereo.enabled);  // defaults of the stereo motion test
  EXPECT_DOUBLE_EQ(c.idy.stereo.chi2, 18.47);
  EXPECT_DOUBLE_EQ(c.idy.stereo.sigma_px, 0.25);
  EXPECT_EQ(c.idy.stereo.strikes, 2);
  EXPECT_EQ(c.idy.stereo.anchor_frames, 40);
  EXPECT_DOUBLE_EQ(c.idy.stereo.drift_mps, 0.02);
  EXPECT_DOUBLE_EQ(c.idy.stereo.remove_chi2, 0.0);
  EXPECT_EQ(c.idy.stereo.persistent_strikes, 3);
  EXPECT_DOUBLE_EQ(c.idy.stereo.left_chi2, 5.99);
  EXPECT_DOUBLE_EQ(c.idy.stereo.noise_ref, 0.1);
  EXPECT_DOUBLE_EQ(c.idy.stereo.noise_quantile, 0.25);
  EXPECT_DOUBLE_EQ(c.idy.stereo.min_disparity_px, 0.0);
  const Config s = loadConfig(writeConfig(
      dir,
      std::string(kConfig) +
          "stereo_motion_test: 0\nstereo_motion_chi2: 13.3\nstereo_motion_sigma_px: 0.4\nstereo_motion_strikes: 1\n"
          "stereo_motion_anchor_frames: 1\nstereo_motion_drift_mps: 0.1\nstereo_motion_left_chi2: 0\n"
          "stereo_motion_noise_ref: 0\nstereo_motion_noise_quantile: 0.5\nstereo_motion_min_disparity_px: 1.5\n"
          "stereo_motion_remove_chi2: 0\nstereo_motion_persistent_strikes: 0\n",
      kCamera));
  EXPECT_FALSE(s.idy.stereo.enabled);
  EXPECT_DOUBLE_EQ(s.idy.stereo.chi2, 13.3);
  EXPECT_DOUBLE_EQ(s.idy.stereo.sigma_px, 0.4);
  EXPECT_EQ(s.idy.stereo.strikes, 1);
  EXPECT_EQ(s.idy.stereo.anchor_frames, 1);
  EXPECT_DOUBLE_EQ(s.idy.stereo.drift_mps, 0.1);
  EXPECT_DOUBLE_EQ(s.idy.stereo.left_chi2, 0.0);
  EXPECT_DOUBLE_EQ(s.idy.stereo.noise_ref, 0.0);
  EXPECT_DOUBLE_EQ(s.idy.stereo.noise_quantile, 0.5);
  EXPECT_DOUBLE_EQ(s.idy.stereo.min_disparity_px, 1.5);
  EXPECT_DOUBLE_EQ(s.idy.stereo.remove_chi2, 0.0);
  EXPECT_EQ(s.idy.stereo.persistent_strikes, 0);
  expectError([&] { loadWith(dir, "stereo_motion_persistent_strikes: -1\n"); }, "stereo_motion_persistent_strikes");
  expectError([&] { loadWith(dir, "stereo_motion_remove_chi2: -1\n"); }, "stereo_motion_remove_chi2");
  expectError([&] { loadWith(dir, "stereo_motion_noise_ref: -1\n"); }, "stereo_motion_noise_ref");
  expectError([&] { loadWith(dir, "stereo_motion_noise_quantile: 1\n"); }, "stereo_motion_noise_quantile");
  expectError([&] { loadWith(dir, "stereo_motion_min_disparity_px: -2\n"); }, "stereo_motion_min_disparity_px");
  expectError([&] { loadWith(dir, "stereo_motion_sigma_px: 0\n"); }, "stereo_motion_sigma_px");
}

TEST(Config, SolverTimeLimitIsOffUnlessAskedFor) {
  TempDir dir;
  const Config c = loadConfig(writeConfig(dir, kConfig, kCamera));
  EXPECT_FALSE(c.estimator.time_limited) << "offline solves must not depend on the clock";
  EXPECT_DOUBLE_EQ(c.estimator.max_solver_time_s, 0.04);   // read, kept for live use
  EXPECT_DOUBLE_EQ(c.estimator.function_tolerance, 1e-4);  // measured default (Ceres' own is 1e-6)
  EXPECT_DOUBLE_EQ(loadWith(dir, "solver_function_tolerance: 1e-6\n").estimator.function_tolerance, 1e-6);
  const Config live = loadWith(dir, "solver_time_limit: 1\n");
  EXPECT_TRUE(live.estimator.time_limited);
  EXPECT_NE(describe(live).find("applied"), std::string::npos);
  expectError([&] { loadWith(dir, "solver_time_limit: yes\n"); }, "solver_time_limit");
}

TEST(Config, KannalaBrandtCamera) {
  TempDir dir;
  writeFile(dir / "kb.yaml",
            "%YAML:1.0\n---\nmodel_type: KANNALA_BRANDT\ncamera_name: c\nimage_width: 752\n"
            "image_height: 480\nprojection_parameters:\n   k2: 0.01\n   k3: -0.002\n   k4: 0.0003\n"
            "   k5: -0.00004\n   mu: 380.0\n   mv: 381.0\n   u0: 370.0\n   v0: 240.0\n");
  const auto cam = loadCameraFile(dir / "kb.yaml");
  EXPECT_EQ(cam.type, camera::ModelType::kKannalaBrandt);
  EXPECT_DOUBLE_EQ(cam.fx, 380.0);
  EXPECT_DOUBLE_EQ(cam.fy, 381.0);
  EXPECT_DOUBLE_EQ(cam.cx, 370.0);
  EXPECT_DOUBLE_EQ(cam.dist[0], 0.01);
  EXPECT_DOUBLE_EQ(cam.dist[3], -0.00004);
}

TEST(Config, MissingFile) {
  expectError([] { loadConfig("/nonexistent/cfg.yaml"); }, "/nonexistent/cfg.yaml: cannot open");
}

TEST(Config, MissingRequiredKeyIsNamed) {
  TempDir dir;
  const auto path = writeConfig(dir, replace(kConfig, "acc_n: 0.1\n", ""), kCamera);
  expectError([&] { loadConfig(path); }, "cfg.yaml: missing required key 'acc_n'");
}

TEST(Config, MissingFrontEndAndSolverKeysTakeTheDefaultsWithOneWarning) {
  // VINS-Fusion's simulation config has none of them (VINS-Fusion reads 0 for each).
  TempDir dir;
  std::string text = kConfig;
  for (const char* line : {"max_cnt: 150\n", "min_dist: 30\n", "F_threshold: 1.0\n", "flow_back: 1\n",
                           "max_solver_time: 0.04\n", "max_num_iterations: 8\n", "keyframe_parallax: 10.0\n"})
    text = replace(text, line, "");
  const Config c = loadConfig(writeConfig(dir, text, kCamera));
  const Config defaults;
  EXPECT_EQ(c.tracker.max_cnt, defaults.tracker.max_cnt);
  EXPECT_EQ(c.estimator.max_num_iterations, defaults.estimator.max_num_iterations);
  std::size_t named = 0;
  for (const std::string& w : c.warnings)
    if (w.find("VINS-Fusion keys missing, idyvins' defaults used") != std::string::npos) {
      ++named;
      for (const char* key : {"max_cnt 150", "min_dist 30", "F_threshold 1", "flow_back 1", "max_solver_time 0.04",
                              "max_num_iterations 8", "keyframe_parallax 10"})
        EXPECT_NE(w.find(key), std::string::npos) << key << " in: " << w;
    }
  EXPECT_EQ(named, 1u);
}

TEST(Config, WrongMatrixSizeNamesTheLine) {
  TempDir dir;
  const auto path = writeConfig(dir, replace(kConfig, "rows: 4", "rows: 3"), kCamera);
  expectError([&] { loadConfig(path); }, "cfg.yaml:7: key 'body_T_cam0': expected a 4x4 matrix");
  const auto path2 = writeConfig(dir, replace(kConfig, "0, 0, 0, 1]", "0, 0, 1]"), kCamera);
  expectError([&] { loadConfig(path2); }, "got rows 4, cols 4, 15 values");
}

TEST(Config, NonRigidTransformRefused) {
  TempDir dir;
  const auto path = writeConfig(dir, replace(kConfig, "[1, 0, 0, 0.1", "[2, 0, 0, 0.1"), kCamera);
  expectError([&] { loadConfig(path); }, "rotation block not orthonormal (|R R^T - I| = 3, expected below 1e-6");
  const auto flipped = writeConfig(dir, replace(kConfig, "[1, 0, 0, 0.1", "[-1, 0, 0, 0.1"), kCamera);
  expectError([&] { loadConfig(flipped); }, "expected a rigid transform");  // det -1: a reflection
}

TEST(Config, UnknownCameraModel) {
  TempDir dir;
  const auto path = writeConfig(dir, kConfig, replace(kCamera, "PINHOLE", "SCARAMUZZA"));
  expectError([&] { loadConfig(path); }, "cam.yaml:3: unknown camera model 'SCARAMUZZA'");
}

TEST(Config, MeiCameraAsCamodocalWritesItAndBack) {
  // The layout of camodocal's MEI files (VINS-Fusion's MYNT EYE and EuRoC *_mei.yaml), with
  // the MYNT EYE left camera's published numbers.
  TempDir dir;
  writeFile(dir / "mei.yaml",
            "%YAML:1.0\n---\nmodel_type: MEI\ncamera_name: camera\nimage_width: 752\nimage_height: 480\n"
            "mirror_parameters:\n   xi: 1.4456544769803834e+00\ndistortion_parameters:\n"
            "   k1: -3.4363053357673362e-01\n   k2: 6.2347376791548004e-02\n   p1: 1.2608078788285675e-03\n"
            "   p2: -2.1374139252651483e-04\nprojection_parameters:\n   gamma1: 8.9594371861807986e+02\n"
            "   gamma2: 8.9741581479032754e+02\n   u0: 3.7221680816143993e+02\n   v0: 2.3833534175557006e+02\n");
  const auto cam = loadCameraFile(dir / "mei.yaml");
  EXPECT_EQ(cam.type, camera::ModelType::kMei);
  EXPECT_DOUBLE_EQ(cam.xi, 1.4456544769803834);
  EXPECT_DOUBLE_EQ(cam.dist[0], -0.34363053357673362);
  EXPECT_DOUBLE_EQ(cam.dist[3], -2.1374139252651483e-04);
  EXPECT_DOUBLE_EQ(cam.fx, 895.94371861807986);
  EXPECT_DOUBLE_EQ(cam.fy, 897.41581479032754);
  EXPECT_DOUBLE_EQ(cam.cx, 372.21680816143993);
  EXPECT_DOUBLE_EQ(cam.cy, 238.33534175557006);
  saveCameraFile(cam, dir / "back.yaml");
  const auto back = loadCameraFile(dir / "back.yaml");
  EXPECT_EQ(back.type, camera::ModelType::kMei);
  EXPECT_EQ(back.xi, cam.xi);
  EXPECT_EQ(back.dist, cam.dist);
  EXPECT_EQ(back.fx, cam.fx);
  EXPECT_EQ(back.cy, cam.cy);
  // A mirror parameter out of range, and a missing block, are named with their line.
  writeFile(dir / "bad.yaml", replace(readFile(dir / "mei.yaml"), "xi: 1.44", "xi: -1.44"));
  expectError([&] { loadCameraFile(dir / "bad.yaml"); }, "bad.yaml:8: expected the mirror parameter xi in [0, 10]");
  writeFile(dir / "nomirror.yaml", replace(readFile(dir / "mei.yaml"), "mirror_parameters", "mirror"));
  expectError([&] { loadCameraFile(dir / "nomirror.yaml"); }, "missing required key 'mirror_parameters'");
}

TEST(Config, TrackerImageKeys) {
  TempDir dir;
  const Config plain = loadConfig(writeConfig(dir, kConfig, kCamera));
  EXPECT_FALSE(plain.tracker.equalize);
  EXPECT_TRUE(plain.tracker.stereo_gain_compensation);
  EXPECT_DOUBLE_EQ(plain.tracker.stereo_epipolar_px, 2.0);
  EXPECT_EQ(plain.tracker.stereo_refine, 0);
  const Config set = loadConfig(writeConfig(
      dir,
      std::string(kConfig) + "equalize: 1\nstereo_gain_compensation: 0\nstereo_epipolar_px: 1.0\nstereo_refine: 1\n",
      kCamera));
  EXPECT_TRUE(set.tracker.equalize);
  EXPECT_FALSE(set.tracker.stereo_gain_compensation);
  EXPECT_DOUBLE_EQ(set.tracker.stereo_epipolar_px, 1.0);
  EXPECT_EQ(set.tracker.stereo_refine, 1);
  EXPECT_EQ(loadWith(dir, "stereo_refine: 2\n").tracker.stereo_refine, 2);
  expectError([&] { loadWith(dir, "stereo_refine: yes\n"); }, "stereo_refine");
  expectError([&] { loadWith(dir, "stereo_refine: 3\n"); }, "expected 0 (off), 1 (affine) or 2 (translation)");
  expectError([&] { loadWith(dir, "stereo_refine: -1\n"); }, "stereo_refine");
  expectError([&] { loadWith(dir, "stereo_epipolar_px: 0\n"); }, "stereo_epipolar_px");
  expectError([&] { loadWith(dir, "equalize: clahe\n"); }, "equalize");
  const Config euroc = loadConfig(std::string(IDYVINS_SOURCE_DIR) + "/config/euroc/euroc_stereo_imu_config.yaml");
  EXPECT_TRUE(euroc.tracker.equalize) << "measured on the real excerpt (test_frontend)";
  EXPECT_DOUBLE_EQ(euroc.tracker.stereo_epipolar_px, 1.0);
  EXPECT_EQ(euroc.tracker.stereo_refine, 1) << "measured on the real excerpt (test_frontend)";
}

TEST(Config, BadValuesNameKeyAndLine) {
  TempDir dir;
  auto path = writeConfig(dir, replace(kConfig, "max_cnt: 150", "max_cnt: lots"), kCamera);
  expectError([&] { loadConfig(path); }, "cfg.yaml:17: key 'max_cnt': expected an integer, got 'lots'");
  path = writeConfig(dir, replace(kConfig, "mode: ransac", "mode: magic"), kCamera);
  expectError([&] { loadConfig(path); }, "key 'mode': expected one of baseline|ransac|seg|idy|idy-pre|idy-ba");
  path = writeConfig(dir, replace(kConfig, "gyr_n: 0.01", "gyr_n: -0.01"), kCamera);
  expectError([&] { loadConfig(path); }, "key 'gyr_n': expected a plausible IMU noise value in (0, 10]");
  // Values no IMU or camera has (issue: 'acc_n: 1e300' and 'fx: 1e300' were accepted).
  path = writeConfig(dir, replace(kConfig, "acc_n: 0.1", "acc_n: 1e300"), kCamera);
  expectError([&] { loadConfig(path); }, "key 'acc_n': expected a plausible IMU noise value in (0, 10]");
  path = writeConfig(dir, replace(kConfig, "g_norm: 9.81", "g_norm: 98.1"), kCamera);
  expectError([&] { loadConfig(path); }, "key 'g_norm': expected a gravity magnitude in [9, 10.5]");
  path = writeConfig(dir, kConfig, replace(kCamera, "fx: 50.0", "fx: 1e300"));
  expectError([&] { loadConfig(path); }, "expected focal lengths in (0, 6400] px for a 64x48 image");
  path = writeConfig(dir, kConfig, replace(kCamera, "cx: 32.0", "cx: 320.0"));
  expectError([&] { loadConfig(path); }, "expected the principal point inside the 64x48 image");
  path = writeConfig(dir, replace(kConfig, "num_of_cam: 1", "num_of_cam: 3"), kCamera);
  expectError([&] { loadConfig(path); }, "key 'num_of_cam': expected 1 or 2, got 3");
  // A camera file whose size differs from the config's (VINS-Fusion's KITTI raw 09_30 and
  // simulation configs): the config's size is used, with a warning; a principal point outside
  // it is still refused.
  path = writeConfig(dir, replace(kConfig, "image_width: 64", "image_width: 640"), kCamera);
  const Config wider = loadConfig(path);
  EXPECT_EQ(wider.cams.at(0).width, 640);
  EXPECT_EQ(wider.cams.at(0).height, 48);
  ASSERT_FALSE(wider.warnings.empty());
  EXPECT_NE(
      wider.warnings.front().find("cam.yaml: image size 64x48 differs from the config's 640x48; the config's is used"),
      std::string::npos)
      << wider.warnings.front();
  path = writeConfig(dir, replace(kConfig, "image_width: 64", "image_width: 20"), kCamera);
  expectError([&] { loadConfig(path); }, "cam.yaml: expected the principal point inside the 20x48 image");
  path = writeConfig(dir, kConfig, replace(kCamera, "   fx: 50.0\n", ""));
  expectError([&] { loadConfig(path); }, "cam.yaml: missing required key 'fx'");
  path = writeConfig(dir, replace(kConfig, "imu: 1\n", "imu: [1\n"), kCamera);
  expectError([&] { loadConfig(path); }, "cfg.yaml:");
}

TEST(Config, AKeyWrittenTwiceIsRefused) {
  TempDir dir;
  const auto path = writeConfig(dir, std::string(kConfig) + "lambda_dy: 6\n", kCamera);  // kConfig has lambda_dy: 5
  expectError([&] { loadConfig(path); }, "cfg.yaml:26: key 'lambda_dy' written twice (first at line 25)");
  expectError([&] { loadConfig(writeConfig(dir, kConfig, std::string(kCamera) + "image_width: 64\n")); },
              "cam.yaml:17: key 'image_width' written twice (first at line 5)");
}

TEST(Config, EstimatedAnchorRaysNeedAFixedTimeOffset) {
  TempDir dir;
  const Config on = loadWith(dir, "estimate_anchor_ray: 1\n");
  EXPECT_TRUE(on.estimator.estimate_anchor_ray);
  EXPECT_FALSE(loadConfig(writeConfig(dir, kConfig, kCamera)).estimator.estimate_anchor_ray);
  const std::string both = std::string(kConfig) + "estimate_td: 1\nestimate_anchor_ray: 1\n";
  expectError([&] { loadConfig(writeConfig(dir, both, kCamera)); },
              "estimate_anchor_ray has no time-offset form: set estimate_td 0 with it");
}

TEST(Config, ImuSpikesMustBeShorterThanTheLargestImuGap) {
  TempDir dir;
  const Config c = loadWith(dir, "imu_spike_acc: 80\nimu_spike_max_ms: 30\n");
  EXPECT_DOUBLE_EQ(c.imu.spike.acc_mps2, 80.0);
  EXPECT_DOUBLE_EQ(c.imu.spike.max_ms, 30.0);
  EXPECT_DOUBLE_EQ(loadConfig(writeConfig(dir, kConfig, kCamera)).imu.spike.max_ms, 50.0);
  EXPECT_DOUBLE_EQ(loadWith(dir, "imu_spike_max_ms: 0\n").imu.spike.max_ms, 0.0);
  expectError([&] { loadWith(dir, "imu_spike_max_ms: 150\n"); },
              "imu_spike_max_ms (150) must be below max_imu_gap (100 ms): a dropped spike leaves a gap to bridge");
  expectError([&] { loadWith(dir, "max_imu_gap: 0.04\n"); }, "imu_spike_max_ms (50) must be below max_imu_gap (40 ms)");
  expectError([&] { loadWith(dir, "imu_spike_gyr: -1\n"); }, "key 'imu_spike_gyr': expected");
}

TEST(Config, TrackDropoutIsAShareOfAThousand) {
  TempDir dir;
  const Config c = loadWith(dir, "track_dropout_permille: 20\ntrack_dropout_seed: 3\n");
  EXPECT_EQ(c.tracker.track_dropout_permille, 20);
  EXPECT_EQ(c.tracker.track_dropout_seed, 3);
  EXPECT_EQ(loadConfig(writeConfig(dir, kConfig, kCamera)).tracker.track_dropout_permille, 0);
  expectError([&] { loadWith(dir, "track_dropout_permille: 1001\n"); },
              "key 'track_dropout_permille': expected 0 to 1000, got 1001");
}

TEST(Config, ModeNames) {
  Mode m{};
  for (const char* name : {"baseline", "ransac", "seg", "idy", "idy-pre", "idy-ba"}) {
    ASSERT_TRUE(parseMode(name, m));
    EXPECT_STREQ(toString(m), name);
  }
  EXPECT_FALSE(parseMode("IDY", m));
}

}  // namespace
TEST(Config, FuzzFindingsAreRefusedWithOneClearError) {
  // Inputs libFuzzer found (scripts/fuzz.sh), kept as regressions: each reader must throw
  // InputError, nothing else. File names start with the fuzz target's name.
  int replayed = 0;
  for (const auto& e : std::filesystem::directory_iterator(IDYVINS_SOURCE_DIR "/tests/fuzz/regressions")) {
    const std::string name = e.path().filename().string(), path = e.path().string();
    SCOPED_TRACE(name);
    if (name.rfind("camera_", 0) == 0)
      EXPECT_THROW(loadCameraFile(path), InputError);
    else if (name.rfind("config_", 0) == 0)
      EXPECT_THROW(loadConfig(path), InputError);
    else
      continue;
    ++replayed;
  }
  EXPECT_GE(replayed, 1);
}

}  // namespace idyvins
