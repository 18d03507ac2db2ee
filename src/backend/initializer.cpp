#include "backend/initializer.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>

#include "core/so3.h"

namespace idyvins::backend {

using Eigen::Matrix3d;
using Eigen::Vector3d;

Vector3d solveGyroBias(const std::vector<Eigen::Quaterniond>& q, const std::vector<const imu::Preintegration*>& pre) {
  Matrix3d A = Matrix3d::Zero();
  Vector3d b = Vector3d::Zero();
  for (std::size_t i = 1; i < q.size(); ++i) {
    const Eigen::Quaterniond q_ij = q[i - 1].conjugate() * q[i];
    const Matrix3d J = pre[i]->jacobian().block<3, 3>(imu::kR, imu::kBg);
    // About each interval's own linearization bias, so the result is the bias itself whatever
    // bias each preintegration was last propagated with (a failed start repropagates them).
    const Vector3d r = 2.0 * (pre[i]->deltaQ().conjugate() * q_ij).vec() + J * pre[i]->linearizedBg();
    A += J.transpose() * J;
    b += J.transpose() * r;
  }
  return A.ldlt().solve(b);
}

Alignment alignVelocityGravity(const std::vector<Eigen::Isometry3d>& T,
                               const std::vector<const imu::Preintegration*>& pre, double g_norm) {
  const int n = static_cast<int>(T.size());
  const int dim = 3 * n + 3;
  Alignment out;
  auto solve = [&](const Vector3d* fixed_g) {
    const int d = fixed_g ? 3 * n : dim;
    Eigen::MatrixXd A = Eigen::MatrixXd::Zero(d, d);
    Eigen::VectorXd b = Eigen::VectorXd::Zero(d);
    for (int j = 1; j < n; ++j) {
      const int i = j - 1;
      const double dt = pre[j]->sumDt();
      const Matrix3d Ri_T = T[i].linear().transpose();
      // Rows: α = Ri_T (pj - pi - vi dt + ½ g dt²);  β = Ri_T (vj - vi + g dt).
      Eigen::MatrixXd H = Eigen::MatrixXd::Zero(6, d);
      Eigen::VectorXd z(6);
      H.block<3, 3>(0, 3 * i) = -Ri_T * dt;
      H.block<3, 3>(3, 3 * i) = -Ri_T;
      H.block<3, 3>(3, 3 * j) = Ri_T;
      z.head<3>() = pre[j]->deltaP() - Ri_T * (T[j].translation() - T[i].translation());
      z.tail<3>() = pre[j]->deltaV();
      if (fixed_g) {
        z.head<3>() -= Ri_T * (*fixed_g) * 0.5 * dt * dt;
        z.tail<3>() -= Ri_T * (*fixed_g) * dt;
      } else {
        H.block<3, 3>(0, 3 * n) = 0.5 * Ri_T * dt * dt;
        H.block<3, 3>(3, 3 * n) = Ri_T * dt;
      }
      A += H.transpose() * H;
      b += H.transpose() * z;
    }
    return Eigen::VectorXd(A.ldlt().solve(b));
  };
  const Eigen::VectorXd x = solve(nullptr);
  const Vector3d g = x.tail<3>();
  out.g_norm_estimated = g.norm();
  if (!(std::abs(g.norm() - g_norm) < 0.1 * g_norm)) return out;
  out.g_w = g.normalized() * g_norm;
  const Eigen::VectorXd v = solve(&out.g_w);
  for (int i = 0; i < n; ++i) out.v_w.push_back(v.segment<3>(3 * i));
  out.ok = v.allFinite();
  return out;
}

std::optional<double> alignRotationTimes(const std::vector<Eigen::Quaterniond>& q, const std::vector<TimeNs>& t,
                                         const std::vector<ImuSample>& imu, double max_shift_s, double step_s,
                                         double* contrast) {
  if (imu.empty() || q.size() != t.size() || step_s <= 0 || max_shift_s < 2 * step_s) return std::nullopt;
  const TimeNs max_ns = static_cast<TimeNs>(std::llround(max_shift_s * 1e9));
  std::vector<std::size_t> pairs;  // i: the pair (i − 1, i)
  for (std::size_t i = 1; i < t.size(); ++i)
    if (t[i - 1] - max_ns >= imu.front().t_ns && t[i] + max_ns <= imu.back().t_ns && t[i] > t[i - 1])
      pairs.push_back(i);
  if (pairs.size() < 3) return std::nullopt;
  const ImuNoise noise;
  const Vector3d zero = Vector3d::Zero();
  // Squared rotation disagreement after the best gyroscope bias (first order) for a shift.
  auto cost = [&](double shift_s) {
    const TimeNs d = static_cast<TimeNs>(std::llround(shift_s * 1e9));
    Matrix3d A = Matrix3d::Zero();
    Vector3d b = Vector3d::Zero();
    std::vector<std::pair<Matrix3d, Vector3d>> terms;
    for (std::size_t i : pairs) {
      const imu::Preintegration pre = imu::integrateBetween(imu, t[i - 1] + d, t[i] + d, zero, zero, noise);
      const Matrix3d J = pre.jacobian().block<3, 3>(imu::kR, imu::kBg);
      const Vector3d r = 2.0 * (pre.deltaQ().conjugate() * (q[i - 1].conjugate() * q[i])).vec();
      A += J.transpose() * J;
      b += J.transpose() * r;
      terms.emplace_back(J, r);
    }
    const Vector3d bg = A.ldlt().solve(b);
    double c = 0;
    for (const auto& [J, r] : terms) c += (r - J * bg).squaredNorm();
    return c;
  };
  const int n = static_cast<int>(std::floor(max_shift_s / step_s));
  std::vector<double> c(2 * n + 1);
  int best = 0;
  for (int k = -n; k <= n; ++k) {
    c[k + n] = cost(k * step_s);
    if (c[k + n] < c[best]) best = k + n;
  }
  if (best == 0 || best == 2 * n) return std::nullopt;
  // Vertex of the parabola through the best grid point and its neighbours.
  const double cm = c[best - 1], c0 = c[best], cp = c[best + 1];
  const double denom = cm - 2 * c0 + cp;
  const double frac = denom > 0 ? 0.5 * (cm - cp) / denom : 0.0;
  if (contrast) {
    const int k = std::max(1, static_cast<int>(std::lround(kContrastShiftS / step_s)));
    // Only a side the range holds (the edge's cost says nothing of the shift's distance).
    double near = std::numeric_limits<double>::infinity();
    if (best - k >= 0) near = std::min(near, c[best - k]);
    if (best + k <= 2 * n) near = std::min(near, c[best + k]);
    *contrast = c0 > 0 ? near / c0 : std::numeric_limits<double>::infinity();
  }
  return ((best - n) + std::clamp(frac, -0.5, 0.5)) * step_s;
}

}  // namespace idyvins::backend
