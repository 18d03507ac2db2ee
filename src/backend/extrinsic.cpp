#include "backend/extrinsic.h"

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <cmath>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>

#include "core/so3.h"

namespace idyvins::backend {

using Eigen::Matrix3d;
using Eigen::Matrix4d;
using Eigen::Quaterniond;
using Eigen::Vector2d;
using Eigen::Vector3d;

PosePriorFactor::PosePriorFactor(const Extrinsic& at, double sigma_t_m, double sigma_rot_rad)
    : at_(at), w_t_(1.0 / sigma_t_m), w_rot_(sigma_rot_rad > 0 ? 1.0 / sigma_rot_rad : 0.0) {}

bool PosePriorFactor::Evaluate(double const* const* parameters, double* residuals, double** jacobians) const {
  const Eigen::Map<const Vector3d> t(parameters[0]);
  const Quaterniond q = Eigen::Map<const Quaterniond>(parameters[0] + 3).normalized();
  const Quaterniond dq = at_.q_b_c.conjugate() * q;
  Eigen::Map<Eigen::Matrix<double, 6, 1>> r(residuals);
  r.head<3>() = w_t_ * (t - at_.t_b_c);
  r.tail<3>() = w_rot_ * 2.0 * dq.vec();
  if (jacobians && jacobians[0]) {
    Eigen::Map<Eigen::Matrix<double, 6, 7, Eigen::RowMajor>> J(jacobians[0]);
    J.setZero();
    J.block<3, 3>(0, 0) = w_t_ * Matrix3d::Identity();
    // 2 vec(dq ⊗ [1, δθ/2]) = 2 vec(dq) + (w I + [v]×) δθ.
    J.block<3, 3>(3, 3) = w_rot_ * (dq.w() * Matrix3d::Identity() + hat(dq.vec()));
  }
  return true;
}

std::optional<PoseSigma> marginalSigma(const MarginalizationPrior& prior, const double* block) {
  int offset = 0, found = -1;
  for (std::size_t k = 0; k < prior.blocks.size(); ++k) {
    if (prior.blocks[k] == block) found = offset;
    offset += prior.tangent_sizes[k];
  }
  if (found < 0) return std::nullopt;
  const Eigen::MatrixXd H = prior.J0.transpose() * prior.J0;
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(H);
  const double floor = 1e-10 * std::max(1.0, eig.eigenvalues().maxCoeff());
  Eigen::VectorXd inv = eig.eigenvalues();
  for (int i = 0; i < inv.size(); ++i) inv(i) = inv(i) > floor ? 1.0 / inv(i) : 0.0;
  const Eigen::MatrixXd V = eig.eigenvectors().middleRows(found, 6);
  const Eigen::MatrixXd cov = V * inv.asDiagonal() * V.transpose();
  PoseSigma s;
  s.t_m = std::sqrt(cov.diagonal().head<3>().maxCoeff());
  s.rot_rad = std::sqrt(cov.diagonal().tail<3>().maxCoeff());
  return s;
}

namespace {

/// Left and right multiplication matrices of a quaternion, coefficients (w, x, y, z).
Matrix4d leftMatrix(const Quaterniond& q) {
  Matrix4d m;
  m(0, 0) = q.w();
  m.block<1, 3>(0, 1) = -q.vec().transpose();
  m.block<3, 1>(1, 0) = q.vec();
  m.block<3, 3>(1, 1) = q.w() * Matrix3d::Identity() + hat(q.vec());
  return m;
}

Matrix4d rightMatrix(const Quaterniond& q) {
  Matrix4d m = leftMatrix(q);
  m.block<3, 3>(1, 1) = q.w() * Matrix3d::Identity() - hat(q.vec());
  return m;
}

}  // namespace

std::optional<Quaterniond> handEyeRotation(const std::vector<RotationPair>& pairs, double min_sigma2) {
  if (pairs.size() < 3) return std::nullopt;
  Quaterniond q_b_c = Quaterniond::Identity();
  Eigen::Vector4d singular = Eigen::Vector4d::Zero();
  constexpr double kHuberRad = 5.0 * M_PI / 180.0;
  for (int pass = 0; pass < 3; ++pass) {
    Eigen::MatrixXd A(4 * static_cast<int>(pairs.size()), 4);
    for (std::size_t k = 0; k < pairs.size(); ++k) {
      double w = 1.0;
      if (pass > 0) {  // pairs that disagree with the last solution count less
        const Quaterniond predicted = q_b_c * pairs[k].q_cam * q_b_c.conjugate();
        const double angle = pairs[k].q_body.angularDistance(predicted);
        if (angle > kHuberRad) w = kHuberRad / angle;
      }
      A.block<4, 4>(4 * static_cast<int>(k), 0) = w * (leftMatrix(pairs[k].q_body) - rightMatrix(pairs[k].q_cam));
    }
    const Eigen::JacobiSVD<Eigen::MatrixXd> svd(A, Eigen::ComputeFullV);
    const Eigen::Vector4d x = svd.matrixV().col(3);
    q_b_c = Quaterniond(x(0), x(1), x(2), x(3)).normalized();
    singular = svd.singularValues();
  }
  if (!(singular(2) > min_sigma2)) return std::nullopt;
  return q_b_c;
}

std::optional<Quaterniond> relativeCameraRotation(const std::vector<Vector2d>& xy_a, const std::vector<Vector2d>& xy_b,
                                                  double focal_px) {
  constexpr int kMinInliers = 15;
  if (xy_a.size() != xy_b.size() || static_cast<int>(xy_a.size()) < kMinInliers) return std::nullopt;
  std::vector<cv::Point2d> a, b;
  for (std::size_t k = 0; k < xy_a.size(); ++k) {
    a.emplace_back(xy_a[k].x(), xy_a[k].y());
    b.emplace_back(xy_b[k].x(), xy_b[k].y());
  }
  cv::Mat inliers;
  const cv::Mat E = cv::findEssentialMat(a, b, 1.0, cv::Point2d(0, 0), cv::RANSAC, 0.999, 1.0 / focal_px, inliers);
  if (E.rows != 3 || E.cols != 3) return std::nullopt;
  cv::Mat R, t;
  const int good = cv::recoverPose(E, a, b, R, t, 1.0, cv::Point2d(0, 0), inliers);
  if (good < kMinInliers) return std::nullopt;
  Matrix3d R_cb_ca;
  cv::cv2eigen(R, R_cb_ca);  // points of camera a into camera b
  return Quaterniond(R_cb_ca.transpose()).normalized();
}

}  // namespace idyvins::backend
