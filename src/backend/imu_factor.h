#pragma once
// The 15-dim IMU preintegration factor between states i and j.

#include <ceres/sized_cost_function.h>

#include "imu/preintegration.h"

namespace idyvins::backend {

/// Residual and tangent Jacobians of the IMU factor (unweighted). Jacobians are
/// 15x6 for poses (tangent [δp, δθ]) and 15x9 for speed/bias; any may be null.
void imuResidual(const imu::Preintegration& pre, const imu::NavState& si, const imu::NavState& sj,
                 imu::Vector15* residual, Eigen::Matrix<double, 15, 6>* d_pose_i, Eigen::Matrix<double, 15, 9>* d_sb_i,
                 Eigen::Matrix<double, 15, 6>* d_pose_j, Eigen::Matrix<double, 15, 9>* d_sb_j);

/// Ceres wrapper. Blocks: pose_i (7), speed_bias_i (9), pose_j (7), speed_bias_j (9).
/// Weighted by the square-root information of the preintegration covariance,
/// computed at construction. The preintegration must outlive the factor.
class ImuFactor final : public ceres::SizedCostFunction<15, 7, 9, 7, 9> {
 public:
  explicit ImuFactor(const imu::Preintegration* pre);
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;

 private:
  const imu::Preintegration* pre_;
  imu::Matrix15 sqrt_info_;
};

/// A prior on the biases of one speed/bias block [v, ba, bg]: residual
/// [(ba − ba0)/σa; (bg − bg0)/σg]; a σ ≤ 0 leaves that bias free (zero rows).
/// Written here rather than ceres::NormalPrior: libceres allocates that class's Eigen members and
/// our code frees them, and under AddressSanitizer Eigen turns off EIGEN_GLIBC_MALLOC_ALREADY_ALIGNED
/// (Eigen/src/Core/util/Memory.h), so an ASan build frees with Eigen's own aligned free what
/// libceres allocated with plain malloc (a heap-buffer-overflow report; release builds match).
class BiasPriorFactor final : public ceres::SizedCostFunction<6, 9> {
 public:
  BiasPriorFactor(const Eigen::Vector3d& ba0, const Eigen::Vector3d& bg0, double sigma_acc, double sigma_gyr);
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;

 private:
  Eigen::Matrix<double, 6, 1> b0_;
  Eigen::Matrix<double, 6, 1> w_;  // 1/σ per row, 0 for a free bias
};

/// Reads a NavState from a pose block and a speed/bias block.
imu::NavState navStateFromBlocks(const double* pose, const double* speed_bias);

}  // namespace idyvins::backend
