#pragma once
// VINS-Fusion-format configuration (OpenCV FileStorage YAML + camodocal camera
// files), loaded once, validated, and passed down as a value (no globals). The modules'
// parameter structs are header-only (core/params.h): io reads, prints and saves their
// keys without linking the modules.

#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "backend/estimator_options.h"
#include "camera/camera_params.h"
#include "camera/rig.h"
#include "core/measurements.h"
#include "dynamic/idy_options.h"
#include "frontend/tracker_params.h"
#include "imu/imu_options.h"
#include "map/loop_options.h"

namespace idyvins {

/// Feature rejection mode of the whole system (DESIGN §4.8).
enum class Mode { kBaseline, kRansac, kSeg, kIdy, kIdyPre, kIdyBa };

/// "baseline", "ransac", "seg", "idy", "idy-pre", "idy-ba".
const char* toString(Mode mode);
/// Parses a mode name; false if unknown.
bool parseMode(const std::string& text, Mode& mode);
/// All mode names, separated by '|', for messages and --help.
std::string modeNames();

/// Whole-system configuration: the rig and the sum of the modules' parameter structs
/// (each the single home of its keys' defaults, core/params.h).
struct Config {
  std::string path;  ///< the config file it was read from
  bool use_imu = true;
  int num_cam = 2;
  int image_width = 0, image_height = 0;
  std::vector<camera::CameraParams> cams;  ///< cam0, cam1 as the file names them
  std::vector<std::string> cam_paths;      ///< resolved camodocal file paths
  std::vector<Eigen::Isometry3d> T_b_c;    ///< body_T_camX: maps camera points into the body
  /// The file's cam0 is the right camera of the pair (cam1 lies to its left, VINS-Fusion's
  /// vi_car): derived from the mounts, not a key. The system tracks on the left camera, so
  /// it takes cam1's images as its left ones (leftFirst, pipeline::System) and names every
  /// output camera as the file does.
  bool cam0_right = false;
  imu::ImuOptions imu;                  ///< IMU noise, limits, spike gate
  Mode mode = Mode::kIdy;               ///< `mode`; what it switches on: config/modes.h
  frontend::TrackerParams tracker;      ///< feature tracker keys
  backend::EstimatorOptions estimator;  ///< solver, time offset and measurement-model keys
  dynamic::IdyOptions idy;              ///< the paper's method and the dynamic-scene tests
  map::LoopOptions loop;                ///< loop closure (off unless loop_closure: 1)
  /// Bag topics (VINS-Fusion's keys imu_topic, image0_topic, image1_topic; idyvins'
  /// groundtruth_topic, empty = none). Used when the dataset is a ROS1 bag.
  std::string imu_topic = "/imu0", image0_topic = "/cam0/image_raw", image1_topic = "/cam1/image_raw";
  std::string groundtruth_topic;
  /// VIODE-style segmentation in a bag: its topic (`segmentation_topic`, e.g.
  /// /cam0/segmentation) and colour tables (`segmentation_rgb_ids`,
  /// `segmentation_vehicle_ids`, resolved against the config's folder).
  std::string segmentation_topic, segmentation_rgb_ids, segmentation_vehicle_ids;
  /// What loadConfig noticed but did not refuse, one line each ("FILE:LINE: ..."): unknown keys
  /// (with the nearest known one), VINS-Fusion keys read but not honoured. `run`, `info` and
  /// the ROS node print them.
  std::vector<std::string> warnings;

  /// The cameras and their mounts.
  camera::Rig rig() const { return {cams, T_b_c}; }
};

/// Reads a camodocal camera file (PINHOLE or KANNALA_BRANDT). Throws InputError.
camera::CameraParams loadCameraFile(const std::string& path);

/// Reads and validates a VINS-Fusion config; camX_calib paths resolve against
/// the config's folder. Throws InputError naming file, line and expectation. With
/// `keys_read`, the names of the config's keys it read (camera files aside) are appended.
Config loadConfig(const std::string& path, std::vector<std::string>* keys_read = nullptr);

/// The rig as the system runs it, left camera first: with cam0_right, the two cameras
/// (cams, cam_paths, T_b_c) swapped and cam0_right false; otherwise `config` itself.
Config leftFirst(const Config& config);

/// Multi-line listing of every config key's value under its key name (what `info`
/// prints): every key loadConfig reads appears in it.
std::string describe(const Config& config);

/// Visits every key of `config` beside the rig's (cameras, extrinsics, image size), in the
/// order saveConfig writes them: IMU noise, mode (as its name), the modules' parameter
/// structs, bag topics. Throws InputError when the visitor leaves an unknown mode name.
void declareParams(ParamVisitor& visitor, Config& config);

/// The name of every key declareParams visits, in its order.
std::vector<std::string> declaredKeyNames();

/// Every key beside the rig's (cameras, extrinsics, image size) as Markdown tables, one per
/// group: key, default ("required" for VINS-Fusion's keys every config carries), unit and
/// meaning. docs/cli.md holds it (tested).
std::string keyTable();

/// Which keys saveConfig writes beside the rig's.
enum class SavedKeys {
  kAll,      ///< every key loadConfig reads
  kChanged,  ///< the required ones and those whose value differs from the default
};

/// Writes `config` as a VINS-Fusion config at `path` (with kChanged, a key left out has its
/// default, so a later change of a default reaches the config), and its camera files next to
/// it (camX_calib names: the file names of config.cam_paths, or cam<i>.yaml); numbers are
/// written so that loadConfig gives them back exactly. Throws InputError when a file cannot
/// be written.
void saveConfig(const Config& config, const std::string& path, SavedKeys keys = SavedKeys::kAll);

/// Whether the config at `path` was written with SavedKeys::kChanged (its comment line says
/// so); false for a config saved with every key, which pins the defaults of the day it was
/// written (the simulator's configs of earlier versions), and for one that cannot be read.
bool savedWithChangedKeysOnly(const std::string& path);

/// Writes a camodocal camera file (PINHOLE or KANNALA_BRANDT) loadCameraFile reads back exactly.
void saveCameraFile(const camera::CameraParams& camera, const std::string& path);

}  // namespace idyvins
