#include "camera/stereo.h"

#include <cmath>

namespace idyvins::camera {

bool stereoDepth(const Eigen::Vector2d& xy_l, const Eigen::Vector2d& xy_r, const Eigen::Isometry3d& T_r_l,
                 double& depth) {
  const Eigen::Vector3d m(xy_l.x(), xy_l.y(), 1.0);
  const Eigen::Vector3d Rm = T_r_l.linear() * m, t = T_r_l.translation();
  // x_r (Rm.z d + t.z) = Rm.x d + t.x, same for y: a d = c.
  const Eigen::Vector2d a(xy_r.x() * Rm.z() - Rm.x(), xy_r.y() * Rm.z() - Rm.y());
  const Eigen::Vector2d c(t.x() - xy_r.x() * t.z(), t.y() - xy_r.y() * t.z());
  const double aa = a.squaredNorm();
  if (aa < 1e-12) return false;
  depth = a.dot(c) / aa;
  return std::isfinite(depth);
}

}  // namespace idyvins::camera
