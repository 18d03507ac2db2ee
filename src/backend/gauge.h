#pragma once
// The 4-DoF gauge of visual-inertial estimation: a rotation about gravity (world z)
// and a translation of the whole window change no residual, so the solver can move
// the window along them freely. After each solve the window is put back so that its
// oldest frame keeps the yaw and position it had before the solve (as VINS-Fusion
// does); roll and pitch stay as optimized (they are observable through gravity).

#include <Eigen/Geometry>

namespace idyvins::backend {

/// The rigid motion T_w_w' (rotation about world z, then translation) that maps the
/// oldest frame's pose after the solve back onto its yaw and position before it:
/// applied as p ← R p + t, q ← R q, v ← R v to every frame of the window. The yaw
/// is the rotation about z closest (Frobenius) to R_before R_after^T, well defined
/// for any body orientation.
Eigen::Isometry3d gaugeCorrection(const Eigen::Isometry3d& T_w_b_before, const Eigen::Isometry3d& T_w_b_after);

}  // namespace idyvins::backend
