#pragma once
// Online camera–IMU extrinsic calibration (estimate_extrinsic, VINS-Fusion's key): the left
// camera's mount T_b_c0 as a pose block of the window (the stereo pair kept rigid), a prior
// from its start values, its marginal uncertainty, and the hand–eye rotation that starts it
// without a usable guess (estimate_extrinsic 2, as VINS-Mono's initial rotation calibration).

#include <ceres/sized_cost_function.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <optional>
#include <vector>

#include "backend/marginalization.h"
#include "backend/projection_factors.h"

namespace idyvins::backend {

/// A prior on a pose block (7: t, q xyzw) at `at`: residual [(t − t0)/σ_t; 2 vec(q0⁻¹ q)/σ_rot].
/// σ_rot ≤ 0 leaves the rotation free (its rows are zero). Block: the pose (7).
class PosePriorFactor final : public ceres::SizedCostFunction<6, 7> {
 public:
  PosePriorFactor(const Extrinsic& at, double sigma_t_m, double sigma_rot_rad);
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;

 private:
  Extrinsic at_;
  double w_t_, w_rot_;
};

/// The marginal standard deviations of a pose block in a prior (its tangent [δt, δθ]): the
/// pseudo-inverse of J0ᵀJ0 (the gauge's null space does not reach a gauge-invariant block).
/// nullopt when the prior does not hold the block.
struct PoseSigma {
  double t_m = 0;      ///< largest translation σ, m
  double rot_rad = 0;  ///< largest rotation σ, rad
};
std::optional<PoseSigma> marginalSigma(const MarginalizationPrior& prior, const double* block);

/// One pair of relative rotations over the same interval: the body's (gyroscope) and the left
/// camera's (its tracks), q_b_k_b_k+1 and q_c_k_c_k+1.
struct RotationPair {
  Eigen::Quaterniond q_body = Eigen::Quaterniond::Identity();
  Eigen::Quaterniond q_cam = Eigen::Quaterniond::Identity();
};

/// Hand–eye rotation q_b_c from pairs with q_body · q_b_c = q_b_c · q_cam: the null vector of
/// the stacked (L(q_body) − R(q_cam)) with pairs weighted down by their disagreement with the
/// previous solution (Huber-like, VINS-Mono's rule). Returns it when the problem is well
/// conditioned (the second-smallest singular value above `min_sigma2`), else nullopt.
std::optional<Eigen::Quaterniond> handEyeRotation(const std::vector<RotationPair>& pairs, double min_sigma2 = 0.25);

/// Relative rotation of the left camera between two frames from matched normalized points
/// (RANSAC essential matrix, the rotation of the cheirality-checked decomposition):
/// q_c_a_c_b maps points of camera b into camera a. nullopt with too few inliers.
std::optional<Eigen::Quaterniond> relativeCameraRotation(const std::vector<Eigen::Vector2d>& xy_a,
                                                         const std::vector<Eigen::Vector2d>& xy_b, double focal_px);

}  // namespace idyvins::backend
