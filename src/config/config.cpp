#include "config/config.h"

#include <yaml-cpp/yaml.h>

#include <Eigen/SVD>
#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "camera/camera_model.h"
#include "config/modes.h"
#include "core/error.h"

namespace fs = std::filesystem;

namespace idyvins {
namespace {

/// A rotation block orthonormal within this (Frobenius norm of R Rᵀ − I) is taken as it is.
constexpr double kOrthonormalTolerance = 1e-14;
/// Beyond this it is refused: Kalibr and VINS-Fusion's shipped configs are orthonormal to 1e-12,
/// and 1e-3 off cost 0.17 m of ATE on a 60 s street.
constexpr double kOrthonormalRefused = 1e-6;

/// YAML document with its file name, for messages with line numbers.
struct YamlFile {
  std::string path;
  YAML::Node root;
  std::vector<std::string>* keys_read = nullptr;  ///< top-level keys read, when recorded
};

int lineOf(const YAML::Node& node) { return node.Mark().line + 1; }

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
  // A key written twice would be read once, the other value silently ignored.
  std::map<std::string, int> first_line;
  for (const auto& kv : file.root) {
    if (!kv.first.IsScalar()) continue;
    const auto [it, fresh] = first_line.emplace(kv.first.Scalar(), lineOf(kv.first));
    if (!fresh)
      throw InputError(
          path, lineOf(kv.first),
          "key '" + kv.first.Scalar() + "' written twice (first at line " + std::to_string(it->second) + ")");
  }
  return file;
}

YAML::Node require(const YamlFile& f, const YAML::Node& parent, const std::string& key, const std::string& what) {
  if (parent && !parent.IsMap())  // a scalar or list where a map is expected (found by fuzzing)
    throw InputError(f.path, lineOf(parent), "expected a map with key '" + key + "' (" + what + ")");
  YAML::Node node = parent[key];
  if (f.keys_read && node && parent == f.root) f.keys_read->push_back(key);
  if (!node) throw InputError(f.path, "missing required key '" + key + "' (" + what + ")");
  return node;
}

template <typename T>
T scalarAs(const YamlFile& f, const YAML::Node& node, const std::string& key, const char* expected) {
  if (!node.IsScalar()) throw InputError(f.path, lineOf(node), "key '" + key + "': expected " + expected);
  try {
    return node.as<T>();
  } catch (const YAML::Exception&) {
    throw InputError(f.path, lineOf(node), "key '" + key + "': expected " + expected + ", got '" + node.Scalar() + "'");
  }
}

double getDouble(const YamlFile& f, const YAML::Node& parent, const std::string& key, const std::string& what) {
  const YAML::Node node = require(f, parent, key, what);
  const double v = scalarAs<double>(f, node, key, "a number");
  if (!std::isfinite(v)) throw InputError(f.path, lineOf(node), "key '" + key + "': expected a finite number");
  return v;
}

int getInt(const YamlFile& f, const YAML::Node& parent, const std::string& key, const std::string& what) {
  return scalarAs<int>(f, require(f, parent, key, what), key, "an integer");
}

std::string getString(const YamlFile& f, const YAML::Node& parent, const std::string& key, const std::string& what) {
  return scalarAs<std::string>(f, require(f, parent, key, what), key, "a string");
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
                     "key '" + key + "': expected a 4x4 matrix (16 values), got rows " + std::to_string(rows) +
                         ", cols " + std::to_string(cols) + ", " + std::to_string(data.size()) + " values");
  }
  Eigen::Matrix4d m;
  for (int i = 0; i < 16; ++i) m(i / 4, i % 4) = scalarAs<double>(f, data[i], key + ".data", "a number");
  if (!m.allFinite()) throw InputError(f.path, line, "key '" + key + "': expected finite numbers, got NaN or inf");
  const Eigen::Matrix3d r = m.topLeftCorner<3, 3>();
  if (const double off = (r * r.transpose() - Eigen::Matrix3d::Identity()).norm(); off > kOrthonormalRefused) {
    std::ostringstream o;
    o << off;
    throw InputError(f.path, line,
                     "key '" + key + "': rotation block not orthonormal (|R R^T - I| = " + o.str() +
                         ", expected below 1e-6: digits lost or a wrong value?)");
  }
  if (r.determinant() < 0.0 || (m.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).norm() > 1e-9) {
    throw InputError(f.path, line,
                     "key '" + key +
                         "': expected a rigid transform (rotation block orthonormal "
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

// The readers proper; loadCameraFile and loadConfig wrap them.
camera::CameraParams readCameraFile(const std::string& path);
Config readConfig(const std::string& path, std::vector<std::string>* keys_read);

namespace {

/// Any yaml-cpp exception a reader lets through (a structure the reader did not expect) as the
/// one error type readers throw.
template <typename Read>
auto refusingYamlErrors(const std::string& path, Read read) {
  try {
    return read();
  } catch (const YAML::Exception& e) {
    if (e.mark.is_null()) throw InputError(path, "unexpected YAML structure: " + e.msg);
    throw InputError(path, e.mark.line + 1, "unexpected YAML structure: " + e.msg);
  }
}

std::string sizeText(int width, int height) { return std::to_string(width) + "x" + std::to_string(height); }

/// Plausible for a real camera: focal lengths up to 100 image widths (a 0.6 degree view), the
/// principal point inside the image. Throws InputError.
void checkIntrinsics(const std::string& path, const camera::CameraParams& cam) {
  const double max_f = 100.0 * std::max(cam.width, cam.height);
  if (!(cam.fx > 0 && cam.fy > 0 && cam.fx <= max_f && cam.fy <= max_f))
    throw InputError(path, "expected focal lengths in (0, " + std::to_string(static_cast<int>(max_f)) + "] px for a " +
                               sizeText(cam.width, cam.height) + " image, got " + std::to_string(cam.fx) + ", " +
                               std::to_string(cam.fy));
  if (!(cam.cx >= 0 && cam.cx <= cam.width && cam.cy >= 0 && cam.cy <= cam.height))
    throw InputError(path, "expected the principal point inside the " + sizeText(cam.width, cam.height) +
                               " image, got (" + std::to_string(cam.cx) + ", " + std::to_string(cam.cy) + ")");
}

}  // namespace

camera::CameraParams loadCameraFile(const std::string& path) {
  return refusingYamlErrors(path, [&] { return readCameraFile(path); });
}

camera::CameraParams readCameraFile(const std::string& path) {
  const YamlFile f = loadYaml(path);
  camera::CameraParams cam;
  const YAML::Node model_node = require(f, f.root, "model_type", "PINHOLE, KANNALA_BRANDT or MEI");
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
    const YAML::Node p = require(f, f.root, "projection_parameters", "map with k2 k3 k4 k5 mu mv u0 v0");
    const char* dk[] = {"k2", "k3", "k4", "k5"};
    for (int i = 0; i < 4; ++i) cam.dist[i] = getDouble(f, p, dk[i], "projection_parameters");
    cam.fx = getDouble(f, p, "mu", "projection_parameters");
    cam.fy = getDouble(f, p, "mv", "projection_parameters");
    cam.cx = getDouble(f, p, "u0", "projection_parameters");
    cam.cy = getDouble(f, p, "v0", "projection_parameters");
  } else if (model == "MEI") {
    cam.type = camera::ModelType::kMei;
    const YAML::Node m = require(f, f.root, "mirror_parameters", "map with xi");
    const YAML::Node d = require(f, f.root, "distortion_parameters", "map with k1 k2 p1 p2");
    const YAML::Node p = require(f, f.root, "projection_parameters", "map with gamma1 gamma2 u0 v0");
    cam.xi = getDouble(f, m, "xi", "mirror_parameters");
    if (!(cam.xi >= 0.0 && cam.xi <= 10.0))
      throw InputError(path, lineOf(m["xi"]),
                       "expected the mirror parameter xi in [0, 10], got " + std::to_string(cam.xi));
    const char* dk[] = {"k1", "k2", "p1", "p2"};
    for (int i = 0; i < 4; ++i) cam.dist[i] = getDouble(f, d, dk[i], "distortion_parameters");
    cam.fx = getDouble(f, p, "gamma1", "projection_parameters");
    cam.fy = getDouble(f, p, "gamma2", "projection_parameters");
    cam.cx = getDouble(f, p, "u0", "projection_parameters");
    cam.cy = getDouble(f, p, "v0", "projection_parameters");
  } else {
    throw InputError(path, lineOf(model_node),
                     "unknown camera model '" + model + "' (expected PINHOLE, KANNALA_BRANDT or MEI)");
  }
  checkIntrinsics(path, cam);
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
      c.warnings.push_back(cam_path.string() + ": image size " + sizeText(cam.width, cam.height) +
                           " differs from the config's " + sizeText(c.image_width, c.image_height) +
                           "; the config's is used (as VINS-Fusion does)");
      cam.width = c.image_width;
      cam.height = c.image_height;
      checkIntrinsics(cam_path.string(), cam);
    }
    c.cams.push_back(cam);
    c.T_b_c.push_back(getTransform(f, "body_T_cam" + std::to_string(i)));
  }
}

