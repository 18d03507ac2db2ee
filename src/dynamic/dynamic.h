#pragma once
// The paper's contribution (DESIGN §4.1-4.4): inertial motion prior, minimum
// projection error d_s, coefficient-of-variation elimination, candidate marking.
// Pure math plus one front-end filter (IdyFilter).

#include <Eigen/Geometry>
#include <algorithm>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

#include "camera/camera_model.h"
#include "camera/camera_params.h"
#include "core/measurements.h"
#include "dynamic/idy_options.h"
#include "dynamic/mono_motion.h"
#include "frontend/feature_filter.h"
#include "imu/preintegration.h"

namespace idyvins::dynamic {

/// Camera motion between frames k and k+1 from the body motion and the extrinsic
/// (exact conjugation T_c = T_bc⁻¹ T_b T_bc, DESIGN §4.1), with the credibility factor.
frontend::MotionPrior cameraMotionPrior(const imu::RelativeMotion& body, const Eigen::Isometry3d& T_b_c);

/// Motion prior for the frame at t_cur from the newest state (at t_prev) and the IMU
/// samples (must cover [t_prev, t_cur]); invalid when they do not.
frontend::MotionPrior motionPrior(const imu::NavState& state_prev, TimeNs t_prev, TimeNs t_cur,
                                  const std::vector<ImuSample>& imu, const ImuNoise& noise,
                                  const Eigen::Isometry3d& T_b_c);

/// Extension (not in the paper), imu: 0: the body motion over [t_prev, t_cur] at the constant
/// velocity, linear and angular, between the two newest states (T_w_b at t_older and t_newer,
/// t_older < t_newer), with the position covariance of an unmodelled acceleration σ_a:
/// (½ σ_a Δt²)² I. The twist is the pair's relative motion in the older body frame, scaled by
/// Δt / (t_newer − t_older) (rotation vector and translation alike).
imu::RelativeMotion constantVelocityMotion(const Eigen::Isometry3d& T_w_b_older, TimeNs t_older,
                                           const Eigen::Isometry3d& T_w_b_newer, TimeNs t_newer, TimeNs t_prev,
                                           TimeNs t_cur, double acc_sigma);

/// Credibility factor Σ = (1 + σ_P / ‖t_c‖)², σ_P² = trace of the position covariance (eq. 3c).
double credibility(const frontend::MotionPrior& prior);

/// Squared pixel distance of x1 (frame k+1) to the epipolar line of x0 (frame k):
/// e² / (a² + b²) with [a b c] = p_kᵀ K⁻ᵀ E K⁻¹, E = [t]× R (eq. 2-3, without Σ). Inputs
/// are undistorted normalized coordinates; fx, fy scale them to pixels. 0 if degenerate.
double epipolarErrorPx2(const Eigen::Vector2d& x0, const Eigen::Vector2d& x1, const Eigen::Matrix3d& R_prev_cur,
                        const Eigen::Vector3d& t_prev_cur, double fx, double fy);

/// Extension of §4.3 (not in the paper): the stereo motion test. The paper's d_s is the
/// projection error minimized over the whole epipolar line, i.e. over every depth, so
/// motion along the line (traffic moving parallel to the camera's own motion) is invisible
/// to it. With a right match in both frames the depth is known up to the stereo noise:
/// the point triangulated in frame k is moved by the prior into frame k+1 and projected
/// into both cameras; the 4-vector of pixel residuals r is weighed by its covariance
/// C = 2 σ_px² diag(S, S) + σ_ρ² J_ρ J_ρᵀ + σ_P² J_t J_tᵀ (measurement noise of the two
/// frames, shaped by S, the match's noise shape in pixels (frontend::matchShape; identity:
/// isotropic), in both images; inverse depth ρ with σ_ρ = √2 σ_px √S_uu / (f b), the
/// disparity's noise along the (horizontal) baseline; the prior's position, σ_P² = trace
/// cov_p / 3; J_ρ, J_t by central differences). chi2 = rᵀ C⁻¹ r (χ², 4 dof, for a static point).
struct StereoMotionError {
  bool valid = false;       ///< false: not triangulable in front of both cameras
  double chi2 = 0;          ///< rᵀ C⁻¹ r
  double chi2_left = 0;     ///< the same for the left image's 2 residuals alone (χ², 2 dof)
  double residual_px2 = 0;  ///< ‖r‖²
  double depth = 0;         ///< triangulated depth in frame k (m)
};

/// x0_l, x0_r: left / right normalized coordinates in frame k; x1_l, x1_r: in frame k+1.
/// T_r_l maps left-camera points into the right camera; (R, t)_prev_cur as in MotionPrior.
StereoMotionError stereoMotionError(const Eigen::Vector2d& x0_l, const Eigen::Vector2d& x0_r,
                                    const Eigen::Vector2d& x1_l, const Eigen::Vector2d& x1_r,
                                    const Eigen::Isometry3d& T_r_l, const Eigen::Matrix3d& R_prev_cur,
                                    const Eigen::Vector3d& t_prev_cur, double sigma_p2, double focal, double sigma_px,
                                    const Eigen::Matrix2d& shape = Eigen::Matrix2d::Identity());

/// Noise scale of the stereo motion test on one frame: max(1, q / ref) with q the
/// `quantile` of the frame's χ² values (static points dominate the low quantiles, so q
/// follows the tracker's noise: blur, sensor noise, weak texture). 1 when ref ≤ 0 or
/// chi2 is empty. The χ² are divided by it before the thresholds.
double stereoNoiseScale(std::vector<double> chi2, double quantile, double ref);

/// Information scale of a candidate observation (DESIGN §4.5): 1 / m_j with m_j
/// (px², minimum projection error to the first window observation) floored at 1 px².
inline double candidateInformation(double m_px2) { return 1.0 / std::max(m_px2, 1.0); }

/// Why the elimination loop stopped (eq. 4).
enum class StopRule { kThreshold, kCvReached, kCvNotLowered, kEmpty };
const char* toString(StopRule rule);

/// Result of the CV elimination over one frame's d_s values.
struct Elimination {
  std::vector<std::size_t> removed;  ///< indices into the input, largest d_s first
  double cv_before = 0, cv_after = 0;
  double mean_after = 0, var_after = 0;  ///< μ, σ² of the remaining values (recursions of eq. 5)
  StopRule stop = StopRule::kEmpty;
};

/// Visits d_s by decreasing value; stops when the largest remaining ≤ λ_dy, or CV ≤ √2,
/// or removing it would not lower CV; μ, σ² updated by the O(1) recursions of eq. 5.
Elimination eliminate(const std::vector<double>& d_s, double lambda_dy);

/// Per-frame statistics of the IDY preprocessing (for stats.json).
struct FrameStats {
  bool prior_valid = false;
  double credibility = 0;
  std::size_t tracked = 0, eliminated = 0, candidates = 0;
  double cv_before = 0, cv_after = 0;
  std::string stop_rule;
  std::vector<double> d_s;            ///< per tracked feature (px²), before elimination
  std::vector<double> d_s_kept;       ///< the ones left after elimination
  std::size_t stereo_tested = 0;      ///< features with a right match now and a stereo anchor (stereo test)
  std::size_t stereo_eliminated = 0;  ///< of those, removed (or marked, idy-ba) by the stereo test
  double stereo_noise_scale = 1;      ///< the χ² were divided by this (stereoNoiseScale)
  std::size_t mono_tested = 0;        ///< one camera: features with an anchor (depth-sign test)
  std::size_t mono_eliminated = 0;    ///< of those, removed (or marked, idy-ba) by the depth-sign test
};

/// Extension of DESIGN §4.3 (not in the paper), the lost-corner test: where the motion
/// prior puts a lost corner's previous-frame stereo point if it is static (p_pred in the
/// current left camera, its pixel uv_pred), and how far from there it may be found:
/// the stereo depth's 3σ interval (disparity noise √2 sigma_px), three prior position
/// sigmas at the point's depth, and base_tol_px. Nullopt when it cannot be said (no valid
/// prior, no usable depth, the point or its depth interval behind the camera).
struct StaticPrediction {
  Eigen::Vector3d p_pred;
  Eigen::Vector2d uv_pred;
  double tol_px;
};
std::optional<StaticPrediction> predictStaticPoint(const frontend::LostCorner& corner,
                                                   const frontend::MotionPrior& prior, const camera::CameraModel& left,
                                                   const Eigen::Isometry3d& T_r_l, double sigma_px, double base_tol_px);

/// The `idy` front-end filter: d_s per tracked feature from the motion prior,
/// elimination (remove), marking (label kCandidate). Frames without a valid prior
/// pass unfiltered. With eliminate = false (mode idy-ba) it only marks. With the stereo
/// test on, features that fail it are removed (idy, idy-pre) or marked (idy-ba) too.
class IdyFilter final : public frontend::FeatureFilter {
 public:
  /// With `eliminate` false (idy-ba) features over lambda_dy are only marked.
  explicit IdyFilter(const IdyOptions& options, bool eliminate = true) : o_(options), eliminate_(eliminate) {}
  /// The paper's filter alone (no T_r_l: no stereo motion test).
  IdyFilter(double lambda_dy, double lambda_dy_c, bool eliminate = true) : eliminate_(eliminate) {
    o_.lambda_dy = lambda_dy;
    o_.lambda_dy_c = lambda_dy_c;
  }
  void apply(const frontend::FilterContext& context, std::vector<frontend::FilterItem>& items) override;
  /// The lost-corner test: a corner is judged moving when the tracker does not find it near
  /// its static prediction (predictStaticPoint), its first patch matches clearly worse
  /// than lost_max_zncc there, and no clearly nearer surface hides the prediction.
  frontend::LostCornerJudgement judgeLost(const frontend::FilterContext& context,
                                          const std::vector<frontend::LostCorner>& lost,
                                          frontend::LostCornerProbe& probe) override;
  const FrameStats& lastStats() const { return stats_; }

