#pragma once
// VINS-Fusion-format configuration (OpenCV FileStorage YAML + camodocal camera
// files), loaded once, validated, and passed down as a value (no globals).

#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "camera/camera_params.h"
#include "core/measurements.h"

namespace idyvins {

/// Feature rejection mode of the whole system (DESIGN §4.8).
enum class Mode { kBaseline, kRansac, kSeg, kIdy, kIdyPre, kIdyBa };

/// "baseline", "ransac", "seg", "idy", "idy-pre", "idy-ba".
const char* toString(Mode mode);
/// Parses a mode name; false if unknown.
bool parseMode(const std::string& text, Mode& mode);
/// All mode names, separated by '|', for messages and --help.
std::string modeNames();

/// Front-end (feature tracker) options.
struct TrackerOptions {
  int max_cnt = 150;          ///< features kept per frame
  double min_dist = 30;       ///< px between features
  double f_threshold = 1.0;   ///< px, F-matrix RANSAC threshold (mode ransac)
  bool flow_back = true;      ///< forward-backward KLT check
  /// `equalize` (VINS-Mono's key, default 0): CLAHE (clip limit 3, 8 x 8 tiles) on both
  /// images before tracking, detection and stereo matching (on the real EuRoC excerpt it
  /// gives more features a right match, docs/method.md).
  bool equalize = false;
  /// `stereo_gain_compensation` (default 1): before the left -> right search, the right
  /// image's brightness is mapped to the left's (gain and offset from the two images' mean
  /// and standard deviation) when they differ by more than 1 %. KLT assumes equal
  /// brightness; EuRoC's right camera is darker than its left (docs/method.md).
  bool stereo_gain_compensation = true;
  /// `stereo_epipolar_px` (default 2): a right match farther than this from its epipolar
  /// line (known extrinsics) is dropped.
  double stereo_epipolar_px = 2.0;
  /// `stereo_refine` (default 0): each right match is refined by aligning the left patch
  /// to the right image (affine, gain and bias invariant, as the first-patch alignment) and
  /// kept when that converges within 1 px of KLT's. KLT assumes equal brightness; a
  /// left/right difference a global gain does not remove (vignetting at the two image
  /// positions, saturation) biases its disparity, most on near, weakly textured surfaces.
  bool stereo_refine = false;
};

/// Back-end (sliding-window solver) options.
struct SolverOptions {
  /// Wall-clock cap per solve, seconds; used only with time_limited (VINS-Fusion's key).
  double max_solver_time_s = 0.04;
  int max_num_iterations = 8;
  double keyframe_parallax_px = 10.0;  ///< mean parallax for a new keyframe, pixels
  /// `solver_time_limit` (default 0): cap each solve at max_solver_time_s of wall clock, as
  /// VINS-Fusion does, for live use. Results then depend on machine load; off, solves stop
  /// on max_num_iterations and Ceres' convergence tolerances only (deterministic).
  bool time_limited = false;
  /// `solver_function_tolerance` (default 1e-4; Ceres' own is 1e-6): a solve has converged
  /// when an iteration lowers the cost by less than this fraction of it. 1e-4 was measured
  /// on the standard benchmark (docs/results.md): idy's ATE equal or better on every
  /// sequence group, optimization 14–19 -> 12–13 ms per frame.
  double function_tolerance = 1e-4;
};

/// Parameters of the paper's method (DESIGN §4).
/// Extension of §4.3 (not in the paper): the stereo motion test (dynamic::stereoMotionError)
/// catches motion along the epipolar line, which d_s cannot see (docs/method.md).
struct StereoMotionOptions {
  bool enabled = true;         ///< `stereo_motion_test`
  double chi2 = 18.47;         ///< `stereo_motion_chi2`: χ²₄ at 99.9 %
  double sigma_px = 0.25;      ///< `stereo_motion_sigma_px`: one KLT / stereo match
  int strikes = 2;             ///< `stereo_motion_strikes`: consecutive failures before removal
                               ///< (an earlier failure marks the feature as a candidate)
  int anchor_frames = 10;      ///< `stereo_motion_anchor_frames`: compare with the stereo
                               ///< observation up to this many frames back (1 = previous frame)
  double drift_mps = 0.02;     ///< `stereo_motion_drift_mps`: drift of the chained priors
  /// `stereo_motion_remove_chi2`: with a value above `chi2`, a repeated failure removes the
  /// feature only when its χ² exceeds this or the failures reach `persistent_strikes`;
  /// otherwise it stays a candidate. 0 = every repeated failure removes (the default; on
  /// clean images slow traffic would be removed too late, docs/method.md).
  double remove_chi2 = 0;
  /// `stereo_motion_persistent_strikes`: with `remove_chi2` on, this many consecutive
  /// failures remove the feature whatever its χ² (slow motion along the line of sight);
  /// 0 = never.
  int persistent_strikes = 3;
  /// `stereo_motion_left_chi2`: a failure whose left-image residual alone is within this
  /// (χ², 2 dof; 5.99 = 95 %) is not counted (the right match is suspect: hidden, or at a
  /// silhouette). 0 = off. Looser gates cost recall (docs/method.md).
  double left_chi2 = 5.99;
  /// `stereo_motion_noise_ref`: the tracker's noise is measured on every frame as a
  /// quantile of the χ² of the tested features (most are static); when that quantile
  /// exceeds this reference, the χ² are divided by quantile / reference before the tests
  /// (the test then holds its false-alarm rate on noisier images). Clean renders keep
  /// the 25 % quantile below 0.1 on every frame (no change); realistic images (blur, noise,
  /// weak texture) sit at 0.2-0.4. 0 = off (fixed σ_px).
  double noise_ref = 0.1;
  double noise_quantile = 0.25;  ///< `stereo_motion_noise_quantile`: the quantile (robust to 75 % moving)
  int noise_min_features = 10;   ///< fewer tested features: keep the previous frame's scale
  /// `stereo_motion_min_disparity_px`: points whose anchor disparity (f·b / depth) is
  /// below this are not judged by the test (their stereo depth cannot tell motion from
  /// noise); 0 = judge all.
  double min_disparity_px = 0;
};

struct DynamicOptions {
  Mode mode = Mode::kIdy;
  double lambda_dy = 4.0;    ///< px^2, elimination threshold (eq. 4)
  double lambda_dy_c = 1.0;  ///< px^2, candidate threshold (eq. 6)
  /// Extension of §4.6 (not in the paper): in the modes with post-processing, a
  /// landmark that fails the 3 px outlier test is confirmed dynamic like a failing candidate
  /// (its track leaves the window for good, dynamic map) instead of being dropped and
  /// re-triangulated from its next observation. Config key `confirm_outliers_dynamic`.
  bool confirm_outliers = true;
  StereoMotionOptions stereo;
  /// Extension of §4.3 (not in the paper): in idy and idy-pre, a new corner lost
  /// in its second frame is labelled dynamic when it is not found where the motion prior
  /// puts it as a static stereo point (frontend::TrackerParams::judge_lost_new_tracks).
  /// Labels and dynamic map only: such a corner never constrains the estimate.
  /// Config key `lost_track_test`.
  bool lost_track_test = true;
};

/// Whole-system configuration.
struct Config {
  std::string path;  ///< the config file it was read from
  bool use_imu = true;
  int num_cam = 2;
  int image_width = 0, image_height = 0;
  std::vector<camera::CameraParams> cams;  ///< cam0 (left), cam1 (right)
  std::vector<std::string> cam_paths;      ///< resolved camodocal file paths
  std::vector<Eigen::Isometry3d> T_b_c;    ///< body_T_camX: maps camera points into the body
  ImuNoise imu;
  TrackerOptions tracker;
  SolverOptions solver;
  bool estimate_td = false;
  double td_s = 0.0;  ///< image clock + td = IMU clock, seconds
  DynamicOptions dynamic;
  /// Bag topics (VINS-Fusion's keys imu_topic, image0_topic, image1_topic; idyvins'
  /// groundtruth_topic, empty = none). Used when the dataset is a ROS1 bag.
  std::string imu_topic = "/imu0", image0_topic = "/cam0/image_raw", image1_topic = "/cam1/image_raw";
  std::string groundtruth_topic;
  /// VIODE-style segmentation in a bag: its topic (`segmentation_topic`, e.g.
  /// /cam0/segmentation) and colour tables (`segmentation_rgb_ids`,
  /// `segmentation_vehicle_ids`, resolved against the config's folder).
  std::string segmentation_topic, segmentation_rgb_ids, segmentation_vehicle_ids;
};

/// Reads a camodocal camera file (PINHOLE or KANNALA_BRANDT). Throws InputError.
camera::CameraParams loadCameraFile(const std::string& path);

/// Reads and validates a VINS-Fusion config; camX_calib paths resolve against
/// the config's folder. Throws InputError naming file, line and expectation. With
/// `keys_read`, the names of the config's keys it read (camera files aside) are appended.
Config loadConfig(const std::string& path, std::vector<std::string>* keys_read = nullptr);

/// Multi-line listing of every config key's value under its key name (what `info`
/// prints): every key loadConfig reads appears in it.
std::string describe(const Config& config);

/// Writes `config` as a VINS-Fusion config at `path` with every key loadConfig reads, and
/// its camera files next to it (camX_calib names: the file names of config.cam_paths, or
/// cam<i>.yaml); numbers are written so that loadConfig gives them back exactly. Throws
/// InputError when a file cannot be written.
void saveConfig(const Config& config, const std::string& path);

/// Writes a camodocal camera file (PINHOLE or KANNALA_BRANDT) loadCameraFile reads back exactly.
void saveCameraFile(const camera::CameraParams& camera, const std::string& path);

}  // namespace idyvins
