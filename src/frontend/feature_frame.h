#pragma once
// What the front end hands to the back end for one stereo frame.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "core/label.h"
#include "core/time.h"

namespace idyvins::frontend {

using idyvins::FeatureLabel;  // core/label.h

/// One tracked feature in the current frame.
struct Feature {
  std::uint64_t id = 0;
  Eigen::Vector2d uv = Eigen::Vector2d::Zero();  ///< left pixel (distorted image)
  Eigen::Vector2d xy = Eigen::Vector2d::Zero();  ///< left normalized, undistorted (x/z, y/z)
  bool has_right = false;
  /// A right match (uv_right, xy_right) that failed only the patch-correlation check
  /// (TrackerParams::stereo_zncc_motion_only): has_right is false, so the motion tests and
  /// the maps ignore it; the estimator uses it as a stereo observation.
  bool right_low_zncc = false;
  bool hasAnyRight() const { return has_right || right_low_zncc; }  ///< a right match of either kind
  Eigen::Vector2d uv_right = Eigen::Vector2d::Zero();
  Eigen::Vector2d xy_right = Eigen::Vector2d::Zero();
  /// Shape of the left match's noise (frontend::matchShape at uv: identity for a corner
  /// textured alike in every direction, stretched along an edge), set with a right match
  /// (identity without one);
  /// the stereo motion test's per-feature noise (dynamic::StereoMotionOptions::shape).
  Eigen::Matrix2d match_shape = Eigen::Matrix2d::Identity();
  Eigen::Vector2d velocity_px = Eigen::Vector2d::Zero();  ///< left pixel velocity, px/s
  /// Velocity on the normalized image plane (1/s), left and right, from the previous frame's
  /// observation of the same track (zero for a new track or without a right match, of
  /// either kind, in both frames); the estimator moves observations along it when it estimates the time offset.
  Eigen::Vector2d velocity_xy = Eigen::Vector2d::Zero();
  Eigen::Vector2d velocity_xy_right = Eigen::Vector2d::Zero();
  int track_length = 1;  ///< frames this id has been tracked (1 = new)
  FeatureLabel label = FeatureLabel::kStatic;
  double d_s_px2 = 0;       ///< IDY: the minimum projection error d_s (px², DESIGN §4.2), 0 if not scored
  double stereo_chi2 = -1;  ///< IDY stereo motion test's χ² (4 dof), -1 if not tested
  double stereo_depth = 0;  ///< depth (m) of the stereo test's anchor point, 0 if not tested
};

/// Why tracks of the previous frame ended in this one, counted per reason.
struct TrackLosses {
  std::size_t klt = 0;        ///< KLT did not converge
  std::size_t border = 0;     ///< ended within border_px of the image border, or outside the camera model
  std::size_t backward = 0;   ///< the forward-backward KLT check failed (flow_back)
  std::size_t alignment = 0;  ///< the first-patch alignment failed (no convergence, ZNCC, correction)
  std::size_t pruned = 0;     ///< dropped within min_dist of a longer track
  std::size_t total() const { return klt + border + backward + alignment + pruned; }
  TrackLosses& operator+=(const TrackLosses& o) {
    klt += o.klt;
    border += o.border;
    backward += o.backward;
    alignment += o.alignment;
    pruned += o.pruned;
    return *this;
  }
};

/// The front end's output for one frame.
struct FeatureFrame {
  TimeNs t_ns = 0;  ///< on the IMU clock: the image stamp + td_s
  double td_s = 0;  ///< camera–IMU time offset the stamp was shifted by (config td, or its estimate)
  std::vector<Feature> features;
  /// Features labelled kEliminated in this frame: removed by the filter now, or (with
  /// TrackerParams::follow_eliminated) removed earlier and still followed.
  std::vector<Feature> removed;
  /// New corners lost in this frame (tracked for one frame only) that are not where the
  /// motion prior puts a static point (TrackerParams::lost_track_test): their
  /// previous-frame observation (uv, xy, right match), labelled kEliminated.
  std::vector<Feature> lost_moving;
  std::size_t lost_tested = 0;  ///< lost new corners the static hypothesis could be tested on
  double tracking_ms = 0;       ///< KLT, detection, stereo, undistortion
  double filter_ms = 0;         ///< the rejection filter (ransac / seg / idy preprocessing)
  std::size_t tracked = 0;      ///< features carried over from the previous frame (before the filter)
  std::size_t rejected = 0;     ///< removed by the filter in this frame
  std::size_t detected = 0;     ///< new corners
  TrackLosses lost_tracks;      ///< tracks of the previous frame (followed eliminated ones included) ended here
  TrackLosses lost_new;         ///< of those, the previous frame's new corners (tracked for one frame)
};

/// Relative motion of the left camera predicted between the previous and the
/// current frame (from the IMU and the newest state): R_ck_ck1, t_ck_ck1 map
/// points of the current camera into the previous one; cov_p is the body
/// position covariance. valid = false before the estimator is initialized.
struct MotionPrior {
  bool valid = false;
  Eigen::Quaterniond q_prev_cur = Eigen::Quaterniond::Identity();
  Eigen::Vector3d t_prev_cur = Eigen::Vector3d::Zero();
  Eigen::Matrix3d cov_p = Eigen::Matrix3d::Zero();
};

}  // namespace idyvins::frontend