const char* ruleText(ParamRule rule) {
  switch (rule) {
    case ParamRule::kPositive:
      return "a positive value";
    case ParamRule::kNonNegative:
      return "a value >= 0";
    case ParamRule::kOpenUnit:
      return "a value in (0, 1)";
    case ParamRule::kFraction:
      return "a value in (0, 1]";
    case ParamRule::kCorrelation:
      return "a value in [-1, 1]";
    case ParamRule::kImuNoise:
      return "a plausible IMU noise value in (0, 10]";
    case ParamRule::kGravity:
      return "a gravity magnitude in [9, 10.5]";
    case ParamRule::kTimeOffset:
      return "a camera-IMU offset within 0.5 s (td is in seconds)";
    case ParamRule::kExtrinsicMode:
      return "0, 1 or 2";
    case ParamRule::kAny:
      break;
  }
  return "a number";
}

bool satisfies(double v, ParamRule rule) {
  switch (rule) {
    case ParamRule::kPositive:
      return v > 0;
    case ParamRule::kNonNegative:
      return v >= 0;
    case ParamRule::kOpenUnit:
      return v > 0 && v < 1;
    case ParamRule::kFraction:
      return v > 0 && v <= 1;
    case ParamRule::kCorrelation:
      return v >= -1 && v <= 1;
    case ParamRule::kImuNoise:
      return v > 0 && v <= 10;
    case ParamRule::kGravity:
      return v >= 9 && v <= 10.5;
    case ParamRule::kTimeOffset:
      return std::abs(v) <= 0.5;
    case ParamRule::kExtrinsicMode:
      return v == 0 || v == 1 || v == 2;
    case ParamRule::kAny:
      break;
  }
  return true;
}