 private:
  IdyOptions o_;
  bool eliminate_ = true;  ///< false: features over lambda_dy only marked (idy-ba)
  FrameStats stats_;
  struct StereoAnchor {
    Eigen::Vector2d xy_l, xy_r;  ///< stereo observation at the anchor frame (normalized)
    Eigen::Matrix3d R;           ///< P_anchor = R P_cur + t, chained priors
    Eigen::Vector3d t;
    double var_p;  ///< summed prior position variance (m²)
    int steps;     ///< frames since the anchor
    int strikes;   ///< consecutive failures of the test up to now
  };
  std::unordered_map<std::uint64_t, StereoAnchor> stereo_anchors_;  ///< id -> anchor
  double noise_scale_ = 1;  ///< the last frame's stereo noise scale (kept on frames with few tests)
  /// CV elimination (eq. 4-5) and marking (eq. 6) of the tracked items; returns which were removed.
  std::vector<bool> eliminateAndMark(std::vector<frontend::FilterItem>& items, const std::vector<std::size_t>& tracked,
                                     const std::vector<double>& raw, const std::vector<double>& ds);
  /// The stereo motion test (DESIGN §4.9) over the tracked items not removed yet.
  void stereoTest(const frontend::FilterContext& ctx, std::vector<frontend::FilterItem>& items,
                  const std::vector<std::size_t>& tracked, const std::vector<bool>& removed, const Eigen::Matrix3d& R,
                  double fx);
  /// This frame's anchor of an item (chained from its old one, or its previous stereo
  /// observation) and the old anchor's failure count; false when it has no anchor.
  /// With need_right false (one camera) any previous observation starts an anchor.
  bool nextAnchor(const frontend::FilterItem& it, const frontend::MotionPrior& prior, const Eigen::Matrix3d& R,
                  double sigma_p2, bool need_right, StereoAnchor& anchor, int& strikes_before) const;
  /// One camera: the depth-sign test (mono_motion.h) over the tracked items not removed yet.
  void monoTest(const frontend::FilterContext& ctx, std::vector<frontend::FilterItem>& items,
                const std::vector<std::size_t>& tracked, const std::vector<bool>& removed, const Eigen::Matrix3d& R,
                double fx);
  /// A feature failed a motion test: the first failure marks, a repeated one removes
  /// (idy, idy-pre) or marks (idy-ba); true when removed or marked by a repeat.
  bool strike(frontend::FilterItem& it, int strikes);
  void markCandidate(frontend::Feature& f);
  /// One feature the stereo motion test ran on this frame.
  struct StereoTested {
    std::size_t item;
    int strikes_before;
    StereoMotionError e;
  };
  /// Updates noise_scale_ from this frame's χ² (kept when too few features were tested).
  void updateNoiseScale(const std::vector<StereoTested>& tested);
  /// Marks or removes the features that failed the test (a first failure marks, a
  /// repeated clear or persistent one removes); their anchors keep the failure count.
  void judgeStereoFailures(std::vector<frontend::FilterItem>& items, const std::vector<StereoTested>& tested,
                           std::unordered_map<std::uint64_t, StereoAnchor>& anchors, double fx);
};

}  // namespace idyvins::dynamic
