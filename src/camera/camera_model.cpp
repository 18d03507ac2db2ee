#include "camera/camera_model.h"

#include <Eigen/LU>
#include <cmath>

namespace idyvins::camera {
namespace {
constexpr int kMaxIterations = 30;
constexpr double kTolerance = 1e-13;  // on the distorted normalized coordinates

/// Radial-tangential distortion (k1 k2 p1 p2) of a point xy; its Jacobian when non-null.
Eigen::Vector2d radtan(const std::array<double, 4>& dist, const Eigen::Vector2d& xy, Eigen::Matrix2d* d_xyd_d_xy) {
  const double k1 = dist[0], k2 = dist[1], p1 = dist[2], p2 = dist[3];
  const double x = xy.x(), y = xy.y();
  const double r2 = x * x + y * y;
  const double radial = 1.0 + k1 * r2 + k2 * r2 * r2;
  const Eigen::Vector2d xyd(x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x),
                            y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y);
  if (d_xyd_d_xy) {
    const double d_radial_d_r2 = k1 + 2.0 * k2 * r2;
    auto& J = *d_xyd_d_xy;
    J(0, 0) = radial + 2.0 * x * x * d_radial_d_r2 + 2.0 * p1 * y + 6.0 * p2 * x;
    J(0, 1) = 2.0 * x * y * d_radial_d_r2 + 2.0 * p1 * x + 2.0 * p2 * y;
    J(1, 0) = 2.0 * x * y * d_radial_d_r2 + 2.0 * p1 * x + 2.0 * p2 * y;
    J(1, 1) = radial + 2.0 * y * y * d_radial_d_r2 + 6.0 * p1 * y + 2.0 * p2 * x;
  }
  return xyd;
}

/// Newton on radtan(xy) = xyd from xyd; false when it does not reach 1e-10.
bool undistortRadtan(const std::array<double, 4>& dist, const Eigen::Vector2d& xyd, Eigen::Vector2d& xy) {
  xy = xyd;
  for (int it = 0; it < kMaxIterations; ++it) {
    Eigen::Matrix2d J;
    const Eigen::Vector2d err = radtan(dist, xy, &J) - xyd;
    if (err.norm() < kTolerance) return true;
    xy -= J.lu().solve(err);
    if (!xy.allFinite()) return false;
  }
  return (radtan(dist, xy, nullptr) - xyd).norm() < 1e-10;
}
}  // namespace

// ---------------------------------------------------------------- pinhole + radtan

Eigen::Vector2d PinholeRadtan::distort(const Eigen::Vector2d& xy, Eigen::Matrix2d* d_xyd_d_xy) const {
  return radtan(params_.dist, xy, d_xyd_d_xy);
}

bool PinholeRadtan::project(const Eigen::Vector3d& p_c, Eigen::Vector2d& uv,
                            Eigen::Matrix<double, 2, 3>* d_uv_d_p) const {
  if (!(p_c.z() > 1e-9)) return false;
  const double iz = 1.0 / p_c.z();
  const Eigen::Vector2d xy(p_c.x() * iz, p_c.y() * iz);
  Eigen::Matrix2d d_xyd_d_xy;
  const Eigen::Vector2d xyd = distort(xy, d_uv_d_p ? &d_xyd_d_xy : nullptr);
  uv << params_.fx * xyd.x() + params_.cx, params_.fy * xyd.y() + params_.cy;
  if (d_uv_d_p) {
    Eigen::Matrix<double, 2, 3> d_xy_d_p;
    d_xy_d_p << iz, 0, -xy.x() * iz, 0, iz, -xy.y() * iz;
    *d_uv_d_p = Eigen::DiagonalMatrix<double, 2>(params_.fx, params_.fy) * d_xyd_d_xy * d_xy_d_p;
  }
  return true;
}

bool PinholeRadtan::liftToNormalized(const Eigen::Vector2d& uv, Eigen::Vector2d& xy) const {
  const Eigen::Vector2d xyd((uv.x() - params_.cx) / params_.fx, (uv.y() - params_.cy) / params_.fy);
  return undistortRadtan(params_.dist, xyd, xy);
}