/// Reads the declared keys present in the file (a required one missing throws) and checks
/// their rules; absent optional keys keep the struct's defaults.
class YamlLoader final : public ParamVisitor {
 public:
  explicit YamlLoader(const YamlFile& f) : f_(f) {}
  /// The required front-end and solver keys the file lacks, each with the default taken (VINS-Fusion's
  /// simulation config has none of them; VINS-Fusion reads 0 for a missing key).
  std::string defaulted;
  void section(const char* title) override { imu_section_ = std::string(title).rfind("IMU noise", 0) == 0; }
  void param(const ParamKey& k, double& v) override {
    if (present(k, v)) v = checked(k, getDouble(f_, f_.root, k.name, k.unit));
  }
  void param(const ParamKey& k, int& v) override {
    if (present(k, v)) v = static_cast<int>(checked(k, getInt(f_, f_.root, k.name, k.unit)));
  }
  void param(const ParamKey& k, bool& v) override {
    if (!present(k, v ? 1 : 0)) return;
    const int i = getInt(f_, f_.root, k.name, "0 or 1");
    if (i != 0 && i != 1)
      throw InputError(f_.path, lineOf(f_.root[k.name]),
                       "key '" + std::string(k.name) + "': expected 0 or 1, got " + std::to_string(i));
    v = i == 1;
  }
  void param(const ParamKey& k, std::string& v) override {
    if (k.required || f_.root[k.name]) v = getString(f_, f_.root, k.name, k.unit);
  }

