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
#include "backend/frame_result.h"
#include "backend/landmark_factors.h"
#include "backend/mono_init.h"
#include "backend/window_state.h"
#include "camera/rig.h"
#include "core/measurements.h"
#include "frontend/feature_frame.h"

namespace ceres {
class CostFunction;
class LossFunction;
}  // namespace ceres

namespace idyvins::backend {

class WindowProblem;
struct WindowSolverSummary;

/// Below this speed (m/s) of the oldest window frame the time offset is held, not estimated.
constexpr double kMinSpeedForTd = 0.2;
/// A segment's biases are trusted after a failure once it has solved this many frames: two
/// windows, past the first window's bias transient (docs/results.md, "A bias prior at the
/// first start"); an earlier failure restarts the biases as a first start does.
constexpr int kSettledFrames = 2 * kWindowSize;
/// At initialization the offset is searched within ± this (s) of the config's (estimate_td).
constexpr double kTdInitSearchS = 0.06;
/// estimate_td: the initialization collects at least this long (s) of PnP poses before it
/// searches the offset over them, and goes on collecting, up to kTdSearchMaxSpanS, while the
/// search does not tell it (alignTimeOffset): a significance (alignRotationTimes' contrast as an
/// F statistic) below kTdSignificance, or a mean turn rate below kTdSearchMinRate (rad/s). Still
/// not telling then, the window starts with the config's offset and estimates it.
constexpr double kTdSearchSpanS = 2.0;
constexpr double kTdSearchMaxSpanS = 5.0;
constexpr double kTdSignificance = 10.0;
constexpr double kTdSearchMinRate = 0.1;
/// One camera: the alignment's scale is taken when its relative standard deviation is at most this.
constexpr double kMonoMaxScaleSigma = 0.1;
/// A rotation-aligned offset this far (s) from the current one restarts the initialization.
constexpr double kTdInitRestartS = 0.001;

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
  /// The rig's extrinsics: the config's, or their current estimate with estimate_extrinsic.
  const Rig& rig() const { return rig_; }
  /// Static landmarks that left the window (DESIGN §4.7; confirmed-dynamic ones come out in
  /// FrameResult::confirmed_points).
  const std::vector<MapPoint>& staticMap() const { return map_.static_points; }
  /// Moves the static landmarks still in the window into the static map (end of a run).
  void flushMap();
  /// The marginalization prior (null before the first keyframe left the window).
  const MarginalizationPrior* prior() const { return w_.prior.get(); }

