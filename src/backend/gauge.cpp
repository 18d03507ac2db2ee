#include "backend/gauge.h"

#include <cmath>

namespace idyvins::backend {

Eigen::Isometry3d gaugeCorrection(const Eigen::Isometry3d& T_w_b_before, const Eigen::Isometry3d& T_w_b_after) {
  const Eigen::Matrix3d dR = T_w_b_before.linear() * T_w_b_after.linear().transpose();
  const double yaw = std::atan2(dR(1, 0) - dR(0, 1), dR(0, 0) + dR(1, 1));
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T.translation() = T_w_b_before.translation() - T.linear() * T_w_b_after.translation();
  return T;
}

}  // namespace idyvins::backend