 private:
  /// Read it: it is in the file, or required (the IMU's noise keys missing throw when read); a
  /// required front-end or solver key missing keeps its default, named in `defaulted`.
  bool present(const ParamKey& k, double default_value) {
    if (f_.root[k.name]) return true;
    if (!k.required) return false;
    if (imu_section_) return true;
    std::ostringstream text;
    text << k.name << " " << default_value;
    defaulted += (defaulted.empty() ? "" : ", ") + text.str();
    return false;
  }
  bool imu_section_ = false;
  double checked(const ParamKey& k, double v) const {
    if (!satisfies(v, k.rule)) {
      std::ostringstream got;
      got << v;
      throw InputError(
          f_.path, lineOf(f_.root[k.name]),
          "key '" + std::string(k.name) + "': expected " + ruleText(k.rule) + " (" + k.unit + "), got " + got.str());
    }
    return v;
  }
  const YamlFile& f_;
};

/// The mode, visited as its name.
void declareModeParam(ParamVisitor& v, std::string& mode_name) {
  v.section("Feature rejection mode (DESIGN §4.8)");
  v.param({"mode", "baseline, ransac, seg, idy, idy-pre or idy-ba"}, mode_name);
}

/// The bag topics and VIODE's segmentation tables.
void declareTopicParams(ParamVisitor& v, Config& c) {
  v.section("Bag topics (ROS1 and ROS 2)");
  v.param({"imu_topic", "ROS topic"}, c.imu_topic);
  v.param({"image0_topic", "ROS topic"}, c.image0_topic);
  v.param({"image1_topic", "ROS topic"}, c.image1_topic);
  v.param({"groundtruth_topic", "ROS topic, empty = none"}, c.groundtruth_topic);
  v.param({"segmentation_topic", "ROS topic of VIODE's segmentation, empty = none"}, c.segmentation_topic);
  v.param({"segmentation_rgb_ids", "VIODE's colour table, beside the config"}, c.segmentation_rgb_ids);
  v.param({"segmentation_vehicle_ids", "VIODE's vehicle ids, beside the config"}, c.segmentation_vehicle_ids);
}

/// Every declared key, in the order saveConfig writes and describe prints them.
void declareAll(ParamVisitor& v, Config& c, std::string& mode_name) {
  c.imu.declareParams(v, c.use_imu);
  declareModeParam(v, mode_name);
  c.tracker.declareParams(v);
  c.estimator.declareParams(v);
  c.idy.declareParams(v);
  c.loop.declareParams(v);
  declareTopicParams(v, c);
}

/// A number as a config file would write it ("50", "0.1").
std::string shortNumber(double v) {
  std::ostringstream o;
  o << v;
  return o.str();
}