 private:
  /// Appends the frame to the window: its state predicted with the IMU from the previous one,
  /// its features to the landmarks. Returns whether it is a keyframe (parallax).
  bool pushFrame(const frontend::FeatureFrame& features, bool without_imu);
  void resetWindow();
  /// After a failure: the window, and the offset back to the config's.
  void resetAfterFailure();
  std::unique_ptr<imu::Preintegration> integrate(TimeNs t0, TimeNs t1, const imu::NavState& from) const;
  bool initStep(FrameResult& result);
  /// imu: 0: the newest frame's start from PnP, kept when near the constant-velocity prediction.
  void startFromPnp();
  /// initStep without the IMU (EstimatorOptions::use_imu false).
  bool initStepStereo(FrameResult& result);
  /// Stereo landmarks the first frame needs to start without the IMU.
  static constexpr int kStereoInitLandmarks = 20;
  bool pnp(int frame);
  bool alignAndStart();
  /// The window's states from poses in the visual world, the alignment's gravity and
  /// velocities and the gyroscope bias: gravity-aligned, biases as biasesFromLastGood says.
  void startAligned(const std::vector<Eigen::Vector3d>& p_w_b, const std::vector<Eigen::Quaterniond>& q_w_b,
                    const Alignment& a, const Eigen::Vector3d& bg);
  /// One camera + IMU: once the window is full, its structure from motion (monocularStructure)
  /// and the alignment with the IMU that gives it the metric scale; the window slides
  /// (keyframes by parallax) until both succeed.
  bool initStepMono(FrameResult& result);
  bool alignMonoAndStart(const MonoStructure& sfm);
  /// The window's body orientations and camera positions (up to scale) from `sfm`, with the
  /// preintegrations between its frames; false when a frame has none.
  bool monoWindow(const MonoStructure& sfm, std::vector<Eigen::Quaterniond>& q_w_b, std::vector<Eigen::Vector3d>& p_w_c,
                  std::vector<const imu::Preintegration*>& pre) const;
  /// The window's camera rotations frame to frame from the gyroscope, its bias from `sfm`.
  MonoRotationPrior gyroRotations(const MonoStructure& sfm) const;
  /// estimate_td: the offset from the rotations of the initialization's poses over
  /// kTdSearchSpanS or more (alignRotationTimes); true while it collects them (the window
  /// slid) and when the offset moved by kTdInitRestartS or more and the window restarted.
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
  int addStateAndImu(WindowProblem& problem, std::vector<std::shared_ptr<ceres::CostFunction>>& costs);
  /// Whether the segment being initialized starts from the last good state's biases (tied to
  /// them): after a failure whose last good state came after its own segment's first-window
  /// transient (kSettledFrames); else from the first start's (zero ba, the alignment's bg).
  bool biasesFromLastGood() const;
  /// The bias prior of the first window after a failure (bias_anchor_), while there is no
  /// marginalization prior.
  void addBiasAnchor(WindowProblem& problem, std::vector<std::shared_ptr<ceres::CostFunction>>& costs);
  /// Projection factors of the usable landmarks (candidates weighted); returns how many.
  int addProjections(WindowProblem& problem, std::vector<std::shared_ptr<ceres::CostFunction>>& costs,
                     ceres::LossFunction& huber, std::deque<CandidateWeight>& weights, int& candidates);
  /// The blocks of a landmark's projection factor for `frame` (-1: its stereo factor in the
  /// anchor frame), T_b_c0 after the poses when estimatesExtrinsic(), the td block last when `with_td`.
  std::vector<double*> factorBlocks(Landmark& lm, int frame, bool with_td);
  bool estimatesTd() const { return options_.estimate_td; }
  /// The two-frame factors carry the T_b_c0 block (estimate_extrinsic, once opened).
  bool estimatesExtrinsic() const { return options_.estimate_extrinsic != 0 && ex_.open; }
  ExtrinsicUse extrinsicUse() const { return {estimatesExtrinsic(), ex_.T_c0_c1}; }
  /// estimate_extrinsic: the T_b_c0 block and its prior into the solve, opened once the window is
  /// initialized and moving (kMinSpeedForTd), held constant while it is slow.
  void addExtrinsic(WindowProblem& problem, std::vector<std::shared_ptr<ceres::CostFunction>>& costs);
  /// After a solve: the rig's extrinsics from the block (the stereo pair rigid).
  void storeExtrinsic();
  ExtrinsicEstimate extrinsicEstimate() const;
  /// estimate_extrinsic 2 before the rotation is known: the newest frame pair's gyroscope and
  /// track rotations into the hand–eye calibration; true once the rotation is set.
  bool calibrateRotation(FrameResult& r);
  /// Landmarks estimate their anchor rays (estimate_anchor_ray; the config refuses it with estimate_td).
  bool estimatesRays() const { return options_.estimate_anchor_ray && !options_.estimate_td; }
  /// After a solve: the estimated rays and extrinsics from their solver blocks.
  void storeSolved();
  /// After a solve with estimated rays: the solver blocks back into the landmarks.
  void storeRays();
  /// Recomputes every candidate weight from the current poses.
  void refreshWeights(std::deque<CandidateWeight>& weights) const;
  /// Moves the window (yaw and position, backend/gauge.h) so that its oldest frame has those of
  /// `T_w_b0_before`: after a solve its own from before it, after a reset the predicted one.
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
  /// too long, no samples), empty when it can; `imu_only` tells that the frames themselves are
  /// near enough (the IMU is what is missing: EstimatorOptions::bridge_imu_gaps).
  std::string bridgeProblem(TimeNs t1, bool& imu_only) const;
  /// Across an IMU gap (bridge_imu_gaps): the sb blocks (speed, biases) no IMU factor or prior
  /// reaches are held constant; the first frame an IMU factor reaches again after a gap keeps the
  /// biases carried across it within the gap's random walk (a bias prior).
  void holdSpeedBiasesAcrossGaps(WindowProblem& problem,
                                 std::vector<std::shared_ptr<ceres::CostFunction>>& costs) const;
  /// Frames that entered without an IMU factor and whose speed no IMU factor reaches: their
  /// velocity from the positions around them (what the IMU factors resume from).
  void velocitiesFromPositions();
  /// After a reset: the new window, just aligned with gravity, moved (yaw and position) onto the
  /// last good state propagated to its oldest frame. Returns how (FrameResult::reanchored).
  std::string reanchor();
  /// True when the block's residual (and the parameters it is evaluated at) are finite.
  void solveWithCeres(const WindowProblem& window, std::deque<CandidateWeight>& weights, SolveProfile& p) const;
  static bool finiteAt(const ceres::CostFunction& cost, const std::vector<double*>& blocks);
  void slide(bool keyframe);
  void marginalizeOldest();
  void dropSecondNewest();

  EstimatorOptions options_;
  Rig rig_;
  ImuNoise noise_;
  WindowState w_;
  SegmentState seg_;
  ExtrinsicState ex_;
  MapState map_;
  std::optional<LeavingKeyframe> leaving_;  ///< set by marginalizeOldest, moved into the frame's result
};

}  // namespace idyvins::backend
