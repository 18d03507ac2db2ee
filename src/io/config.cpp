#include "io/config.h"

#include <yaml-cpp/yaml.h>

#include <Eigen/SVD>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/error.h"

namespace fs = std::filesystem;

namespace idyvins {
namespace {

constexpr const char* kModeNames[] = {"baseline", "ransac", "seg", "idy", "idy-pre", "idy-ba"};

/// YAML document with its file name, for messages with line numbers.
struct YamlFile {
  std::string path;
  YAML::Node root;
};

YamlFile loadYaml(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path, "cannot open file (missing or unreadable)");
  std::stringstream buffer;
  buffer << in.rdbuf();
  std::string text = buffer.str();
  // OpenCV FileStorage writes "%YAML:1.0"; yaml-cpp wants "%YAML 1.x". Keep
  // the line (as a comment) so that line numbers stay right.
  if (text.rfind("%YAML:", 0) == 0) text[0] = '#';
  YamlFile file{path, {}};
  try {
    file.root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw InputError(path, e.mark.line + 1, "YAML syntax error: " + e.msg);
  }
  if (!file.root.IsMap()) throw InputError(path, "expected a YAML map of keys");
  return file;
}

int lineOf(const YAML::Node& node) { return node.Mark().line + 1; }

YAML::Node require(const YamlFile& f, const YAML::Node& parent, const std::string& key,
                   const std::string& what) {
  YAML::Node node = parent[key];
  if (!node) throw InputError(f.path, "missing required key '" + key + "' (" + what + ")");
  return node;
}

template <typename T>
T scalarAs(const YamlFile& f, const YAML::Node& node, const std::string& key,
           const char* expected) {
  if (!node.IsScalar())
    throw InputError(f.path, lineOf(node), "key '" + key + "': expected " + expected);
  try {
    return node.as<T>();
  } catch (const YAML::Exception&) {
    throw InputError(f.path, lineOf(node),
                     "key '" + key + "': expected " + expected + ", got '" + node.Scalar() + "'");
  }
}

double getDouble(const YamlFile& f, const YAML::Node& parent, const std::string& key,
                 const std::string& what) {
  const YAML::Node node = require(f, parent, key, what);
  const double v = scalarAs<double>(f, node, key, "a number");
  if (!std::isfinite(v))
    throw InputError(f.path, lineOf(node), "key '" + key + "': expected a finite number");
  return v;
}

double getDoubleOr(const YamlFile& f, const std::string& key, double fallback) {
  const YAML::Node node = f.root[key];
  return node ? getDouble(f, f.root, key, "") : fallback;
}

int getInt(const YamlFile& f, const YAML::Node& parent, const std::string& key,
           const std::string& what) {
  return scalarAs<int>(f, require(f, parent, key, what), key, "an integer");
}

std::string getString(const YamlFile& f, const YAML::Node& parent, const std::string& key,
                      const std::string& what) {
  return scalarAs<std::string>(f, require(f, parent, key, what), key, "a string");
}

void checkPositive(const YamlFile& f, const std::string& key, double value) {
  if (!(value > 0))
    throw InputError(f.path, lineOf(f.root[key]),
                     "key '" + key + "': expected a positive value, got " + std::to_string(value));
}

/// Reads a 4x4 `!!opencv-matrix` rigid transform (rotation checked, then re-orthonormalized).
Eigen::Isometry3d getTransform(const YamlFile& f, const std::string& key) {
  const YAML::Node node = require(f, f.root, key, "4x4 !!opencv-matrix camera-to-body transform");
  const int line = lineOf(node);
  if (!node.IsMap() || !node["rows"] || !node["cols"] || !node["data"] || !node["data"].IsSequence())
    throw InputError(f.path, line, "key '" + key + "': expected an !!opencv-matrix with rows, cols, data");
  const int rows = scalarAs<int>(f, node["rows"], key + ".rows", "an integer");
  const int cols = scalarAs<int>(f, node["cols"], key + ".cols", "an integer");
  const YAML::Node data = node["data"];
  if (rows != 4 || cols != 4 || data.size() != 16) {
    throw InputError(f.path, line,
                     "key '" + key + "': expected a 4x4 matrix (16 values), got rows " +
                         std::to_string(rows) + ", cols " + std::to_string(cols) + ", " +
                         std::to_string(data.size()) + " values");
  }
  Eigen::Matrix4d m;
  for (int i = 0; i < 16; ++i) m(i / 4, i % 4) = scalarAs<double>(f, data[i], key + ".data", "a number");
  const Eigen::Matrix3d r = m.topLeftCorner<3, 3>();
  if ((r * r.transpose() - Eigen::Matrix3d::Identity()).norm() > 1e-2 || r.determinant() < 0.0 ||
      (m.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).norm() > 1e-9) {
    throw InputError(f.path, line,
                     "key '" + key + "': expected a rigid transform (rotation block orthonormal "
                     "with det +1, last row 0 0 0 1)");
  }
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(r, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = svd.matrixU() * svd.matrixV().transpose();
  t.translation() = m.topRightCorner<3, 1>();
  return t;
}

}  // namespace

const char* toString(Mode mode) { return kModeNames[static_cast<int>(mode)]; }

bool parseMode(const std::string& text, Mode& mode) {
  for (int i = 0; i < 6; ++i) {
    if (text == kModeNames[i]) {
      mode = static_cast<Mode>(i);
      return true;
    }
  }
  return false;
}

std::string modeNames() {
  std::string s;
  for (const char* n : kModeNames) s += (s.empty() ? "" : "|") + std::string(n);
  return s;
}

camera::CameraParams loadCameraFile(const std::string& path) {
  const YamlFile f = loadYaml(path);
  camera::CameraParams cam;
  const YAML::Node model_node = require(f, f.root, "model_type", "PINHOLE or KANNALA_BRANDT");
  const std::string model = scalarAs<std::string>(f, model_node, "model_type", "a string");
  if (f.root["camera_name"]) cam.name = getString(f, f.root, "camera_name", "");
  cam.width = getInt(f, f.root, "image_width", "pixels");
  cam.height = getInt(f, f.root, "image_height", "pixels");
  if (cam.width <= 0 || cam.height <= 0)
    throw InputError(path, lineOf(f.root["image_width"]), "expected a positive image size");
  if (model == "PINHOLE") {
    cam.type = camera::ModelType::kPinhole;
    const YAML::Node d = require(f, f.root, "distortion_parameters", "map with k1 k2 p1 p2");
    const YAML::Node p = require(f, f.root, "projection_parameters", "map with fx fy cx cy");
    const char* dk[] = {"k1", "k2", "p1", "p2"};
    for (int i = 0; i < 4; ++i) cam.dist[i] = getDouble(f, d, dk[i], "distortion_parameters");
    cam.fx = getDouble(f, p, "fx", "projection_parameters");
    cam.fy = getDouble(f, p, "fy", "projection_parameters");
    cam.cx = getDouble(f, p, "cx", "projection_parameters");
    cam.cy = getDouble(f, p, "cy", "projection_parameters");
  } else if (model == "KANNALA_BRANDT") {
    cam.type = camera::ModelType::kKannalaBrandt;
    const YAML::Node p = require(f, f.root, "projection_parameters",
                                 "map with k2 k3 k4 k5 mu mv u0 v0");
    const char* dk[] = {"k2", "k3", "k4", "k5"};
    for (int i = 0; i < 4; ++i) cam.dist[i] = getDouble(f, p, dk[i], "projection_parameters");
    cam.fx = getDouble(f, p, "mu", "projection_parameters");
    cam.fy = getDouble(f, p, "mv", "projection_parameters");
    cam.cx = getDouble(f, p, "u0", "projection_parameters");
    cam.cy = getDouble(f, p, "v0", "projection_parameters");
  } else {
    throw InputError(path, lineOf(model_node),
                     "unknown camera model '" + model + "' (expected PINHOLE or KANNALA_BRANDT)");
  }
  if (!(cam.fx > 0 && cam.fy > 0))
    throw InputError(path, "expected positive focal lengths, got " + std::to_string(cam.fx) +
                               ", " + std::to_string(cam.fy));
  return cam;
}

namespace {

/// cam0/cam1: camodocal files (relative to the config's folder) and body_T_camX.
void readCameras(const YamlFile& f, const std::string& path, Config& c) {
  const fs::path folder = fs::path(path).parent_path();
  for (int i = 0; i < c.num_cam; ++i) {
    const std::string key = "cam" + std::to_string(i) + "_calib";
    const std::string rel = getString(f, f.root, key, "camodocal camera file");
    const fs::path cam_path = fs::path(rel).is_absolute() ? fs::path(rel) : folder / rel;
    c.cam_paths.push_back(cam_path.string());
    camera::CameraParams cam = loadCameraFile(cam_path.string());
    if (cam.width != c.image_width || cam.height != c.image_height) {
      throw InputError(cam_path.string(),
                       "image size " + std::to_string(cam.width) + "x" + std::to_string(cam.height) +
                           " differs from the config's " + std::to_string(c.image_width) + "x" +
                           std::to_string(c.image_height));
    }
    c.cams.push_back(cam);
    c.T_b_c.push_back(getTransform(f, "body_T_cam" + std::to_string(i)));
  }
}

/// IMU noise, tracker and solver keys.
void readImuTrackerSolver(const YamlFile& f, Config& c) {
  if (c.use_imu) {
    c.imu.acc_n = getDouble(f, f.root, "acc_n", "accelerometer noise density");
    c.imu.gyr_n = getDouble(f, f.root, "gyr_n", "gyroscope noise density");
    c.imu.acc_w = getDouble(f, f.root, "acc_w", "accelerometer bias random walk");
    c.imu.gyr_w = getDouble(f, f.root, "gyr_w", "gyroscope bias random walk");
    c.imu.g_norm = getDouble(f, f.root, "g_norm", "gravity magnitude, m/s^2");
    for (const char* k : {"acc_n", "gyr_n", "acc_w", "gyr_w", "g_norm"})
      checkPositive(f, k, getDouble(f, f.root, k, ""));
  }

  c.tracker.max_cnt = getInt(f, f.root, "max_cnt", "features per frame");
  c.tracker.min_dist = getDouble(f, f.root, "min_dist", "pixels between features");
  c.tracker.f_threshold = getDouble(f, f.root, "F_threshold", "RANSAC threshold, pixels");
  c.tracker.flow_back = getInt(f, f.root, "flow_back", "0 or 1") != 0;
  if (f.root["equalize"]) c.tracker.equalize = getInt(f, f.root, "equalize", "0 or 1") != 0;
  if (f.root["stereo_gain_compensation"])
    c.tracker.stereo_gain_compensation = getInt(f, f.root, "stereo_gain_compensation", "0 or 1") != 0;
  c.tracker.stereo_epipolar_px = getDoubleOr(f, "stereo_epipolar_px", c.tracker.stereo_epipolar_px);
  checkPositive(f, "stereo_epipolar_px", c.tracker.stereo_epipolar_px);
  if (f.root["stereo_refine"]) c.tracker.stereo_refine = getInt(f, f.root, "stereo_refine", "0 or 1") != 0;
  c.solver.max_solver_time_s = getDouble(f, f.root, "max_solver_time", "seconds per solve");
  c.solver.max_num_iterations = getInt(f, f.root, "max_num_iterations", "solver iterations");
  c.solver.keyframe_parallax_px = getDouble(f, f.root, "keyframe_parallax", "pixels");
  checkPositive(f, "max_cnt", c.tracker.max_cnt);
  checkPositive(f, "max_solver_time", c.solver.max_solver_time_s);
  checkPositive(f, "max_num_iterations", c.solver.max_num_iterations);
  if (f.root["solver_time_limit"])
    c.solver.time_limited = getInt(f, f.root, "solver_time_limit", "0 or 1") != 0;
  c.solver.function_tolerance = getDoubleOr(f, "solver_function_tolerance", c.solver.function_tolerance);
  checkPositive(f, "solver_function_tolerance", c.solver.function_tolerance);
}

/// The IDY keys (DESIGN §4), all optional.
void readDynamic(const YamlFile& f, const std::string& path, Config& c) {
  c.dynamic.lambda_dy = getDoubleOr(f, "lambda_dy", 4.0);
  c.dynamic.lambda_dy_c = getDoubleOr(f, "lambda_dy_c", 1.0);
  if (f.root["confirm_outliers_dynamic"])
    c.dynamic.confirm_outliers = getInt(f, f.root, "confirm_outliers_dynamic", "0 or 1") != 0;
  if (f.root["stereo_motion_test"])
    c.dynamic.stereo.enabled = getInt(f, f.root, "stereo_motion_test", "0 or 1") != 0;
  c.dynamic.stereo.chi2 = getDoubleOr(f, "stereo_motion_chi2", c.dynamic.stereo.chi2);
  c.dynamic.stereo.sigma_px = getDoubleOr(f, "stereo_motion_sigma_px", c.dynamic.stereo.sigma_px);
  if (f.root["stereo_motion_strikes"]) {
    c.dynamic.stereo.strikes = getInt(f, f.root, "stereo_motion_strikes", "consecutive failures, >= 1");
    checkPositive(f, "stereo_motion_strikes", c.dynamic.stereo.strikes);
  }
  if (f.root["stereo_motion_anchor_frames"]) {
    c.dynamic.stereo.anchor_frames = getInt(f, f.root, "stereo_motion_anchor_frames", "frames, >= 1");
    checkPositive(f, "stereo_motion_anchor_frames", c.dynamic.stereo.anchor_frames);
  }
  c.dynamic.stereo.drift_mps = getDoubleOr(f, "stereo_motion_drift_mps", c.dynamic.stereo.drift_mps);
  c.dynamic.stereo.remove_chi2 = getDoubleOr(f, "stereo_motion_remove_chi2", c.dynamic.stereo.remove_chi2);
  if (f.root["stereo_motion_persistent_strikes"]) {
    c.dynamic.stereo.persistent_strikes =
        getInt(f, f.root, "stereo_motion_persistent_strikes", "consecutive failures, >= 0 (0 = never)");
    if (c.dynamic.stereo.persistent_strikes < 0)
      throw InputError(f.path, lineOf(f.root["stereo_motion_persistent_strikes"]),
                       "key 'stereo_motion_persistent_strikes': expected consecutive failures >= 0 (0 = never), got " +
                           std::to_string(c.dynamic.stereo.persistent_strikes));
  }
  if (!(c.dynamic.stereo.remove_chi2 >= 0))
    throw InputError(f.path, lineOf(f.root["stereo_motion_remove_chi2"]),
                     "key 'stereo_motion_remove_chi2': expected a chi2 >= 0 (0 = stereo_motion_chi2), got " +
                         std::to_string(c.dynamic.stereo.remove_chi2));
  c.dynamic.stereo.left_chi2 = getDoubleOr(f, "stereo_motion_left_chi2", c.dynamic.stereo.left_chi2);
  c.dynamic.stereo.noise_ref = getDoubleOr(f, "stereo_motion_noise_ref", c.dynamic.stereo.noise_ref);
  c.dynamic.stereo.noise_quantile = getDoubleOr(f, "stereo_motion_noise_quantile", c.dynamic.stereo.noise_quantile);
  c.dynamic.stereo.min_disparity_px =
      getDoubleOr(f, "stereo_motion_min_disparity_px", c.dynamic.stereo.min_disparity_px);
  if (!(c.dynamic.stereo.min_disparity_px >= 0))
    throw InputError(f.path, lineOf(f.root["stereo_motion_min_disparity_px"]),
                     "key 'stereo_motion_min_disparity_px': expected pixels >= 0 (0 = off), got " +
                         std::to_string(c.dynamic.stereo.min_disparity_px));
  if (!(c.dynamic.stereo.noise_ref >= 0))
    throw InputError(f.path, lineOf(f.root["stereo_motion_noise_ref"]),
                     "key 'stereo_motion_noise_ref': expected a chi2 >= 0 (0 = off), got " +
                         std::to_string(c.dynamic.stereo.noise_ref));
  if (!(c.dynamic.stereo.noise_quantile > 0 && c.dynamic.stereo.noise_quantile < 1))
    throw InputError(f.path, lineOf(f.root["stereo_motion_noise_quantile"]),
                     "key 'stereo_motion_noise_quantile': expected a quantile in (0, 1), got " +
                         std::to_string(c.dynamic.stereo.noise_quantile));
  checkPositive(f, "stereo_motion_chi2", c.dynamic.stereo.chi2);
  if (f.root["lost_track_test"])
    c.dynamic.lost_track_test = getInt(f, f.root, "lost_track_test", "0 or 1") != 0;
  checkPositive(f, "stereo_motion_sigma_px", c.dynamic.stereo.sigma_px);
  if (f.root["mode"]) {
    const std::string m = getString(f, f.root, "mode", modeNames());
    if (!parseMode(m, c.dynamic.mode))
      throw InputError(path, lineOf(f.root["mode"]),
                       "key 'mode': expected one of " + modeNames() + ", got '" + m + "'");
  }
  if (c.dynamic.lambda_dy_c > c.dynamic.lambda_dy)
    throw InputError(path, "lambda_dy_c (" + std::to_string(c.dynamic.lambda_dy_c) +
                               ") must not exceed lambda_dy (" +
                               std::to_string(c.dynamic.lambda_dy) + ")");
}

}  // namespace

Config loadConfig(const std::string& path) {
  const YamlFile f = loadYaml(path);
  Config c;
  c.path = path;
  c.use_imu = getInt(f, f.root, "imu", "1 to use the IMU, 0 for vision only") != 0;
  c.num_cam = getInt(f, f.root, "num_of_cam", "1 or 2");
  if (c.num_cam != 1 && c.num_cam != 2)
    throw InputError(path, lineOf(f.root["num_of_cam"]),
                     "key 'num_of_cam': expected 1 or 2, got " + std::to_string(c.num_cam));
  c.image_width = getInt(f, f.root, "image_width", "pixels");
  c.image_height = getInt(f, f.root, "image_height", "pixels");
  if (c.image_width <= 0 || c.image_height <= 0)
    throw InputError(path, lineOf(f.root["image_width"]), "expected a positive image size");

  readCameras(f, path, c);
  readImuTrackerSolver(f, c);
  if (f.root["estimate_td"]) c.estimate_td = getInt(f, f.root, "estimate_td", "0 or 1") != 0;
  c.td_s = getDoubleOr(f, "td", 0.0);

  readDynamic(f, path, c);
  for (auto [key, value] : {std::pair<const char*, std::string*>{"imu_topic", &c.imu_topic},
                            {"image0_topic", &c.image0_topic},
                            {"image1_topic", &c.image1_topic},
                            {"groundtruth_topic", &c.groundtruth_topic}})
    if (f.root[key]) *value = getString(f, f.root, key, "a ROS topic name");
  if (f.root["segmentation_topic"]) c.segmentation_topic = getString(f, f.root, "segmentation_topic", "a ROS topic name");
  const std::filesystem::path folder = std::filesystem::path(path).parent_path();
  for (auto [key, value] : {std::pair<const char*, std::string*>{"segmentation_rgb_ids", &c.segmentation_rgb_ids},
                            {"segmentation_vehicle_ids", &c.segmentation_vehicle_ids}})
    if (f.root[key]) *value = (folder / getString(f, f.root, key, "a file next to the config")).string();
  if (!c.segmentation_topic.empty() && (c.segmentation_rgb_ids.empty() || c.segmentation_vehicle_ids.empty()))
    throw InputError(path, lineOf(f.root["segmentation_topic"]),
                     "segmentation_topic needs segmentation_rgb_ids and segmentation_vehicle_ids (VIODE's tables)");
  return c;
}

std::string describe(const Config& c) {
  std::ostringstream o;
  o << "config: " << c.path << "\n";
  o << "  imu: " << (c.use_imu ? "yes" : "no") << ", cameras: " << c.num_cam << ", image "
    << c.image_width << "x" << c.image_height << "\n";
  for (std::size_t i = 0; i < c.cams.size(); ++i) {
    const auto& k = c.cams[i];
    o << "  cam" << i << ": " << camera::toString(k.type) << " f=(" << k.fx << ", " << k.fy
      << ") c=(" << k.cx << ", " << k.cy << ") dist=[" << k.dist[0] << ", " << k.dist[1] << ", "
      << k.dist[2] << ", " << k.dist[3] << "] from " << c.cam_paths[i] << "\n";
    const Eigen::Vector3d t = c.T_b_c[i].translation();
    o << "        t_b_c = [" << t.transpose() << "] m\n";
  }
  if (c.cams.size() == 2) {
    const Eigen::Isometry3d T_c0_c1 = c.T_b_c[0].inverse() * c.T_b_c[1];
    o << "  stereo baseline: " << T_c0_c1.translation().norm() << " m\n";
  }
  if (c.use_imu)
    o << "  imu noise: acc_n " << c.imu.acc_n << ", gyr_n " << c.imu.gyr_n << ", acc_w "
      << c.imu.acc_w << ", gyr_w " << c.imu.gyr_w << ", g_norm " << c.imu.g_norm << "\n";
  o << "  tracker: max_cnt " << c.tracker.max_cnt << ", min_dist " << c.tracker.min_dist
    << ", F_threshold " << c.tracker.f_threshold << ", flow_back " << c.tracker.flow_back << ", equalize "
    << c.tracker.equalize << ", stereo_gain_compensation " << c.tracker.stereo_gain_compensation
    << ", stereo_epipolar_px " << c.tracker.stereo_epipolar_px << ", stereo_refine " << c.tracker.stereo_refine << "\n";
  o << "  solver: max_num_iterations " << c.solver.max_num_iterations << ", max_solver_time "
    << c.solver.max_solver_time_s << " s ("
    << (c.solver.time_limited ? "applied: solver_time_limit 1, results depend on load" : "not applied: deterministic")
    << "), function_tolerance " << c.solver.function_tolerance << ", keyframe_parallax "
    << c.solver.keyframe_parallax_px << " px\n";
  o << "  td: " << c.td_s << " s (estimate_td " << c.estimate_td << ")\n";
  o << "  mode: " << toString(c.dynamic.mode) << ", lambda_dy " << c.dynamic.lambda_dy
    << " px^2, lambda_dy_c " << c.dynamic.lambda_dy_c << " px^2, outliers confirmed dynamic: "
    << (c.dynamic.confirm_outliers ? "yes" : "no") << "\n";
  o << "  stereo motion test: " << (c.dynamic.stereo.enabled ? "on" : "off") << " (chi2 " << c.dynamic.stereo.chi2
    << ", sigma " << c.dynamic.stereo.sigma_px << " px, " << c.dynamic.stereo.strikes << " strikes, anchor " << c.dynamic.stereo.anchor_frames
    << " frames, drift " << c.dynamic.stereo.drift_mps << " m/s)\n";
  return o.str();
}

}  // namespace idyvins