/// Checks between keys, after they are read.
void checkTogether(const YamlFile& f, const std::string& mode_name, Config& c) {
  if (!parseMode(mode_name, c.mode))
    throw InputError(f.path, lineOf(f.root["mode"]),
                     "key 'mode': expected one of " + modeNames() + ", got '" + mode_name + "'");
  if (!c.use_imu && !f.root["mode"] &&
      traitsOf(c.mode).filter == FilterKind::kIdy) {  // a VINS-Fusion stereo-only config as it is
    c.mode = Mode::kBaseline;
    c.warnings.push_back(
        f.path +
        ": imu: 0 and no mode key: mode baseline (idy without the IMU takes a constant-velocity motion "
        "prior, worth it on some traffic and not on other: docs/results.md)");
  }
  if (c.idy.lambda_dy_c > c.idy.lambda_dy)
    throw InputError(f.path, "lambda_dy_c (" + std::to_string(c.idy.lambda_dy_c) + ") must not exceed lambda_dy (" +
                                 std::to_string(c.idy.lambda_dy) + ")");
  if (c.tracker.track_dropout_permille > 1000)
    throw InputError(
        f.path, lineOf(f.root["track_dropout_permille"]),
        "key 'track_dropout_permille': expected 0 to 1000, got " + std::to_string(c.tracker.track_dropout_permille));
  if (c.tracker.stereo_refine > 2)
    throw InputError(f.path, lineOf(f.root["stereo_refine"]),
                     "key 'stereo_refine': expected 0 (off), 1 (affine) or 2 (translation), got " +
                         std::to_string(c.tracker.stereo_refine));
  if (c.imu.spike.max_ms >= 1e3 * c.estimator.max_imu_gap_s) {  // a dropped spike leaves a gap to bridge
    const YAML::Node at = f.root["imu_spike_max_ms"] ? f.root["imu_spike_max_ms"] : f.root["max_imu_gap"];
    throw InputError(f.path, lineOf(at),
                     "imu_spike_max_ms (" + shortNumber(c.imu.spike.max_ms) + ") must be below max_imu_gap (" +
                         shortNumber(1e3 * c.estimator.max_imu_gap_s) + " ms): a dropped spike leaves a gap to bridge");
  }
  if (c.estimator.estimate_anchor_ray && c.estimator.estimate_td)
    throw InputError(f.path, lineOf(f.root["estimate_anchor_ray"]),
                     "estimate_anchor_ray has no time-offset form: set estimate_td 0 with it");
  if (c.estimator.estimate_extrinsic != 0 && c.estimator.estimate_anchor_ray)
    throw InputError(f.path, lineOf(f.root["estimate_anchor_ray"]),
                     "estimate_anchor_ray has no form with estimated extrinsics: set estimate_extrinsic 0 with it");
  if (c.estimator.estimate_extrinsic != 0 && !c.use_imu)
    throw InputError(f.path, lineOf(f.root["estimate_extrinsic"]),
                     "estimate_extrinsic " + std::to_string(c.estimator.estimate_extrinsic) +
                         " needs the IMU (imu: 0 has no body frame to mount the cameras on): set it 0");
  const fs::path folder = fs::path(f.path).parent_path();
  for (std::string* table : {&c.segmentation_rgb_ids, &c.segmentation_vehicle_ids})
    if (!table->empty() && fs::path(*table).is_relative()) *table = (folder / *table).string();
  for (const auto& [key, topic] : {std::pair<const char*, const std::string*>{"image1_topic", &c.image1_topic},
                                   {"segmentation_topic", &c.segmentation_topic}})
    for (const auto& [other, other_topic] :
         {std::pair<const char*, const std::string*>{"image0_topic", &c.image0_topic},
          {"image1_topic", &c.image1_topic}})
      if (key != std::string(other) && !topic->empty() && *topic == *other_topic)
        throw InputError(
            f.path, lineOf(f.root[key] ? f.root[key] : f.root[other]),
            std::string(key) + " and " + other + " are the same topic '" + *topic + "': each stream needs its own");
  if (!c.segmentation_topic.empty() && (c.segmentation_rgb_ids.empty() || c.segmentation_vehicle_ids.empty()))
    throw InputError(f.path, lineOf(f.root["segmentation_topic"]),
                     "segmentation_topic needs segmentation_rgb_ids and segmentation_vehicle_ids (VIODE's tables)");
}

