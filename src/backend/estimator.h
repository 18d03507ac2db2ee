#pragma once
// The sliding-window stereo-inertial estimator (VINS-Fusion class): window of 10
// keyframes + the newest frame, stereo + IMU initialization, Ceres solve with IMU,
// projection and marginalization factors, outlier removal, marginalization of the
// oldest keyframe or the second newest frame, failure detection with reset.

#include <deque>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "backend/estimator_options.h"
#include "backend/window_state.h"
#include "camera/rig.h"
#include "core/measurements.h"
#include "frontend/feature_frame.h"

namespace ceres {
class CostFunction;
class LossFunction;
class Problem;
}  // namespace ceres

namespace idyvins::backend {

/// Below this speed (m/s) of the oldest window frame the time offset is held, not estimated.
constexpr double kMinSpeedForTd = 0.2;
/// A segment's biases are trusted after a failure once it has solved this many frames: two
/// windows, past the first window's bias transient (docs/results.md, "A bias prior at the
/// first start"); an earlier failure restarts the biases as a first start does.
constexpr int kSettledFrames = 2 * kWindowSize;
/// At initialization the offset is searched within ± this (s) of the config's (estimate_td).
constexpr double kTdInitSearchS = 0.03;
/// A rotation-aligned offset this far (s) from the current one restarts the initialization.
constexpr double kTdInitRestartS = 0.001;

/// A landmark as the keyframe leaving the window saw it (loop closure's keyframe database).
struct KeyframeObservation {
  std::uint64_t id = 0;
  FeatureLabel label = FeatureLabel::kStatic;
  bool has_position = false;                       ///< triangulated: p_w valid
  Eigen::Vector3d p_w = Eigen::Vector3d::Zero();   ///< world position
  Eigen::Vector2d uv = Eigen::Vector2d::Zero();    ///< left pixel in this keyframe
  Eigen::Vector2d xy = Eigen::Vector2d::Zero();    ///< left normalized in this keyframe
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

/// What the estimator says about one frame.
struct FrameResult {
  TimeNs t_ns = 0;
  bool initialized = false;  ///< the pose below is valid
  bool reset = false;        ///< a failure was detected at this frame (state reset)
  std::string status;        ///< e.g. "initializing: 4/10 frames", "tracking", "reset: ..."
  imu::NavState state;       ///< body state in the world (valid when initialized)
  double optimization_ms = 0;
  SolveProfile solve;             ///< breakdown of optimization_ms (zero when no solve ran)
  double marginalization_ms = 0;  ///< sliding the window (marginalization or frame drop)
  int landmarks = 0;         ///< landmarks used in the solve
  int candidates = 0;        ///< candidate landmarks in the solve
  int confirmed_dynamic = 0; ///< candidates confirmed dynamic after this solve
  int cleared = 0;           ///< candidates cleared to static after this solve
  std::vector<std::uint64_t> outlier_ids;  ///< landmarks removed by the outlier test after this solve
  int outliers_confirmed = 0;  ///< of those, confirmed dynamic (EstimatorOptions::confirm_outliers)
  int right_outliers = 0;  ///< right observations dropped after this solve (EstimatorOptions::stereo_outlier_px)
  /// Landmarks confirmed dynamic at this frame (post-processing and confirmed outliers), where
  /// they were: the dynamic map's confirmed points (pipeline::System collects them).
  std::vector<MapPoint> confirmed_points;
  bool keyframe = false;
  double td_s = 0;  ///< camera–IMU time offset after this frame (the config's td unless estimate_td)
  /// Why the window was reset at this frame (with `reset`); `status` may say what came next.
  std::string reset_why;
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

/// One instance per sequence; feed IMU samples and frames in time order. Its rooms:
/// estimator.cpp (the frame step), estimator_init.cpp, estimator_solve.cpp,
/// estimator_post.cpp, estimator_reset.cpp, estimator_marginalize.cpp; its state:
/// window_state.h.
class Estimator {
 public:
  Estimator(const camera::Rig& rig, const ImuNoise& noise, const EstimatorOptions& options);
  void addImu(const ImuSample& sample);
  FrameResult addFrame(const frontend::FeatureFrame& features);
  LatestState latest() const;
  /// Current camera–IMU time offset (s): the config's td, or its estimate with estimate_td.
  double timeOffset() const { return w_.td_s; }
  const Rig& rig() const { return rig_; }
  /// Static landmarks that left the window (DESIGN §4.7; confirmed-dynamic ones come out in
  /// FrameResult::confirmed_points).
  const std::vector<MapPoint>& staticMap() const { return map_.static_points; }
  /// Moves the static landmarks still in the window into the static map (end of a run).
  void flushMap();
  /// The marginalization prior (null before the first keyframe left the window).
  const MarginalizationPrior* prior() const { return w_.prior.get(); }

