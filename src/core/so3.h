#pragma once
// SO(3) helpers on Eigen: hat, exp/log, right Jacobian, quaternion products as matrices.
// Rotation perturbations are on the right: R ⊞ δθ = R Exp(δθ).

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace idyvins {

/// Skew-symmetric matrix [v]_x such that [v]_x w = v × w.
inline Eigen::Matrix3d hat(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

/// Exp map: rotation vector (rad) to unit quaternion.
inline Eigen::Quaterniond expQuat(const Eigen::Vector3d& w) {
  const double theta = w.norm();
  if (theta < 1e-8) return Eigen::Quaterniond(1.0, 0.5 * w.x(), 0.5 * w.y(), 0.5 * w.z()).normalized();
  const Eigen::Vector3d axis = w / theta;
  return Eigen::Quaterniond(Eigen::AngleAxisd(theta, axis));
}

/// Log map: unit quaternion to rotation vector (rad), angle in [0, pi].
inline Eigen::Vector3d logQuat(const Eigen::Quaterniond& q_in) {
  Eigen::Quaterniond q = q_in.w() < 0 ? Eigen::Quaterniond(-q_in.coeffs()) : q_in;
  const double n = q.vec().norm();
  if (n < 1e-10) return 2.0 * q.vec() / q.w();
  const double theta = 2.0 * std::atan2(n, q.w());
  return theta / n * q.vec();
}

/// Right Jacobian of SO(3): Exp(φ + δ) ≈ Exp(φ) Exp(Jr(φ) δ).
inline Eigen::Matrix3d rightJacobian(const Eigen::Vector3d& phi) {
  const double theta = phi.norm();
  const Eigen::Matrix3d K = hat(phi);
  if (theta < 1e-6) return Eigen::Matrix3d::Identity() - 0.5 * K + K * K / 6.0;
  const double t2 = theta * theta;
  return Eigen::Matrix3d::Identity() - (1.0 - std::cos(theta)) / t2 * K +
         (theta - std::sin(theta)) / (t2 * theta) * K * K;
}

/// Small-angle quaternion [1, θ/2] (normalized), as used by midpoint integration.
inline Eigen::Quaterniond deltaQ(const Eigen::Vector3d& theta) {
  return Eigen::Quaterniond(1.0, 0.5 * theta.x(), 0.5 * theta.y(), 0.5 * theta.z()).normalized();
}

/// Left-multiplication matrix: q ⊗ p = qLeft(q) * [p.w, p.vec] (w first).
inline Eigen::Matrix4d qLeft(const Eigen::Quaterniond& q) {
  Eigen::Matrix4d m;
  m(0, 0) = q.w();
  m.block<1, 3>(0, 1) = -q.vec().transpose();
  m.block<3, 1>(1, 0) = q.vec();
  m.block<3, 3>(1, 1) = q.w() * Eigen::Matrix3d::Identity() + hat(q.vec());
  return m;
}

/// Right-multiplication matrix: p ⊗ q = qRight(q) * [p.w, p.vec] (w first).
inline Eigen::Matrix4d qRight(const Eigen::Quaterniond& q) {
  Eigen::Matrix4d m;
  m(0, 0) = q.w();
  m.block<1, 3>(0, 1) = -q.vec().transpose();
  m.block<3, 1>(1, 0) = q.vec();
  m.block<3, 3>(1, 1) = q.w() * Eigen::Matrix3d::Identity() - hat(q.vec());
  return m;
}

/// Quaternion with non-negative w (same rotation).
inline Eigen::Quaterniond positiveW(const Eigen::Quaterniond& q) {
  return q.w() >= 0 ? q : Eigen::Quaterniond(-q.coeffs());
}

}  // namespace idyvins