/// The rig's keys, read beside the declared ones.
const std::vector<std::string> kRigKeys = {"imu",        "num_of_cam", "image_width", "image_height",
                                           "cam0_calib", "cam1_calib", "body_T_cam0", "body_T_cam1"};

/// VINS-Fusion's keys that idyvins reads past without using, and why.
const std::vector<std::pair<std::string, std::string>> kVinsKeysNotUsed = {
    {"output_path", "outputs go to run --out"},
    {"multiple_thread", "run --threads decides"},
    {"freq", "every frame is processed"},
    {"show_track", "idyvins track --save-tracks, the ROS node's ~feature_image"},
    {"load_previous_pose_graph", "run --load-map"},
    {"pose_graph_save_path", "run --save-map"},
    {"save_image", "not used"},
    {"use_gpu", "not used"},
    {"use_gpu_acc_flow", "not used"},
    {"use_gpu_ceres", "not used"},
    {"visualize_imu_forward", "not used"},  // VINS-Mono's rviz keys (VINS-Fusion's simulation config)
    {"visualize_camera_size", "not used"}};

/// Every declared key's name.
class KeyNames final : public ParamVisitor {
 public:
  void section(const char*) override {}
  void param(const ParamKey& k, double&) override { names.push_back(k.name); }
  void param(const ParamKey& k, int&) override { names.push_back(k.name); }
  void param(const ParamKey& k, bool&) override { names.push_back(k.name); }
  void param(const ParamKey& k, std::string&) override { names.push_back(k.name); }
  std::vector<std::string> names;
};

/// Levenshtein distance of the lower-cased words.
/// Warnings for the keys of `f` that idyvins does not read: an unknown key names the nearest
/// known one when it looks like a typo; VINS-Fusion's unused keys are listed in one line.
void warnAboutKeys(const YamlFile& f, Config& c) {
  std::vector<std::string> known = declaredKeyNames();
  known.insert(known.end(), kRigKeys.begin(), kRigKeys.end());
  std::string unused;
  for (const auto& kv : f.root) {
    if (!kv.first.IsScalar()) continue;
    const std::string key = kv.first.Scalar();
    if (std::find(known.begin(), known.end(), key) != known.end()) continue;
    const auto vins =
        std::find_if(kVinsKeysNotUsed.begin(), kVinsKeysNotUsed.end(), [&](const auto& k) { return k.first == key; });
    if (vins != kVinsKeysNotUsed.end()) {
      unused += (unused.empty() ? "" : ", ") + key + " (" + vins->second + ")";
      continue;
    }
    std::string nearest;
    std::size_t best = 3;  // at most 2 edits, or the same word in other case
    for (const std::string& k : known)
      if (const std::size_t d = editDistance(key, k); d < best || (d == 0 && best > 0)) best = d, nearest = k;
    c.warnings.push_back(f.path + ":" + std::to_string(lineOf(kv.first)) + ": unknown key '" + key + "' ignored" +
                         (nearest.empty() ? " (docs/cli.md lists the keys)" : "; did you mean '" + nearest + "'?"));
  }
  if (!unused.empty()) c.warnings.push_back(f.path + ": VINS-Fusion keys read but not used by idyvins: " + unused);
}

