#include "backend/parameter_blocks.h"

#include "core/so3.h"

namespace idyvins::backend {

void posePlus(const double* x, const double* delta, double* x_plus_delta) {
  Eigen::Map<const Eigen::Vector3d> p(x);
  Eigen::Map<const Eigen::Quaterniond> q(x + 3);
  Eigen::Map<const Eigen::Vector3d> dp(delta);
  Eigen::Map<const Eigen::Vector3d> dq(delta + 3);
  Eigen::Map<Eigen::Vector3d> p_out(x_plus_delta);
  Eigen::Map<Eigen::Quaterniond> q_out(x_plus_delta + 3);
  p_out = p + dp;
  q_out = (q * expQuat(dq)).normalized();
}

ceres::Problem::Options borrowingProblemOptions() {
  ceres::Problem::Options o;
  o.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  o.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  o.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  return o;
}

void setPose(const Eigen::Vector3d& p, const Eigen::Quaterniond& q, double* block) {
  Eigen::Map<Eigen::Vector3d> p_out(block);
  Eigen::Map<Eigen::Quaterniond> q_out(block + 3);
  p_out = p;
  q_out = q.normalized();
}

bool PoseManifold::Plus(const double* x, const double* delta, double* x_plus_delta) const {
  posePlus(x, delta, x_plus_delta);
  return true;
}

bool PoseManifold::PlusJacobian(const double*, double* jacobian) const {
  Eigen::Map<Eigen::Matrix<double, 7, 6, Eigen::RowMajor>> J(jacobian);
  J.setZero();
  J.topRows<6>().setIdentity();
  return true;
}

bool PoseManifold::Minus(const double* y, const double* x, double* y_minus_x) const {
  Eigen::Map<const Eigen::Vector3d> py(y), px(x);
  Eigen::Map<const Eigen::Quaterniond> qy(y + 3), qx(x + 3);
  Eigen::Map<Eigen::Matrix<double, 6, 1>> d(y_minus_x);
  d.head<3>() = py - px;
  d.tail<3>() = logQuat(qx.conjugate() * qy);
  return true;
}

bool PoseManifold::MinusJacobian(const double*, double* jacobian) const {
  Eigen::Map<Eigen::Matrix<double, 6, 7, Eigen::RowMajor>> J(jacobian);
  J.setZero();
  J.leftCols<6>().setIdentity();
  return true;
}

}  // namespace idyvins::backend
