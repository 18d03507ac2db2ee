#pragma once
// A camera rig: each camera's intrinsics and its mount on the body (IMU) frame.

#include <Eigen/Geometry>
#include <vector>

#include "camera/camera_params.h"

namespace idyvins::camera {

struct Rig {
  std::vector<CameraParams> cams;        ///< cam0 (left), cam1 (right) when stereo
  std::vector<Eigen::Isometry3d> T_b_c;  ///< body_T_camX: maps camera points into the body
  bool stereo() const { return cams.size() >= 2 && T_b_c.size() >= 2; }
};

}  // namespace idyvins::camera
