#include "io/config.h"

#include <yaml-cpp/yaml.h>

#include <Eigen/SVD>
#include <charconv>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/error.h"

namespace fs = std::filesystem;

namespace idyvins {
namespace {

/// A rotation block orthonormal within this (Frobenius norm of R Rᵀ − I) is taken as it is.
constexpr double kOrthonormalTolerance = 1e-14;

constexpr const char* kModeNames[] = {"baseline", "ransac", "seg", "idy", "idy-pre", "idy-ba"};

/// YAML document with its file name, for messages with line numbers.
struct YamlFile {
  std::string path;
  YAML::Node root;
  std::vector<std::string>* keys_read = nullptr;  ///< top-level keys read, when recorded
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
  if (f.keys_read && node && parent == f.root) f.keys_read->push_back(key);
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
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = r;
  // Re-orthonormalized unless it already is to rounding (then a saved config reads back exactly).
  if ((r * r.transpose() - Eigen::Matrix3d::Identity()).norm() > kOrthonormalTolerance) {
    Eigen::JacobiSVD<Eigen::Matrix3d> svd(r, Eigen::ComputeFullU | Eigen::ComputeFullV);
    t.linear() = svd.matrixU() * svd.matrixV().transpose();
  }
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

/// The stereo motion test's keys (`stereo_motion_*`), all optional.
void readStereoMotion(const YamlFile& f, StereoMotionOptions& m) {
  if (f.root["stereo_motion_test"])
    m.enabled = getInt(f, f.root, "stereo_motion_test", "0 or 1") != 0;
  m.chi2 = getDoubleOr(f, "stereo_motion_chi2", m.chi2);
  m.sigma_px = getDoubleOr(f, "stereo_motion_sigma_px", m.sigma_px);
  if (f.root["stereo_motion_strikes"]) {
    m.strikes = getInt(f, f.root, "stereo_motion_strikes", "consecutive failures, >= 1");
    checkPositive(f, "stereo_motion_strikes", m.strikes);
  }
  if (f.root["stereo_motion_anchor_frames"]) {
    m.anchor_frames = getInt(f, f.root, "stereo_motion_anchor_frames", "frames, >= 1");
    checkPositive(f, "stereo_motion_anchor_frames", m.anchor_frames);
  }
  m.drift_mps = getDoubleOr(f, "stereo_motion_drift_mps", m.drift_mps);
  m.remove_chi2 = getDoubleOr(f, "stereo_motion_remove_chi2", m.remove_chi2);
  if (f.root["stereo_motion_persistent_strikes"]) {
    m.persistent_strikes =
        getInt(f, f.root, "stereo_motion_persistent_strikes", "consecutive failures, >= 0 (0 = never)");
    if (m.persistent_strikes < 0)
      throw InputError(f.path, lineOf(f.root["stereo_motion_persistent_strikes"]),
                       "key 'stereo_motion_persistent_strikes': expected consecutive failures >= 0 (0 = never), got " +
                           std::to_string(m.persistent_strikes));
  }
  if (!(m.remove_chi2 >= 0))
    throw InputError(f.path, lineOf(f.root["stereo_motion_remove_chi2"]),
                     "key 'stereo_motion_remove_chi2': expected a chi2 >= 0 (0 = stereo_motion_chi2), got " +
                         std::to_string(m.remove_chi2));
  m.left_chi2 = getDoubleOr(f, "stereo_motion_left_chi2", m.left_chi2);
  m.noise_ref = getDoubleOr(f, "stereo_motion_noise_ref", m.noise_ref);
  m.noise_quantile = getDoubleOr(f, "stereo_motion_noise_quantile", m.noise_quantile);
  m.min_disparity_px =
      getDoubleOr(f, "stereo_motion_min_disparity_px", m.min_disparity_px);
  if (!(m.min_disparity_px >= 0))
    throw InputError(f.path, lineOf(f.root["stereo_motion_min_disparity_px"]),
                     "key 'stereo_motion_min_disparity_px': expected pixels >= 0 (0 = off), got " +
                         std::to_string(m.min_disparity_px));
  if (!(m.noise_ref >= 0))
    throw InputError(f.path, lineOf(f.root["stereo_motion_noise_ref"]),
                     "key 'stereo_motion_noise_ref': expected a chi2 >= 0 (0 = off), got " +
                         std::to_string(m.noise_ref));
  if (!(m.noise_quantile > 0 && m.noise_quantile < 1))
    throw InputError(f.path, lineOf(f.root["stereo_motion_noise_quantile"]),
                     "key 'stereo_motion_noise_quantile': expected a quantile in (0, 1), got " +
                         std::to_string(m.noise_quantile));
  checkPositive(f, "stereo_motion_chi2", m.chi2);
}

/// The IDY keys (DESIGN §4), all optional.
void readDynamic(const YamlFile& f, const std::string& path, Config& c) {
  c.dynamic.lambda_dy = getDoubleOr(f, "lambda_dy", 4.0);
  c.dynamic.lambda_dy_c = getDoubleOr(f, "lambda_dy_c", 1.0);
  if (f.root["confirm_outliers_dynamic"])
    c.dynamic.confirm_outliers = getInt(f, f.root, "confirm_outliers_dynamic", "0 or 1") != 0;
  readStereoMotion(f, c.dynamic.stereo);
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

Config loadConfig(const std::string& path, std::vector<std::string>* keys_read) {
  YamlFile f = loadYaml(path);
  f.keys_read = keys_read;
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

namespace {

/// The shortest decimal text that reads back as the same double.
std::string number(double v) {
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof(buf), v);
  return std::string(buf, r.ptr);
}

std::string matrixYaml(const Eigen::Matrix4d& m) {
  std::string s = " !!opencv-matrix\n   rows: 4\n   cols: 4\n   dt: d\n   data: [";
  for (int i = 0; i < 16; ++i) s += (i ? ", " : "") + number(m(i / 4, i % 4));
  return s + "]\n";
}

void writeFile(const std::string& path, const std::string& text) {
  std::ofstream out(path);
  out << text;
  if (!out) throw InputError(path, "cannot write file");
}

/// key value lines of one group; a string value is quoted.
struct KeyLines {
  std::string text;
  KeyLines& operator()(const char* key, double v) { return add(key, number(v)); }
  KeyLines& operator()(const char* key, int v) { return add(key, std::to_string(v)); }
  KeyLines& operator()(const char* key, bool v) { return add(key, v ? "1" : "0"); }
  KeyLines& operator()(const char* key, const std::string& v) { return add(key, "\"" + v + "\""); }
  KeyLines& add(const char* key, const std::string& v) {
    text += std::string(key) + ": " + v + "\n";
    return *this;
  }
};

/// Every key of the config but the cameras' and the extrinsics, in groups, as saveConfig
/// writes them and describe prints them.
std::vector<std::pair<std::string, KeyLines>> keyGroups(const Config& c) {
  std::vector<std::pair<std::string, KeyLines>> g;
  g.push_back({"IMU noise (VINS-Fusion semantics, docs/conventions.md)",
                KeyLines()("acc_n", c.imu.acc_n)("gyr_n", c.imu.gyr_n)("acc_w", c.imu.acc_w)("gyr_w", c.imu.gyr_w)(
                    "g_norm", c.imu.g_norm)});
  const TrackerOptions& t = c.tracker;
  g.push_back({"Feature tracker", KeyLines()("max_cnt", t.max_cnt)("min_dist", t.min_dist)("F_threshold", t.f_threshold)(
                                      "flow_back", t.flow_back)("equalize", t.equalize)(
                                      "stereo_gain_compensation", t.stereo_gain_compensation)(
                                      "stereo_epipolar_px", t.stereo_epipolar_px)("stereo_refine", t.stereo_refine)});
  const SolverOptions& s = c.solver;
  g.push_back({"Sliding-window optimization",
                KeyLines()("max_solver_time", s.max_solver_time_s)("max_num_iterations", s.max_num_iterations)(
                    "keyframe_parallax", s.keyframe_parallax_px)("solver_time_limit", s.time_limited)(
                    "solver_function_tolerance", s.function_tolerance)});
  g.push_back({"Camera-IMU time offset: image stamp + td = IMU time (s)",
                KeyLines()("estimate_td", c.estimate_td)("td", c.td_s)});
  const DynamicOptions& d = c.dynamic;
  const StereoMotionOptions& m = d.stereo;
  g.push_back({"IDY-VINS", KeyLines()("mode", std::string(toString(d.mode)))("lambda_dy", d.lambda_dy)(
                               "lambda_dy_c", d.lambda_dy_c)("confirm_outliers_dynamic", d.confirm_outliers)(
                               "lost_track_test", d.lost_track_test)});
  g.push_back({"IDY-VINS stereo motion test",
                KeyLines()("stereo_motion_test", m.enabled)("stereo_motion_chi2", m.chi2)(
                    "stereo_motion_sigma_px", m.sigma_px)("stereo_motion_strikes", m.strikes)(
                    "stereo_motion_anchor_frames", m.anchor_frames)("stereo_motion_drift_mps", m.drift_mps)(
                    "stereo_motion_remove_chi2", m.remove_chi2)("stereo_motion_persistent_strikes", m.persistent_strikes)(
                    "stereo_motion_left_chi2", m.left_chi2)("stereo_motion_noise_ref", m.noise_ref)(
                    "stereo_motion_noise_quantile", m.noise_quantile)(
                    "stereo_motion_min_disparity_px", m.min_disparity_px)});
  KeyLines topics;
  topics("imu_topic", c.imu_topic)("image0_topic", c.image0_topic)("image1_topic", c.image1_topic);
  if (!c.groundtruth_topic.empty()) topics("groundtruth_topic", c.groundtruth_topic);
  if (!c.segmentation_topic.empty())
    topics("segmentation_topic", c.segmentation_topic)("segmentation_rgb_ids", c.segmentation_rgb_ids)(
        "segmentation_vehicle_ids", c.segmentation_vehicle_ids);
  g.push_back({"ROS1 bag topics", topics});
  return g;
}

std::string indented(const std::string& lines, const std::string& indent) {
  std::string out;
  std::istringstream in(lines);
  for (std::string line; std::getline(in, line);) out += indent + line + "\n";
  return out;
}

}  // namespace

std::string describe(const Config& c) {
  std::ostringstream o;
  o << "config: " << c.path << "\n";
  o << "  imu: " << (c.use_imu ? 1 : 0) << ", num_of_cam: " << c.num_cam << ", image_width: " << c.image_width
    << ", image_height: " << c.image_height << "\n";
  for (std::size_t i = 0; i < c.cams.size(); ++i) {
    const auto& k = c.cams[i];
    o << "  cam" << i << "_calib: " << c.cam_paths[i] << " (" << camera::toString(k.type) << " f=(" << k.fx << ", "
      << k.fy << ") c=(" << k.cx << ", " << k.cy << ") dist=[" << k.dist[0] << ", " << k.dist[1] << ", " << k.dist[2]
      << ", " << k.dist[3] << "])\n";
    const Eigen::Vector3d t = c.T_b_c[i].translation();
    o << "  body_T_cam" << i << ": t = [" << t.transpose() << "] m\n";
  }
  if (c.cams.size() == 2) {
    const Eigen::Isometry3d T_c0_c1 = c.T_b_c[0].inverse() * c.T_b_c[1];
    o << "  stereo baseline: " << T_c0_c1.translation().norm() << " m\n";
  }
  for (const auto& [title, keys] : keyGroups(c)) o << "  # " << title << "\n" << indented(keys.text, "  ");
  o << "  (max_solver_time "
    << (c.solver.time_limited ? "applied: solver_time_limit 1, results depend on load" : "not applied: deterministic")
    << ")\n";
  return o.str();
}

void saveCameraFile(const camera::CameraParams& k, const std::string& path) {
  std::string s = "%YAML:1.0\n---\n";
  const bool pinhole = k.type == camera::ModelType::kPinhole;
  s += std::string("model_type: ") + (pinhole ? "PINHOLE" : "KANNALA_BRANDT") + "\n";
  s += "camera_name: " + (k.name.empty() ? std::string("camera") : k.name) + "\n";
  s += "image_width: " + std::to_string(k.width) + "\nimage_height: " + std::to_string(k.height) + "\n";
  const char* dk[] = {"k1", "k2", "p1", "p2"};
  const char* kb[] = {"k2", "k3", "k4", "k5"};
  if (pinhole) {
    s += "distortion_parameters:\n";
    for (int i = 0; i < 4; ++i) s += std::string("   ") + dk[i] + ": " + number(k.dist[i]) + "\n";
    s += "projection_parameters:\n   fx: " + number(k.fx) + "\n   fy: " + number(k.fy) + "\n   cx: " + number(k.cx) +
         "\n   cy: " + number(k.cy) + "\n";
  } else {
    s += "projection_parameters:\n";
    for (int i = 0; i < 4; ++i) s += std::string("   ") + kb[i] + ": " + number(k.dist[i]) + "\n";
    s += "   mu: " + number(k.fx) + "\n   mv: " + number(k.fy) + "\n   u0: " + number(k.cx) + "\n   v0: " +
         number(k.cy) + "\n";
  }
  writeFile(path, s);
}

void saveConfig(const Config& c, const std::string& path) {
  const fs::path folder = fs::path(path).parent_path();
  std::string s = "%YAML:1.0\n# idyvins config (VINS-Fusion format)\n";
  s += "imu: " + std::to_string(c.use_imu ? 1 : 0) + "\nnum_of_cam: " + std::to_string(c.num_cam) + "\n";
  for (int i = 0; i < c.num_cam; ++i) {
    const std::string name = i < static_cast<int>(c.cam_paths.size()) && !c.cam_paths[i].empty()
                                 ? fs::path(c.cam_paths[i]).filename().string()
                                 : "cam" + std::to_string(i) + ".yaml";
    saveCameraFile(c.cams.at(i), (folder / name).string());
    s += "cam" + std::to_string(i) + "_calib: \"" + name + "\"\n";
  }
  s += "image_width: " + std::to_string(c.image_width) + "\nimage_height: " + std::to_string(c.image_height) + "\n";
  s += "# VINS-Fusion's key, for its readers: idyvins keeps the extrinsics fixed\nestimate_extrinsic: 0\n";
  for (int i = 0; i < c.num_cam; ++i) s += "body_T_cam" + std::to_string(i) + ":" + matrixYaml(c.T_b_c.at(i).matrix());
  for (const auto& [title, keys] : keyGroups(c)) s += "\n# " + title + "\n" + keys.text;
  writeFile(path, s);
}

}  // namespace idyvins
