#pragma once
// Parameter-block layouts of the sliding-window problem and the pose manifold.
//
// Pose block (7):       p_w_b (x y z), q_w_b (x y z w, Eigen's coefficient order).
// SpeedBias block (9):  v_w (3), ba (3), bg (3).
// InvDepth block (1):   inverse depth of a landmark in its anchor (first) left camera.
//
// Jacobian convention for pose blocks (as in VINS-Fusion): a cost function writes
// the derivative with respect to the 6-dim tangent perturbation [δp, δθ] (with
// p + δp, q ⊗ Exp(δθ)) into the first 6 columns of its 7-column Jacobian and zero
// into the last; PoseManifold::PlusJacobian is [I6; 0], so Ceres' tangent
// Jacobian J·PlusJacobian is exactly that derivative.

#include <ceres/manifold.h>
#include <ceres/problem.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace idyvins::backend {

constexpr int kPoseSize = 7;
constexpr int kPoseTangentSize = 6;
constexpr int kSpeedBiasSize = 9;

/// Right-perturbation manifold of a pose block: p + δp, q ⊗ Exp(δθ).
class PoseManifold final : public ceres::Manifold {
 public:
  int AmbientSize() const override { return kPoseSize; }
  int TangentSize() const override { return kPoseTangentSize; }
  bool Plus(const double* x, const double* delta, double* x_plus_delta) const override;
  bool PlusJacobian(const double* x, double* jacobian) const override;
  bool Minus(const double* y, const double* x, double* y_minus_x) const override;
  bool MinusJacobian(const double* x, double* jacobian) const override;
};

/// Applies a tangent perturbation to a pose block (same as PoseManifold::Plus).
void posePlus(const double* x, const double* delta, double* x_plus_delta);

/// Problem options for cost functions, losses and manifolds owned by the caller.
ceres::Problem::Options borrowingProblemOptions();

/// Writes p and q into a pose block.
void setPose(const Eigen::Vector3d& p, const Eigen::Quaterniond& q, double* block);

}  // namespace idyvins::backend
