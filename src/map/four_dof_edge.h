#pragma once
// The pose graph's edge residual as a Ceres cost (map/pose_graph.h builds the graph of them).

#include <ceres/sized_cost_function.h>

#include <Eigen/Core>

#include "map/pose_graph.h"

namespace idyvins::map {

/// Residual of one edge i -> j, weighted: [ (R_i^T (p_j - p_i) - t_ij) / sigma_t ; wrap(yaw_j - yaw_i - dyaw_ij) /
/// sigma_yaw ] with R_i = Rz(yaw_i) * tilt_i, tilt_i = Ry(pitch_i) Rx(roll_i) fixed. Parameters: p_i (3), yaw_i (1),
/// p_j (3), yaw_j (1).
class FourDofEdgeCost final : public ceres::SizedCostFunction<4, 3, 1, 3, 1> {
 public:
  FourDofEdgeCost(const RelativePose4& measured, const Eigen::Matrix3d& tilt_i, double sigma_t, double sigma_yaw);
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;

 private:
  RelativePose4 measured_;
  Eigen::Matrix3d tilt_i_;
  double w_t_, w_yaw_;
};

}  // namespace idyvins::map
