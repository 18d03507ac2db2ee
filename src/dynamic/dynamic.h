#pragma once
// The paper's contribution (DESIGN §4.1-4.4): inertial motion prior, minimum
// projection error d_s, coefficient-of-variation elimination, candidate marking.
// Pure math plus one front-end filter (IdyFilter).

#include <Eigen/Geometry>
#include <algorithm>
#include <string>
#include <vector>

#include "camera/camera_params.h"
#include "core/measurements.h"
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

/// Credibility factor Σ = (1 + σ_P / ‖t_c‖)², σ_P² = trace of the position covariance (eq. 3c).
double credibility(const frontend::MotionPrior& prior);

/// Squared pixel distance of x1 (frame k+1) to the epipolar line of x0 (frame k):
/// e² / (a² + b²) with [a b c] = p_kᵀ K⁻ᵀ E K⁻¹, E = [t]× R (eq. 2-3, without Σ). Inputs
/// are undistorted normalized coordinates; fx, fy scale them to pixels. 0 if degenerate.
double epipolarErrorPx2(const Eigen::Vector2d& x0, const Eigen::Vector2d& x1, const Eigen::Matrix3d& R_prev_cur,
                        const Eigen::Vector3d& t_prev_cur, double fx, double fy);

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
  std::vector<double> d_s;       ///< per tracked feature (px²), before elimination
  std::vector<double> d_s_kept;  ///< the ones left after elimination
};

/// The `idy` front-end filter: d_s per tracked feature from the motion prior,
/// elimination (remove), marking (label kCandidate). Frames without a valid prior
/// pass unfiltered. With eliminate = false (mode idy-ba) it only marks.
class IdyFilter final : public frontend::FeatureFilter {
 public:
  IdyFilter(double lambda_dy, double lambda_dy_c, bool eliminate = true)
      : lambda_dy_(lambda_dy), lambda_c_(lambda_dy_c), eliminate_(eliminate) {}
  void apply(const frontend::FilterContext& context, std::vector<frontend::FilterItem>& items) override;
  const FrameStats& lastStats() const { return stats_; }

 private:
  double lambda_dy_, lambda_c_;
  bool eliminate_;
  FrameStats stats_;
};

}  // namespace idyvins::dynamic
