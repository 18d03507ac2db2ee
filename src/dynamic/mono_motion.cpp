#include "dynamic/mono_motion.h"

#include <Eigen/Geometry>
#include <cmath>

namespace idyvins::dynamic {

using Eigen::Matrix3d;
using Eigen::Vector2d;
using Eigen::Vector3d;

namespace {

/// ρ of the two rays; false when the rays do not meet in a usable way.
bool inverseDepth(const Vector2d& x_a, const Vector2d& x_c, const Matrix3d& R, const Vector3d& t, double& rho) {
  const Vector3d f_a(x_a.x(), x_a.y(), 1.0), w = R * Vector3d(x_c.x(), x_c.y(), 1.0);
  const Vector3d wt = w.cross(t), wf = w.cross(f_a);
  const double n2 = wt.squaredNorm();
  if (n2 < 1e-18) return false;
  rho = wt.dot(wf) / n2;
  // The current ray must point at the point: (f_a - ρ t) along +w.
  return (f_a - rho * t).dot(w) > 0;
}

}  // namespace

DepthSign depthSign(const Vector2d& x_a, const Vector2d& x_c, const Matrix3d& R_a_c, const Vector3d& t_a_c,
                    double sigma_p2, double focal, double sigma_px) {
  DepthSign out;
  double rho = 0;
  if (focal <= 0 || !inverseDepth(x_a, x_c, R_a_c, t_a_c, rho)) return out;
  const double h_x = 1e-6, h_t = 1e-6 * std::max(t_a_c.norm(), 1e-3);
  double var_x = 0, var_t = 0;
  for (int i = 0; i < 2; ++i) {
    const Vector2d e = Vector2d::Unit(i) * h_x;
    double ap, am, cp, cm;
    if (!inverseDepth(x_a + e, x_c, R_a_c, t_a_c, ap) || !inverseDepth(x_a - e, x_c, R_a_c, t_a_c, am) ||
        !inverseDepth(x_a, x_c + e, R_a_c, t_a_c, cp) || !inverseDepth(x_a, x_c - e, R_a_c, t_a_c, cm))
      return out;
    var_x += std::pow((ap - am) / (2 * h_x), 2) + std::pow((cp - cm) / (2 * h_x), 2);
  }
  for (int i = 0; i < 3; ++i) {
    const Vector3d e = Vector3d::Unit(i) * h_t;
    double p, m;
    if (!inverseDepth(x_a, x_c, R_a_c, t_a_c + e, p) || !inverseDepth(x_a, x_c, R_a_c, t_a_c - e, m)) return out;
    var_t += std::pow((p - m) / (2 * h_t), 2);
  }
  const double sigma_n = sigma_px / focal;
  out.rho = rho;
  out.sigma_rho = std::sqrt(sigma_n * sigma_n * var_x + std::max(sigma_p2, 0.0) * var_t);
  if (!(out.sigma_rho > 0) || !std::isfinite(out.sigma_rho)) return out;
  out.z = rho / out.sigma_rho;
  out.valid = true;
  return out;
}

}  // namespace idyvins::dynamic
