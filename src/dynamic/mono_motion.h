#pragma once
// Extension of DESIGN §4.3 (not in the paper) for one camera: the depth-sign test. The
// paper's d_s is blind to motion along the epipolar line; two cameras measure the depth
// (the stereo motion test), one cannot. What one camera still sees is where on the line a
// point lies: a static point lies between its image at infinity and the epipole's side a
// finite depth puts it on. A point on a vehicle that overtakes the camera moves the other
// way, as if it were beyond infinity (a negative inverse depth).

#include <Eigen/Core>

namespace idyvins::dynamic {

/// The inverse depth at which the anchor ray x_a (normalized, anchor frame) meets the
/// current ray x_c (normalized, current frame) under the motion P_a = R P_c + t, and its
/// standard deviation from the two observations' noise (sigma_px / focal per coordinate)
/// and the translation's (sigma_p2 per axis, m²). z = rho / sigma_rho: a static point has
/// z ≳ 0; z ≪ 0 says it moved along the line away from the camera's own motion.
struct DepthSign {
  bool valid = false;    ///< false: no translation across the ray, or the current ray points away
  double rho = 0;        ///< inverse depth at the anchor (1/m, in the units of t)
  double sigma_rho = 0;  ///< its standard deviation
  double z = 0;          ///< rho / sigma_rho
};

/// rho from x̃_c ∥ Rᵀ(x̃_a − ρ t): with w = R x̃_c, ρ = (w × t)·(w × x̃_a) / ‖w × t‖²; the
/// derivatives by central differences. Invalid when ‖w × t‖ is below 1e-9 (the point on
/// the epipole or no translation) or the point would lie behind the current camera.
DepthSign depthSign(const Eigen::Vector2d& x_a, const Eigen::Vector2d& x_c, const Eigen::Matrix3d& R_a_c,
                    const Eigen::Vector3d& t_a_c, double sigma_p2, double focal, double sigma_px);

}  // namespace idyvins::dynamic
