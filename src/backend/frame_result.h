#pragma once
// What the estimator says about each frame and about the window's newest state: plain data
// without Ceres, for everything downstream of the estimator (pipeline::System's outputs, the
// loop closer's keyframes, observers).

#include <Eigen/Geometry>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "core/label.h"
#include "core/time.h"
#include "imu/preintegration.h"

namespace idyvins::backend {

/// Frames in the sliding window: kWindowSize keyframes and the newest frame.
constexpr int kWindowSize = 10;

/// A map point: static, eliminated in the front end, or confirmed dynamic.
struct MapPoint {
  Eigen::Vector3d p_w;
  FeatureLabel label = FeatureLabel::kStatic;
  std::uint64_t id = 0;
};

/// A landmark as the keyframe leaving the window saw it (loop closure's keyframe database).
struct KeyframeObservation {
  std::uint64_t id = 0;
  FeatureLabel label = FeatureLabel::kStatic;
  bool has_position = false;                      ///< triangulated: p_w valid
  Eigen::Vector3d p_w = Eigen::Vector3d::Zero();  ///< world position
  Eigen::Vector2d uv = Eigen::Vector2d::Zero();   ///< left pixel in this keyframe
  Eigen::Vector2d xy = Eigen::Vector2d::Zero();   ///< left normalized in this keyframe
};

/// The oldest keyframe of the window when it leaves (marginalized), with its final estimate.
struct LeavingKeyframe {
  TimeNs t_ns = 0;  ///< IMU clock, as the frame was added
  Eigen::Vector3d p_w_b = Eigen::Vector3d::Zero();
  Eigen::Quaterniond q_w_b = Eigen::Quaterniond::Identity();
  std::vector<KeyframeObservation> observations;  ///< every landmark it observed, any label
};

/// Where one window solve spent its time (ms, wall clock) and how it ended (DESIGN §4.10:
/// offline solves stop on iterations and convergence, never on the clock).
struct SolveProfile {
  double build_ms = 0;          ///< building the Ceres problem (factors, weights)
  double preprocess_ms = 0;     ///< Ceres preprocessing (program, ordering, linear solver set-up)
  double residual_ms = 0;       ///< residual evaluations alone
  double jacobian_ms = 0;       ///< residual + Jacobian evaluations
  double linear_solver_ms = 0;  ///< Schur complement, dense Cholesky, back substitution
  double minimizer_ms = 0;      ///< the whole trust-region loop (includes the three above)
  double post_ms = 0;           ///< gauge restoration and IMU repropagation
  int iterations = 0;           ///< trust-region steps tried
  bool converged = false;       ///< stopped by a tolerance (not by the iteration or time cap)
  /// Sums the times and iterations of another solve into this one (converged is left as is).
  SolveProfile& operator+=(const SolveProfile& o) {
    build_ms += o.build_ms;
    preprocess_ms += o.preprocess_ms;
    residual_ms += o.residual_ms;
    jacobian_ms += o.jacobian_ms;
    linear_solver_ms += o.linear_solver_ms;
    minimizer_ms += o.minimizer_ms;
    post_ms += o.post_ms;
    iterations += o.iterations;
    return *this;
  }
};

/// The left camera's mount as estimate_extrinsic has it after a frame.
struct ExtrinsicEstimate {
  Eigen::Vector3d t_b_c0 = Eigen::Vector3d::Zero();
  Eigen::Quaterniond q_b_c0 = Eigen::Quaterniond::Identity();
  bool open = false;           ///< refined in the window's solves (the motion excited it)
  bool rotation_known = true;  ///< estimate_extrinsic 2: the hand–eye rotation has converged
  double sigma_t_m = -1;       ///< marginal σ from what left the window (-1: none yet)
  double sigma_rot_deg = -1;
};

/// What the estimator says about one frame.
struct FrameResult {
  TimeNs t_ns = 0;
  bool initialized = false;  ///< the pose below is valid
  bool reset = false;        ///< a failure was detected at this frame (state reset)
  std::string status;        ///< e.g. "initializing: 4/10 frames", "tracking", "reset: ..."
  imu::NavState state;       ///< body state in the world (valid when initialized)
  double optimization_ms = 0;
  SolveProfile solve;                      ///< breakdown of optimization_ms (zero when no solve ran)
  double marginalization_ms = 0;           ///< sliding the window (marginalization or frame drop)
  int landmarks = 0;                       ///< landmarks used in the solve
  int candidates = 0;                      ///< candidate landmarks in the solve
  int confirmed_dynamic = 0;               ///< candidates confirmed dynamic after this solve
  int cleared = 0;                         ///< candidates cleared to static after this solve
  std::vector<std::uint64_t> outlier_ids;  ///< landmarks removed by the outlier test after this solve
  int outliers_confirmed = 0;              ///< of those, confirmed dynamic (EstimatorOptions::confirm_outliers)
  int right_outliers = 0;  ///< right observations dropped after this solve (EstimatorOptions::stereo_outlier_px)
  /// Landmarks confirmed dynamic at this frame (post-processing and confirmed outliers), where
  /// they were: the dynamic map's confirmed points (pipeline::System collects them).
  std::vector<MapPoint> confirmed_points;
  bool keyframe = false;
  double td_s = 0;  ///< camera–IMU time offset after this frame (the config's td unless estimate_td)
  /// Why the window was reset at this frame (with `reset`); `status` may say what came next.
  std::string reset_why;
  /// The IMU gap this frame entered the window across without an IMU factor (bridge_imu_gaps),
  /// empty when it has one.
  std::string stereo_only;
  /// The first initialized frame after a reset: the new segment was put in the world frame of
  /// the last good state, propagated to it with the IMU ("imu"); across an IMU gap of at most
  /// max_frame_gap at constant velocity ("extrapolated"), across a longer one (a time jump, a
  /// stop) held ("held"); empty otherwise.
  std::string reanchored;
  /// With `reanchored`: the new segment started from the last good state's biases (tied to them,
  /// EstimatorOptions::reset_bias_prior_acc); false when that state came inside its own segment's
  /// first kSettledFrames frames and the biases started again as at the first start.
  bool biases_from_last_good = false;
  int skipped_blocks = 0;  ///< residual blocks left out of this solve: not finite at their start values
  /// estimate_extrinsic: the left camera's mount after this frame (nullopt when not estimated).
  std::optional<ExtrinsicEstimate> extrinsic;
  /// The keyframe that left the window at this frame (initialized windows only).
  std::optional<LeavingKeyframe> left_window;
};

/// The newest state, for the front end's motion prior (DESIGN §2: one small struct).
struct LatestState {
  bool valid = false;
  TimeNs t_ns = 0;
  imu::NavState state;
  double td_s = 0;  ///< current camera–IMU time offset (image stamp + td = IMU clock)
};

}  // namespace idyvins::backend
