#include "imu/preintegration.h"

#include <algorithm>
#include <stdexcept>

#include "core/so3.h"

namespace idyvins::imu {

using Eigen::Matrix3d;
using Eigen::Quaterniond;
using Eigen::Vector3d;

Preintegration::Preintegration(const Vector3d& acc0, const Vector3d& gyr0, const Vector3d& ba, const Vector3d& bg,
                               const ImuNoise& noise)
    : acc0_first_(acc0), gyr0_first_(gyr0), ba_(ba), bg_(bg), g_w_(0, 0, noise.g_norm) {
  const double q[6] = {noise.acc_n, noise.gyr_n, noise.acc_n, noise.gyr_n, noise.acc_w, noise.gyr_w};
  for (int k = 0; k < 6; ++k) noise_diag_.segment<3>(3 * k).setConstant(q[k] * q[k]);
  reset();
}

void Preintegration::reset() {
  acc0_ = acc0_first_;
  gyr0_ = gyr0_first_;
  sum_dt_ = 0;
  delta_p_.setZero();
  delta_v_.setZero();
  delta_q_.setIdentity();
  jacobian_.setIdentity();
  covariance_.setZero();
}

void Preintegration::push(double dt, const Vector3d& acc1, const Vector3d& gyr1) {
  samples_.push_back({dt, acc1, gyr1});
  step(dt, acc1, gyr1);
}

void Preintegration::repropagate(const Vector3d& ba, const Vector3d& bg) {
  ba_ = ba;
  bg_ = bg;
  reset();
  for (const auto& s : samples_) step(s.dt, s.acc, s.gyr);
}

bool Preintegration::needsRepropagation(const Vector3d& ba, const Vector3d& bg) const {
  // Thresholds as in VINS-Fusion's estimator: beyond them the linear correction drifts.
  return (ba - ba_).norm() > 0.10 || (bg - bg_).norm() > 0.01;
}

void Preintegration::step(double dt, const Vector3d& acc1, const Vector3d& gyr1) {
  const Matrix3d I = Matrix3d::Identity();
  const Vector3d a0 = acc0_ - ba_, a1 = acc1 - ba_;
  const Vector3d w = 0.5 * (gyr0_ + gyr1) - bg_;
  const Matrix3d R0 = delta_q_.toRotationMatrix();
  const Quaterniond q1 = (delta_q_ * idyvins::deltaQ(w * dt)).normalized();
  const Matrix3d R1 = q1.toRotationMatrix();
  const Vector3d un_acc = 0.5 * (R0 * a0 + R1 * a1);
  const Vector3d p1 = delta_p_ + delta_v_ * dt + 0.5 * un_acc * dt * dt;
  const Vector3d v1 = delta_v_ + un_acc * dt;

  const Matrix3d Wx = hat(w), A0x = hat(a0), A1x = hat(a1);
  const Matrix3d IminusWdt = I - Wx * dt;
  const double dt2 = dt * dt;
  Matrix15 F = Matrix15::Zero();
  F.block<3, 3>(kP, kP) = I;
  F.block<3, 3>(kP, kR) = -0.25 * R0 * A0x * dt2 - 0.25 * R1 * A1x * IminusWdt * dt2;
  F.block<3, 3>(kP, kV) = I * dt;
  F.block<3, 3>(kP, kBa) = -0.25 * (R0 + R1) * dt2;
  F.block<3, 3>(kP, kBg) = 0.25 * R1 * A1x * dt2 * dt;
  F.block<3, 3>(kR, kR) = IminusWdt;
  F.block<3, 3>(kR, kBg) = -I * dt;
  F.block<3, 3>(kV, kR) = -0.5 * R0 * A0x * dt - 0.5 * R1 * A1x * IminusWdt * dt;
  F.block<3, 3>(kV, kV) = I;
  F.block<3, 3>(kV, kBa) = -0.5 * (R0 + R1) * dt;
  F.block<3, 3>(kV, kBg) = 0.5 * R1 * A1x * dt2;
  F.block<3, 3>(kBa, kBa) = I;
  F.block<3, 3>(kBg, kBg) = I;

  Eigen::Matrix<double, 15, 18> V = Eigen::Matrix<double, 15, 18>::Zero();
  V.block<3, 3>(kP, 0) = 0.25 * R0 * dt2;
  V.block<3, 3>(kP, 3) = -0.125 * R1 * A1x * dt2 * dt;
  V.block<3, 3>(kP, 6) = 0.25 * R1 * dt2;
  V.block<3, 3>(kP, 9) = V.block<3, 3>(kP, 3);
  V.block<3, 3>(kR, 3) = 0.5 * I * dt;
  V.block<3, 3>(kR, 9) = 0.5 * I * dt;
  V.block<3, 3>(kV, 0) = 0.5 * R0 * dt;
  V.block<3, 3>(kV, 3) = -0.25 * R1 * A1x * dt2;
  V.block<3, 3>(kV, 6) = 0.5 * R1 * dt;
  V.block<3, 3>(kV, 9) = V.block<3, 3>(kV, 3);
  V.block<3, 3>(kBa, 12) = I * dt;
  V.block<3, 3>(kBg, 15) = I * dt;

  jacobian_ = F * jacobian_;
  covariance_ = F * covariance_ * F.transpose() + V * noise_diag_.asDiagonal() * V.transpose();

  delta_p_ = p1;
  delta_v_ = v1;
  delta_q_ = q1;
  sum_dt_ += dt;
  acc0_ = acc1;
  gyr0_ = gyr1;
}

Vector3d Preintegration::correctedDeltaP(const Vector3d& ba, const Vector3d& bg) const {
  return delta_p_ + jacobian_.block<3, 3>(kP, kBa) * (ba - ba_) + jacobian_.block<3, 3>(kP, kBg) * (bg - bg_);
}

Vector3d Preintegration::correctedDeltaV(const Vector3d& ba, const Vector3d& bg) const {
  return delta_v_ + jacobian_.block<3, 3>(kV, kBa) * (ba - ba_) + jacobian_.block<3, 3>(kV, kBg) * (bg - bg_);
}

Quaterniond Preintegration::correctedDeltaQ(const Vector3d& bg) const {
  return (delta_q_ * expQuat(jacobian_.block<3, 3>(kR, kBg) * (bg - bg_))).normalized();
}

Vector15 Preintegration::residual(const NavState& si, const NavState& sj) const {
  const double T = sum_dt_;
  const Quaterniond qi_inv = si.q_w_b.conjugate();
  Vector15 r;
  r.segment<3>(kP) = qi_inv * (0.5 * g_w_ * T * T + sj.p_w_b - si.p_w_b - si.v_w * T) - correctedDeltaP(si.ba, si.bg);
  r.segment<3>(kR) = 2.0 * (correctedDeltaQ(si.bg).conjugate() * (qi_inv * sj.q_w_b)).vec();
  r.segment<3>(kV) = qi_inv * (g_w_ * T + sj.v_w - si.v_w) - correctedDeltaV(si.ba, si.bg);
  r.segment<3>(kBa) = sj.ba - si.ba;
  r.segment<3>(kBg) = sj.bg - si.bg;
  return r;
}

NavState Preintegration::predict(const NavState& si) const {
  const double T = sum_dt_;
  NavState sj = si;
  sj.q_w_b = (si.q_w_b * correctedDeltaQ(si.bg)).normalized();
  sj.p_w_b = si.p_w_b + si.v_w * T - 0.5 * g_w_ * T * T + si.q_w_b * correctedDeltaP(si.ba, si.bg);
  sj.v_w = si.v_w - g_w_ * T + si.q_w_b * correctedDeltaV(si.ba, si.bg);
  return sj;
}

RelativeMotion Preintegration::relativeMotion(const NavState& si) const {
  const NavState sj = predict(si);
  RelativeMotion m;
  m.q_bi_bj = (si.q_w_b.conjugate() * sj.q_w_b).normalized();
  m.p_bi_bj = si.q_w_b.conjugate() * (sj.p_w_b - si.p_w_b);
  m.cov_p = covariance_.block<3, 3>(kP, kP);
  return m;
}

Preintegration integrateBetween(const std::vector<ImuSample>& samples, TimeNs t_i, TimeNs t_j, const Vector3d& ba,
                                const Vector3d& bg, const ImuNoise& noise) {
  if (samples.empty() || samples.front().t_ns > t_i || samples.back().t_ns < t_j || t_j < t_i)
    throw std::invalid_argument("integrateBetween: IMU samples do not cover the interval");
  // Linear interpolation of a sample at time t.
  const auto at = [&](TimeNs t) {
    const auto it =
        std::lower_bound(samples.begin(), samples.end(), t, [](const ImuSample& s, TimeNs v) { return s.t_ns < v; });
    if (it->t_ns == t || it == samples.begin()) return *it;
    const ImuSample& a = *(it - 1);
    const ImuSample& b = *it;
    const double u = static_cast<double>(t - a.t_ns) / static_cast<double>(b.t_ns - a.t_ns);
    ImuSample s;
    s.t_ns = t;
    s.acc_b = (1 - u) * a.acc_b + u * b.acc_b;
    s.gyr_b = (1 - u) * a.gyr_b + u * b.gyr_b;
    return s;
  };
  const ImuSample first = at(t_i);
  Preintegration pre(first.acc_b, first.gyr_b, ba, bg, noise);
  TimeNs t_prev = t_i;
  for (auto it = std::upper_bound(samples.begin(), samples.end(), t_i,
                                  [](TimeNs v, const ImuSample&s) { return v < s.t_ns; });
       it != samples.end() && it->t_ns < t_j; ++it) {
    pre.push(toSeconds(it->t_ns - t_prev), it->acc_b, it->gyr_b);
    t_prev = it->t_ns;
  }
  if (t_j > t_prev) {
    const ImuSample last = at(t_j);
    pre.push(toSeconds(t_j - t_prev), last.acc_b, last.gyr_b);
  }
  return pre;
}

}  // namespace idyvins::imu