/// Plausibility of the rig beyond each key's own rule: the stereo baseline and the lens distortion (a unit or sign
/// error makes each of them absurd).
void checkRig(const YamlFile& f, Config& c) {
  if (c.cams.size() == 2) {
    const Eigen::Vector3d t = (c.T_b_c[0].inverse() * c.T_b_c[1]).translation();  // cam1 in cam0's frame
    const double b = t.norm();
    if (b < 0.01 || b > 3.0)
      throw InputError(f.path, lineOf(f.root["body_T_cam1"]),
                       "stereo baseline " + shortNumber(b) + " m (|t| of cam1 in cam0's frame): expected 0.01 to 3 m " +
                           (b > 3.0 ? "(translations in millimetres?)" : "(body_T_cam1 equal to body_T_cam0?)"));
    c.cam0_right = t.x() < 0 && std::abs(t.x()) > std::max(std::abs(t.y()), std::abs(t.z()));
    if (c.cam0_right)
      c.warnings.push_back(f.path + ":" + std::to_string(lineOf(f.root["body_T_cam1"])) + ": cam1 lies " +
                           shortNumber(-t.x()) + " m left of cam0: idyvins tracks on cam1, matches into cam0 " +
                           "(features are cam1's; cam0's masks are not used)");
  }
  for (std::size_t i = 0; i < c.cams.size(); ++i) {
    // The image corner lifted to the normalized plane and compared with its undistorted guess:
    // a real lens moves it by well under a factor 4.
    const camera::CameraParams& k = c.cams[i];
    const auto model = camera::makeCamera(k);
    const Eigen::Vector2d corner(0.0, 0.0);
    Eigen::Vector2d xy;
    const double pinhole = std::hypot(k.cx / k.fx, k.cy / k.fy);
    const bool lifted = model->liftToNormalized(corner, xy) && xy.allFinite();
    const double ratio = lifted ? xy.norm() / pinhole : 0.0;
    if (!(ratio > 0.25 && ratio < 4.0) && k.type == camera::ModelType::kPinhole)
      throw InputError(c.cam_paths[i], "distortion [" + shortNumber(k.dist[0]) + ", " + shortNumber(k.dist[1]) + ", " +
                                           shortNumber(k.dist[2]) + ", " + shortNumber(k.dist[3]) +
                                           "] moves the image corner by a factor " + shortNumber(ratio) +
                                           " (expected 0.25 to 4 for a real lens: a wrong value or unit?)");
  }
}

}  // namespace

Config loadConfig(const std::string& path, std::vector<std::string>* keys_read) {
  return refusingYamlErrors(path, [&] { return readConfig(path, keys_read); });
}

Config readConfig(const std::string& path, std::vector<std::string>* keys_read) {
  YamlFile f = loadYaml(path);
  f.keys_read = keys_read;
  Config c;
  c.path = path;
  c.use_imu = getInt(f, f.root, "imu", "1 to use the IMU, 0 for vision only") != 0;
  c.estimator.use_imu = c.use_imu;
  c.num_cam = getInt(f, f.root, "num_of_cam", "1 or 2");
  if (c.num_cam != 1 && c.num_cam != 2)
    throw InputError(path, lineOf(f.root["num_of_cam"]),
                     "key 'num_of_cam': expected 1 or 2, got " + std::to_string(c.num_cam));
  c.image_width = getInt(f, f.root, "image_width", "pixels");
  c.image_height = getInt(f, f.root, "image_height", "pixels");
  if (c.image_width <= 0 || c.image_height <= 0)
    throw InputError(path, lineOf(f.root["image_width"]), "expected a positive image size");

  readCameras(f, path, c);
  std::string mode_name = toString(c.mode);
  YamlLoader loader(f);
  declareAll(loader, c, mode_name);
  if (!loader.defaulted.empty())
    c.warnings.push_back(
        path + ": VINS-Fusion keys missing, idyvins' defaults used (VINS-Fusion would read 0): " + loader.defaulted);
  checkTogether(f, mode_name, c);
  checkRig(f, c);
  warnAboutKeys(f, c);
  return c;
}

void declareParams(ParamVisitor& visitor, Config& c) {
  std::string mode_name = toString(c.mode);
  declareAll(visitor, c, mode_name);
  if (!parseMode(mode_name, c.mode))
    throw InputError("mode", "expected one of " + modeNames() + ", got '" + mode_name + "'");
}

std::vector<std::string> declaredKeyNames() {
  Config c;
  std::string mode_name = toString(c.mode);
  KeyNames names;
  declareAll(names, c, mode_name);
  return names.names;
}

}  // namespace idyvins
