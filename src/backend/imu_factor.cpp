#include "backend/imu_factor.h"

#include <Eigen/Cholesky>

#include "core/so3.h"

namespace idyvins::backend {

using Eigen::Matrix3d;
using Eigen::Quaterniond;
using Eigen::Vector3d;
using imu::kBa;
using imu::kBg;
using imu::kP;
using imu::kR;
using imu::kV;

imu::NavState navStateFromBlocks(const double* pose, const double* sb) {
  imu::NavState s;
  s.p_w_b = Eigen::Map<const Vector3d>(pose);
  s.q_w_b = Eigen::Map<const Quaterniond>(pose + 3).normalized();
  s.v_w = Eigen::Map<const Vector3d>(sb);
  s.ba = Eigen::Map<const Vector3d>(sb + 3);
  s.bg = Eigen::Map<const Vector3d>(sb + 6);
  return s;
}

void imuResidual(const imu::Preintegration& pre, const imu::NavState& si, const imu::NavState& sj,
                 imu::Vector15* residual, Eigen::Matrix<double, 15, 6>* d_pose_i, Eigen::Matrix<double, 15, 9>* d_sb_i,
                 Eigen::Matrix<double, 15, 6>* d_pose_j, Eigen::Matrix<double, 15, 9>* d_sb_j) {
  if (residual) *residual = pre.residual(si, sj);
  if (!d_pose_i && !d_sb_i && !d_pose_j && !d_sb_j) return;
  const double T = pre.sumDt();
  const Vector3d& g = pre.gravity();
  const Matrix3d Ri_T = si.q_w_b.conjugate().toRotationMatrix();
  const auto Jblk = [&](int row, int col) { return pre.jacobian().block<3, 3>(row, col); };
  const Vector3d phi = Jblk(kR, kBg) * (si.bg - pre.linearizedBg());
  const Quaterniond c = pre.correctedDeltaQ(si.bg);
  const Quaterniond qij = si.q_w_b.conjugate() * sj.q_w_b;
  const Quaterniond M = c.conjugate() * qij;  // rotation error quaternion

  if (d_pose_i) {
    auto& D = *d_pose_i;
    D.setZero();
    D.block<3, 3>(kP, 0) = -Ri_T;
    D.block<3, 3>(kP, 3) = hat(Ri_T * (0.5 * g * T * T + sj.p_w_b - si.p_w_b - si.v_w * T));
    D.block<3, 3>(kR, 3) = -(qLeft(c.conjugate()) * qRight(qij)).bottomRightCorner<3, 3>();
    D.block<3, 3>(kV, 3) = hat(Ri_T * (g * T + sj.v_w - si.v_w));
  }
  if (d_sb_i) {
    auto& D = *d_sb_i;
    D.setZero();
    D.block<3, 3>(kP, 0) = -Ri_T * T;
    D.block<3, 3>(kP, 3) = -Jblk(kP, kBa);
    D.block<3, 3>(kP, 6) = -Jblk(kP, kBg);
    D.block<3, 3>(kR, 6) = -qRight(M).bottomRightCorner<3, 3>() * rightJacobian(phi) * Jblk(kR, kBg);
    D.block<3, 3>(kV, 0) = -Ri_T;
    D.block<3, 3>(kV, 3) = -Jblk(kV, kBa);
    D.block<3, 3>(kV, 6) = -Jblk(kV, kBg);
    D.block<3, 3>(kBa, 3) = -Matrix3d::Identity();
    D.block<3, 3>(kBg, 6) = -Matrix3d::Identity();
  }
  if (d_pose_j) {
    auto& D = *d_pose_j;
    D.setZero();
    D.block<3, 3>(kP, 0) = Ri_T;
    D.block<3, 3>(kR, 3) = qLeft(M).bottomRightCorner<3, 3>();
  }
  if (d_sb_j) {
    auto& D = *d_sb_j;
    D.setZero();
    D.block<3, 3>(kV, 0) = Ri_T;
    D.block<3, 3>(kBa, 3) = Matrix3d::Identity();
    D.block<3, 3>(kBg, 6) = Matrix3d::Identity();
  }
}

ImuFactor::ImuFactor(const imu::Preintegration* pre) : pre_(pre) {
  const imu::Matrix15 info = pre->covariance().inverse();
  sqrt_info_ = Eigen::LLT<imu::Matrix15>(0.5 * (info + info.transpose())).matrixL().transpose();
}

bool ImuFactor::Evaluate(double const* const* parameters, double* residuals, double** jacobians) const {
  const imu::NavState si = navStateFromBlocks(parameters[0], parameters[1]);
  const imu::NavState sj = navStateFromBlocks(parameters[2], parameters[3]);
  imu::Vector15 r;
  Eigen::Matrix<double, 15, 6> Jpi, Jpj;
  Eigen::Matrix<double, 15, 9> Jsi, Jsj;
  const bool want = jacobians != nullptr;
  imuResidual(*pre_, si, sj, &r, want && jacobians[0] ? &Jpi : nullptr, want && jacobians[1] ? &Jsi : nullptr,
              want && jacobians[2] ? &Jpj : nullptr, want && jacobians[3] ? &Jsj : nullptr);
  Eigen::Map<imu::Vector15> r_out(residuals);
  r_out = sqrt_info_ * r;
  if (!want) return true;
  using Pose15 = Eigen::Matrix<double, 15, 7, Eigen::RowMajor>;
  using Sb15 = Eigen::Matrix<double, 15, 9, Eigen::RowMajor>;
  if (jacobians[0]) {
    Eigen::Map<Pose15> out(jacobians[0]);
    out.leftCols<6>() = sqrt_info_ * Jpi;
    out.rightCols<1>().setZero();
  }
  if (jacobians[1]) {
    Eigen::Map<Sb15> out(jacobians[1]);
    out = sqrt_info_ * Jsi;
  }
  if (jacobians[2]) {
    Eigen::Map<Pose15> out(jacobians[2]);
    out.leftCols<6>() = sqrt_info_ * Jpj;
    out.rightCols<1>().setZero();
  }
  if (jacobians[3]) {
    Eigen::Map<Sb15> out(jacobians[3]);
    out = sqrt_info_ * Jsj;
  }
  return true;
}

BiasPriorFactor::BiasPriorFactor(const Vector3d& ba0, const Vector3d& bg0, double sigma_acc, double sigma_gyr) {
  b0_ << ba0, bg0;
  w_ << Vector3d::Constant(sigma_acc > 0 ? 1.0 / sigma_acc : 0.0),
      Vector3d::Constant(sigma_gyr > 0 ? 1.0 / sigma_gyr : 0.0);
}

bool BiasPriorFactor::Evaluate(double const* const* parameters, double* residuals, double** jacobians) const {
  const Eigen::Map<const Eigen::Matrix<double, 6, 1>> b(parameters[0] + 3);
  Eigen::Map<Eigen::Matrix<double, 6, 1>> r(residuals);
  r = w_.cwiseProduct(b - b0_);
  if (jacobians && jacobians[0]) {
    Eigen::Map<Eigen::Matrix<double, 6, 9, Eigen::RowMajor>> J(jacobians[0]);
    J.setZero();
    J.rightCols<6>().diagonal() = w_;
  }
  return true;
}

}  // namespace idyvins::backend