// ---------------------------------------------------------------- Kannala-Brandt

/// The widest ray a Kannala–Brandt lens images here (rad off the axis).
constexpr double kMaxTheta = 0.5 * M_PI + 0.4;

double KannalaBrandt::radius(double theta, double* d_r_d_theta) const {
  const double t2 = theta * theta;
  const auto& k = params_.dist;
  // r = θ (1 + k2 θ² + k3 θ⁴ + k4 θ⁶ + k5 θ⁸)
  const double poly = 1.0 + t2 * (k[0] + t2 * (k[1] + t2 * (k[2] + t2 * k[3])));
  if (d_r_d_theta) *d_r_d_theta = 1.0 + t2 * (3.0 * k[0] + t2 * (5.0 * k[1] + t2 * (7.0 * k[2] + t2 * 9.0 * k[3])));
  return theta * poly;
}

bool KannalaBrandt::project(const Eigen::Vector3d& p_c, Eigen::Vector2d& uv,
                            Eigen::Matrix<double, 2, 3>* d_uv_d_p) const {
  const double x = p_c.x(), y = p_c.y(), z = p_c.z();
  const double rho2 = x * x + y * y;
  const double rho = std::sqrt(rho2);
  if (p_c.norm() < 1e-12) return false;
  const double theta = std::atan2(rho, z);
  if (theta > kMaxTheta) return false;  // beyond the fisheye's useful field of view
  double dr = 0;
  const double r = radius(theta, &dr);
  if (rho < 1e-12) {  // on the optical axis: r/ρ → 1/z
    uv << params_.cx, params_.cy;
    if (d_uv_d_p) *d_uv_d_p << params_.fx / z, 0, 0, 0, params_.fy / z, 0;
    return z > 0;
  }
  const double s = r / rho;  // pixels per unit of (x, y), before the focal scaling
  uv << params_.fx * s * x + params_.cx, params_.fy * s * y + params_.cy;
  if (d_uv_d_p) {
    const double n2 = rho2 + z * z;
    // θ = atan2(ρ, z): dθ/dx = z x / (ρ n²), dθ/dy = z y / (ρ n²), dθ/dz = -ρ / n²
    const Eigen::Vector3d d_theta(z * x / (rho * n2), z * y / (rho * n2), -rho / n2);
    // s = r(θ)/ρ: ds = dr/ρ dθ - r/ρ² dρ, with dρ = (x, y, 0)/ρ
    const Eigen::Vector3d d_rho(x / rho, y / rho, 0.0);
    const Eigen::Vector3d d_s = dr / rho * d_theta - r / rho2 * d_rho;
    Eigen::Matrix<double, 2, 3> J;
    J.row(0) = params_.fx * (x * d_s.transpose() + Eigen::RowVector3d(s, 0, 0));
    J.row(1) = params_.fy * (y * d_s.transpose() + Eigen::RowVector3d(0, s, 0));
    *d_uv_d_p = J;
  }
  return true;
}

bool KannalaBrandt::angleOf(double r, double& theta) const {
  theta = r;  // Newton on radius(θ) = r
  bool converged = false;
  for (int it = 0; it < kMaxIterations; ++it) {
    double dr = 0;
    const double err = radius(theta, &dr) - r;
    if (std::abs(err) < kTolerance) {
      converged = true;
      break;
    }
    if (std::abs(dr) < 1e-12) return false;
    theta -= err / dr;
  }
  return converged || std::abs(radius(theta) - r) <= 1e-10;
}

bool KannalaBrandt::liftToRay(const Eigen::Vector2d& uv, Eigen::Vector3d& ray) const {
  const Eigen::Vector2d m((uv.x() - params_.cx) / params_.fx, (uv.y() - params_.cy) / params_.fy);
  const double r = m.norm();
  double theta = 0;
  if (r < 1e-15) {
    ray = Eigen::Vector3d::UnitZ();
    return true;
  }
  if (!angleOf(r, theta) || !(theta >= 0.0 && theta <= kMaxTheta)) return false;  // past the model's field of view
  ray << std::sin(theta) / r * m, std::cos(theta);
  return true;
}