 private:
  void resetWindow();
  /// After a failure: the window, and the offset back to the config's.
  void resetAfterFailure();
  std::unique_ptr<imu::Preintegration> integrate(TimeNs t0, TimeNs t1, const imu::NavState& from) const;
  bool initStep(FrameResult& result);
  bool pnp(int frame);
  bool alignAndStart();
  /// estimate_td: the offset from the initialization window's rotations (alignRotationTimes);
  /// true when it moved by kTdInitRestartS or more and the window restarted.
  bool alignTimeOffset(FrameResult& r);
  /// One candidate observation's information scale 1/m_j (DESIGN §4.5).
  struct CandidateWeight {
    Landmark* lm;
    int frame;
    double info;
  };
  /// The window's Ceres solve: state, prior, IMU and projection factors; gauge restored.
  void optimize(FrameResult& result);
  /// Returns the number of blocks left out (not finite at their start values).
  int addStateAndImu(ceres::Problem& problem, std::vector<std::shared_ptr<ceres::CostFunction>>& costs);
  /// Whether the segment being initialized starts from the last good state's biases (tied to
  /// them): after a failure whose last good state came after its own segment's first-window
  /// transient (kSettledFrames); else from the first start's (zero ba, the alignment's bg).
  bool biasesFromLastGood() const;
  /// The bias prior of the first window after a failure (bias_anchor_), while there is no
  /// marginalization prior.
  void addBiasAnchor(ceres::Problem& problem, std::vector<std::shared_ptr<ceres::CostFunction>>& costs);
  /// Projection factors of the usable landmarks (candidates weighted); returns how many.
  int addProjections(ceres::Problem& problem, std::vector<std::shared_ptr<ceres::CostFunction>>& costs,
                     ceres::LossFunction& huber, std::deque<CandidateWeight>& weights, int& candidates);
  /// The blocks of a landmark's projection factor for `frame` (-1: its stereo factor in the
  /// anchor frame), the td block last when `with_td`.
  std::vector<double*> factorBlocks(Landmark& lm, int frame, bool with_td);
  bool estimatesTd() const { return options_.estimate_td; }
  /// Landmarks estimate their anchor rays (estimate_anchor_ray; the config refuses it with estimate_td).
  bool estimatesRays() const { return options_.estimate_anchor_ray && !options_.estimate_td; }
  /// After a solve with estimated rays: the solver blocks back into the landmarks.
  void storeRays();
  /// Recomputes every candidate weight from the current poses.
  void refreshWeights(std::deque<CandidateWeight>& weights) const;
  /// Moves the window back so that its oldest frame keeps its yaw and position (backend/gauge.h).
  void restoreGauge(const Eigen::Isometry3d& T_w_b0_before);
  void removeOutliers(FrameResult& result);
  /// EstimatorOptions::stereo_outlier_px: right observations that do not fit their landmark.
  int dropRightOutliers();
  void postProcess(FrameResult& result);
  /// Mean left-camera reprojection error (px) of a landmark from its anchor into its other
  /// observations, or into its newest `last_n` ones only (0: all).
  double meanReprojectionErrorPx(const Landmark& lm, int last_n = 0) const;
  Eigen::Vector3d landmarkWorld(const Landmark& lm) const;
  LeavingKeyframe leavingKeyframe() const;  ///< frame 0 and its landmarks, before it leaves
  void addToStaticMap(const Landmark& lm);
  bool failureDetected(std::string& why) const;
  /// Why frame `t1` cannot be integrated to from the window's newest frame (a frame or IMU gap
  /// too long, no samples), empty when it can.
  std::string bridgeProblem(TimeNs t1) const;
  /// After a reset: the new window, just aligned with gravity, moved (yaw and position) onto the
  /// last good state propagated to its oldest frame. Returns how (FrameResult::reanchored).
  std::string reanchor();
  /// True when the block's residual (and the parameters it is evaluated at) are finite.
  static bool finiteAt(const ceres::CostFunction& cost, const std::vector<double*>& blocks);
  void slide(bool keyframe);
  void marginalizeOldest();
  void dropSecondNewest();

  EstimatorOptions options_;
  Rig rig_;
  ImuNoise noise_;
  WindowState w_;
  SegmentState seg_;
  MapState map_;
  std::optional<LeavingKeyframe> leaving_;  ///< set by marginalizeOldest, moved into the frame's result
};

}  // namespace idyvins::backend
