#include "backend/window_state.h"

#include "backend/imu_factor.h"
#include "backend/parameter_blocks.h"

namespace idyvins::backend {

Eigen::Isometry3d WindowFrame::T_w_b() const {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::Map<const Eigen::Quaterniond>(pose.data() + 3).normalized().toRotationMatrix();
  T.translation() = Eigen::Map<const Eigen::Vector3d>(pose.data());
  return T;
}

imu::NavState WindowFrame::nav() const { return navStateFromBlocks(pose.data(), sb.data()); }

void WindowFrame::setNav(const imu::NavState& s) {
  setPose(s.p_w_b, s.q_w_b, pose.data());
  Eigen::Map<Eigen::Matrix<double, 9, 1>> v(sb.data());
  v << s.v_w, s.ba, s.bg;
}

std::vector<Eigen::Isometry3d> WindowState::poses() const {
  std::vector<Eigen::Isometry3d> T;
  for (int i = 0; i <= count; ++i) T.push_back(frames[i].T_w_b());
  return T;
}

}  // namespace idyvins::backend