bool KannalaBrandt::liftToNormalized(const Eigen::Vector2d& uv, Eigen::Vector2d& xy) const {
  const Eigen::Vector2d m((uv.x() - params_.cx) / params_.fx, (uv.y() - params_.cy) / params_.fy);
  const double r = m.norm();
  if (r < 1e-15) {
    xy.setZero();
    return true;
  }
  double theta = 0;
  if (!angleOf(r, theta)) return false;
  if (!(theta >= 0.0 && theta < 0.5 * M_PI - 1e-6)) return false;  // not in front of the camera
  xy = std::tan(theta) / r * m;
  return true;
}

// ---------------------------------------------------------------- Mei (unified omnidirectional)

bool Mei::project(const Eigen::Vector3d& p_c, Eigen::Vector2d& uv, Eigen::Matrix<double, 2, 3>* d_uv_d_p) const {
  const double xi = params_.xi, n = p_c.norm();
  if (n < 1e-12) return false;
  if (xi > 1.0 && p_c.z() <= -n / xi) return false;  // beyond the fold: two rays share a pixel
  const double zz = p_c.z() + xi * n;
  if (!(zz > 1e-9)) return false;
  const Eigen::Vector2d mu(p_c.x() / zz, p_c.y() / zz);
  Eigen::Matrix2d d_md_d_mu;
  const Eigen::Vector2d md = radtan(params_.dist, mu, d_uv_d_p ? &d_md_d_mu : nullptr);
  uv << params_.fx * md.x() + params_.cx, params_.fy * md.y() + params_.cy;
  if (d_uv_d_p) {
    // m_u = (x, y) / zz with zz = z + ξ ‖p‖: dzz/dp = ξ p / ‖p‖ + e_z
    const Eigen::RowVector3d d_zz = xi / n * p_c.transpose() + Eigen::RowVector3d(0, 0, 1);
    Eigen::Matrix<double, 2, 3> d_mu_d_p;
    d_mu_d_p.row(0) = (Eigen::RowVector3d(1, 0, 0) - mu.x() * d_zz) / zz;
    d_mu_d_p.row(1) = (Eigen::RowVector3d(0, 1, 0) - mu.y() * d_zz) / zz;
    *d_uv_d_p = Eigen::DiagonalMatrix<double, 2>(params_.fx, params_.fy) * d_md_d_mu * d_mu_d_p;
  }
  return true;
}

bool Mei::liftToSphere(const Eigen::Vector2d& uv, Eigen::Vector3d& ray) const {
  const Eigen::Vector2d md((uv.x() - params_.cx) / params_.fx, (uv.y() - params_.cy) / params_.fy);
  Eigen::Vector2d mu;
  if (!undistortRadtan(params_.dist, md, mu)) return false;
  // The sphere point whose projection is m_u: λ (m_u, 1) − (0, 0, ξ) with ‖·‖ = 1.
  const double xi = params_.xi, r2 = mu.squaredNorm();
  const double disc = 1.0 + (1.0 - xi * xi) * r2;
  if (disc < 0) return false;  // outside the image of the sphere (ξ > 1)
  const double lambda = (xi + std::sqrt(disc)) / (1.0 + r2);
  ray << lambda * mu.x(), lambda * mu.y(), lambda - xi;
  return xi <= 1.0 || ray.z() > -1.0 / xi;
}

bool Mei::liftToNormalized(const Eigen::Vector2d& uv, Eigen::Vector2d& xy) const {
  Eigen::Vector3d ray;
  if (!liftToSphere(uv, ray) || !(ray.z() > 1e-6)) return false;  // not in front of the camera
  xy = ray.head<2>() / ray.z();
  return true;
}

std::unique_ptr<CameraModel> makeCamera(const CameraParams& params) {
  switch (params.type) {
    case ModelType::kPinhole:
      return std::make_unique<PinholeRadtan>(params);
    case ModelType::kKannalaBrandt:
      return std::make_unique<KannalaBrandt>(params);
    case ModelType::kMei:
      return std::make_unique<Mei>(params);
  }
  return nullptr;
}

}  // namespace idyvins::camera
