#pragma once
// Depth of a stereo observation.

#include <Eigen/Geometry>

namespace idyvins::camera {

/// Depth in the left camera of a point seen at normalized xy_l (left) and xy_r (right),
/// least squares over the two right-image equations; false when ill-conditioned.
bool stereoDepth(const Eigen::Vector2d& xy_l, const Eigen::Vector2d& xy_r, const Eigen::Isometry3d& T_r_l,
                 double& depth);

}  // namespace idyvins::camera
