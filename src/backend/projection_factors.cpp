#include "backend/projection_factors.h"

#include <cmath>

#include "core/so3.h"

namespace idyvins::backend {

using Eigen::Matrix3d;
using Eigen::Quaterniond;
using Eigen::Vector2d;
using Eigen::Vector3d;
using PoseJac = Eigen::Matrix<double, 2, 7, Eigen::RowMajor>;

namespace {

/// d(x/z, y/z)/d(x, y, z), pre-multiplied by the scalar sqrt information.
Eigen::Matrix<double, 2, 3> reduceJacobian(const Vector3d& p, double sqrt_info) {
  Eigen::Matrix<double, 2, 3> r;
  const double iz = 1.0 / p.z();
  r << iz, 0, -p.x() * iz * iz, 0, iz, -p.y() * iz * iz;
  return sqrt_info * r;
}

Vector3d homogeneous(const Vector2d& xy) { return Vector3d(xy.x(), xy.y(), 1.0); }

}  // namespace

double ProjectionWeight::sqrtInfo() const {
  const double base = focal_px / sigma_px;
  return info_scale ? base * std::sqrt(*info_scale) : base;
}

Vector3d transferPoint(const Vector3d& pts_i, double inv_depth, const Vector3d& p_i, const Quaterniond& q_i,
                       const Vector3d& p_j, const Quaterniond& q_j, const Extrinsic& cam_a, const Extrinsic& cam_b) {
  const Vector3d pts_w = q_i * (cam_a.q_b_c * (pts_i / inv_depth) + cam_a.t_b_c) + p_i;
  return cam_b.q_b_c.conjugate() * (q_j.conjugate() * (pts_w - p_j) - cam_b.t_b_c);
}

ProjectionTwoFrame::ProjectionTwoFrame(const Vector2d& xy_i, const Vector2d& xy_j, const Extrinsic& T_b_c0,
                                       const Extrinsic& T_b_cb, const ProjectionWeight& weight)
    : pts_i_(homogeneous(xy_i)), pts_j_(homogeneous(xy_j)), ex0_(T_b_c0), exb_(T_b_cb), weight_(weight) {}

namespace {

/// ProjectionTwoFrame's residual and Jacobians for homogeneous observations pts_i, pts_j;
/// with jacobians and d_pts_i, also the residual's Jacobian by the anchor point pts_i
/// (R_cj_ci / ρ through the projection), for the estimated-ray factors.
bool evaluateTwoFrame(const Vector3d& pts_i, const Vector3d& pts_j, const Extrinsic& ex0, const Extrinsic& exb,
                      const ProjectionWeight& weight, double const* const* parameters, double* residuals,
                      double** jacobians, Eigen::Matrix<double, 2, 3>* d_pts_i = nullptr) {
  // Rotation matrices once (a quaternion rotates a vector in about twice the operations of a
  // matrix), and the Jacobians as 2x3 blocks: the projection's reduction applied first.
  const Eigen::Map<const Vector3d> Pi(parameters[0]), Pj(parameters[1]);
  const Matrix3d Ri = Eigen::Map<const Quaterniond>(parameters[0] + 3).normalized().toRotationMatrix();
  const Matrix3d Rj = Eigen::Map<const Quaterniond>(parameters[1] + 3).normalized().toRotationMatrix();
  const Matrix3d R_b_ca = ex0.q_b_c.toRotationMatrix(), R_cb_b = exb.q_b_c.toRotationMatrix().transpose();
  const double inv_dep = parameters[2][0];
  const Vector3d pts_imu_i = R_b_ca * (pts_i / inv_dep) + ex0.t_b_c;
  const Vector3d pts_imu_j = Rj.transpose() * (Ri * pts_imu_i + Pi - Pj);
  const Vector3d pts_cam_j = R_cb_b * (pts_imu_j - exb.t_b_c);
  const double sqrt_info = weight.sqrtInfo();
  Eigen::Map<Vector2d> r(residuals);
  r = sqrt_info * (pts_cam_j.head<2>() / pts_cam_j.z() - pts_j.head<2>());
  if (!jacobians) return true;

  const Eigen::Matrix<double, 2, 3> reduce = reduceJacobian(pts_cam_j, sqrt_info);
  const Eigen::Matrix<double, 2, 3> d_p_bj = reduce * (R_cb_b * Rj.transpose());  // by the point in the world
  const Eigen::Matrix<double, 2, 3> d_p_bi = d_p_bj * Ri;                         // by the point in body i
  if (jacobians[0]) {
    Eigen::Map<PoseJac> J(jacobians[0]);
    J.leftCols<3>() = d_p_bj;
    J.middleCols<3>(3) = -d_p_bi * hat(pts_imu_i);
    J.rightCols<1>().setZero();
  }
  if (jacobians[1]) {
    Eigen::Map<PoseJac> J(jacobians[1]);
    J.leftCols<3>() = -d_p_bj;
    J.middleCols<3>(3) = (reduce * R_cb_b) * hat(pts_imu_j);
    J.rightCols<1>().setZero();
  }
  const Eigen::Matrix<double, 2, 3> d_p_ca = d_p_bi * R_b_ca;  // by the point in camera a
  if (jacobians[2]) {
    Eigen::Map<Vector2d> J(jacobians[2]);
    J = d_p_ca * pts_i * (-1.0 / (inv_dep * inv_dep));
  }
  if (d_pts_i) *d_pts_i = d_p_ca / inv_dep;
  return true;
}

}  // namespace

bool ProjectionTwoFrame::Evaluate(double const* const* parameters, double* residuals, double** jacobians) const {
  return evaluateTwoFrame(pts_i_, pts_j_, ex0_, exb_, weight_, parameters, residuals, jacobians);
}

ProjectionOneFrameTwoCam::ProjectionOneFrameTwoCam(const Vector2d& xy_left, const Vector2d& xy_right,
                                                   const Extrinsic& T_b_c0, const Extrinsic& T_b_c1,
                                                   const ProjectionWeight& weight)
    : pts_i_(homogeneous(xy_left)), pts_j_(homogeneous(xy_right)), ex0_(T_b_c0), ex1_(T_b_c1), weight_(weight) {}

namespace {

/// ProjectionOneFrameTwoCam's residual and Jacobian for homogeneous observations pts_i, pts_j;
/// with jacobians and d_pts_i, also the Jacobian by the anchor point pts_i (as evaluateTwoFrame).
bool evaluateOneFrameTwoCam(const Vector3d& pts_i, const Vector3d& pts_j, const Extrinsic& ex0, const Extrinsic& ex1,
                            const ProjectionWeight& weight, double const* const* parameters, double* residuals,
                            double** jacobians, Eigen::Matrix<double, 2, 3>* d_pts_i = nullptr) {
  const double inv_dep = parameters[0][0];
  const Vector3d pts_imu = ex0.q_b_c * (pts_i / inv_dep) + ex0.t_b_c;
  const Vector3d pts_cam_j = ex1.q_b_c.conjugate() * (pts_imu - ex1.t_b_c);
  const double sqrt_info = weight.sqrtInfo();
  Eigen::Map<Vector2d> r(residuals);
  r = sqrt_info * (pts_cam_j.head<2>() / pts_cam_j.z() - pts_j.head<2>());
  if (jacobians && jacobians[0]) {
    Eigen::Map<Vector2d> J(jacobians[0]);
    J = reduceJacobian(pts_cam_j, sqrt_info) * ex1.q_b_c.conjugate().toRotationMatrix() * ex0.q_b_c.toRotationMatrix() *
        pts_i * (-1.0 / (inv_dep * inv_dep));
  }
  if (jacobians && d_pts_i)
    *d_pts_i = reduceJacobian(pts_cam_j, sqrt_info) * ex1.q_b_c.conjugate().toRotationMatrix() *
               ex0.q_b_c.toRotationMatrix() / inv_dep;
  return true;
}

}  // namespace

bool ProjectionOneFrameTwoCam::Evaluate(double const* const* parameters, double* residuals, double** jacobians) const {
  return evaluateOneFrameTwoCam(pts_i_, pts_j_, ex0_, ex1_, weight_, parameters, residuals, jacobians);
}

namespace {

/// The observation moved to the current time offset td, homogeneous.
Vector3d atOffset(const TimedObservation& o, double td) { return homogeneous(o.xy - (td - o.td_obs) * o.velocity); }

Vector3d velocity3(const TimedObservation& o) { return Vector3d(o.velocity.x(), o.velocity.y(), 0.0); }

}  // namespace

ProjectionTwoFrameTd::ProjectionTwoFrameTd(const TimedObservation& obs_i, const TimedObservation& obs_j,
                                           const Extrinsic& T_b_c0, const Extrinsic& T_b_cb,
                                           const ProjectionWeight& weight)
    : i_(obs_i), j_(obs_j), ex0_(T_b_c0), exb_(T_b_cb), weight_(weight) {}

namespace {

/// d r / d td of a two-frame factor at the moved observations pts_i (anchor) and the
/// observation velocities v_i, v_j: pts_i moves by −v_i (the anchor ray scaled by 1/ρ), pts_j by −v_j.
Vector2d twoFrameTdJacobian(const Vector3d& pts_i, double const* const* poses, double inv_dep, const Extrinsic& ex0,
                            const Extrinsic& exb, double sqrt_info, const TimedObservation& i,
                            const TimedObservation& j) {
  const Eigen::Map<const Vector3d> Pi(poses[0]);
  const Quaterniond Qi = Eigen::Map<const Quaterniond>(poses[0] + 3).normalized();
  const Eigen::Map<const Vector3d> Pj(poses[1]);
  const Quaterniond Qj = Eigen::Map<const Quaterniond>(poses[1] + 3).normalized();
  const Vector3d pts_cam_j = transferPoint(pts_i, inv_dep, Pi, Qi, Pj, Qj, ex0, exb);
  const Matrix3d R_cj_ci = exb.q_b_c.conjugate().toRotationMatrix() * Qj.conjugate().toRotationMatrix() *
                           Qi.toRotationMatrix() * ex0.q_b_c.toRotationMatrix();
  return reduceJacobian(pts_cam_j, sqrt_info) * R_cj_ci * (-velocity3(i) / inv_dep) + sqrt_info * j.velocity;
}

}  // namespace

bool ProjectionTwoFrameTd::Evaluate(double const* const* parameters, double* residuals, double** jacobians) const {
  const double td = parameters[3][0];
  const Vector3d pts_i = atOffset(i_, td), pts_j = atOffset(j_, td);
  // The residual and the pose and depth Jacobians are the fixed-offset factor's at the moved
  // observations (no factor object built per evaluation: this runs in the solver loop).
  if (!evaluateTwoFrame(pts_i, pts_j, ex0_, exb_, weight_, parameters, residuals, jacobians)) return false;
  if (!jacobians || !jacobians[3]) return true;
  Eigen::Map<Vector2d> J(jacobians[3]);
  J = twoFrameTdJacobian(pts_i, parameters, parameters[2][0], ex0_, exb_, weight_.sqrtInfo(), i_, j_);
  return true;
}

Extrinsic compose(const Extrinsic& T_b_c0, const Extrinsic& T_c0_cb) {
  Extrinsic e;
  e.q_b_c = (T_b_c0.q_b_c * T_c0_cb.q_b_c).normalized();
  e.t_b_c = T_b_c0.q_b_c * T_c0_cb.t_b_c + T_b_c0.t_b_c;
  return e;
}

Extrinsic relative(const Extrinsic& T_b_c0, const Extrinsic& T_b_c1) {
  Extrinsic e;
  e.q_b_c = (T_b_c0.q_b_c.conjugate() * T_b_c1.q_b_c).normalized();
  e.t_b_c = T_b_c0.q_b_c.conjugate() * (T_b_c1.t_b_c - T_b_c0.t_b_c);
  return e;
}

namespace {

Extrinsic extrinsicBlock(const double* block) {
  Extrinsic e;
  e.t_b_c = Eigen::Map<const Vector3d>(block);
  e.q_b_c = Eigen::Map<const Quaterniond>(block + 3).normalized();
  return e;
}

/// A two-frame factor with the T_b_c0 block: blocks {pose_i, pose_j, T_b_c0, inv_depth}; the
/// residual and the pose and depth Jacobians are evaluateTwoFrame's at the current mount, the
/// mount's (tangent [δt, δθ], T_b_c0 ∘ (δt, Exp δθ) as a pose block) through both cameras.
bool evaluateTwoFrameEx(const Vector3d& pts_i, const Vector3d& pts_j, const Extrinsic& rel,
                        const ProjectionWeight& weight, double const* const* parameters, double* residuals,
                        double** jacobians) {
  const Extrinsic ex0 = extrinsicBlock(parameters[2]), exb = compose(ex0, rel);
  const double* fixed[3] = {parameters[0], parameters[1], parameters[3]};
  double* fixed_jac[3] = {nullptr, nullptr, nullptr};
  if (jacobians) fixed_jac[0] = jacobians[0], fixed_jac[1] = jacobians[1], fixed_jac[2] = jacobians[3];
  if (!evaluateTwoFrame(pts_i, pts_j, ex0, exb, weight, fixed, residuals, jacobians ? fixed_jac : nullptr))
    return false;
  if (!jacobians || !jacobians[2]) return true;
  const Quaterniond Qi = Eigen::Map<const Quaterniond>(parameters[0] + 3).normalized();
  const Eigen::Map<const Vector3d> Pi(parameters[0]), Pj(parameters[1]);
  const Quaterniond Qj = Eigen::Map<const Quaterniond>(parameters[1] + 3).normalized();
  const double inv_dep = parameters[3][0];
  const Vector3d pts_cam_i = pts_i / inv_dep;
  const Vector3d pts_imu_j = Qj.conjugate() * (Qi * (ex0.q_b_c * pts_cam_i + ex0.t_b_c) + Pi - Pj);
  const Vector3d u = ex0.q_b_c.conjugate() * (pts_imu_j - ex0.t_b_c);  // the point in the left camera j
  const Vector3d pts_cam_j = rel.q_b_c.conjugate() * (u - rel.t_b_c);
  const Matrix3d R0 = ex0.q_b_c.toRotationMatrix(), Rr_T = rel.q_b_c.conjugate().toRotationMatrix();
  const Matrix3d R_ji = Qj.conjugate().toRotationMatrix() * Qi.toRotationMatrix();
  Eigen::Matrix<double, 3, 6> jaco;
  jaco.leftCols<3>() = Rr_T * R0.transpose() * (R_ji - Matrix3d::Identity());
  jaco.rightCols<3>() = Rr_T * (-R0.transpose() * R_ji * R0 * hat(pts_cam_i) + hat(u));
  Eigen::Map<PoseJac> J(jacobians[2]);
  J.leftCols<6>() = reduceJacobian(pts_cam_j, weight.sqrtInfo()) * jaco;
  J.rightCols<1>().setZero();
  return true;
}

}  // namespace

ProjectionTwoFrameEx::ProjectionTwoFrameEx(const Vector2d& xy_i, const Vector2d& xy_j, const Extrinsic& T_c0_cb,
                                           const ProjectionWeight& weight)
    : pts_i_(homogeneous(xy_i)), pts_j_(homogeneous(xy_j)), rel_(T_c0_cb), weight_(weight) {}

bool ProjectionTwoFrameEx::Evaluate(double const* const* parameters, double* residuals, double** jacobians) const {
  return evaluateTwoFrameEx(pts_i_, pts_j_, rel_, weight_, parameters, residuals, jacobians);
}

ProjectionTwoFrameExTd::ProjectionTwoFrameExTd(const TimedObservation& obs_i, const TimedObservation& obs_j,
                                               const Extrinsic& T_c0_cb, const ProjectionWeight& weight)
    : i_(obs_i), j_(obs_j), rel_(T_c0_cb), weight_(weight) {}

bool ProjectionTwoFrameExTd::Evaluate(double const* const* parameters, double* residuals, double** jacobians) const {
  const double td = parameters[4][0];
  const Vector3d pts_i = atOffset(i_, td), pts_j = atOffset(j_, td);
  if (!evaluateTwoFrameEx(pts_i, pts_j, rel_, weight_, parameters, residuals, jacobians)) return false;
  if (!jacobians || !jacobians[4]) return true;
  const Extrinsic ex0 = extrinsicBlock(parameters[2]);
  Eigen::Map<Vector2d> J(jacobians[4]);
  J = twoFrameTdJacobian(pts_i, parameters, parameters[3][0], ex0, compose(ex0, rel_), weight_.sqrtInfo(), i_, j_);
  return true;
}

ProjectionOneFrameTwoCamTd::ProjectionOneFrameTwoCamTd(const TimedObservation& left, const TimedObservation& right,
                                                       const Extrinsic& T_b_c0, const Extrinsic& T_b_c1,
                                                       const ProjectionWeight& weight)
    : left_(left), right_(right), ex0_(T_b_c0), ex1_(T_b_c1), weight_(weight) {}

bool ProjectionOneFrameTwoCamTd::Evaluate(double const* const* parameters, double* residuals,
                                          double** jacobians) const {
  const double td = parameters[1][0];
  const Vector3d pts_i = atOffset(left_, td), pts_j = atOffset(right_, td);
  if (!evaluateOneFrameTwoCam(pts_i, pts_j, ex0_, ex1_, weight_, parameters, residuals, jacobians)) return false;
  if (!jacobians || !jacobians[1]) return true;
  const double inv_dep = parameters[0][0];
  const double sqrt_info = weight_.sqrtInfo();
  const Vector3d pts_imu = ex0_.q_b_c * (pts_i / inv_dep) + ex0_.t_b_c;
  const Vector3d pts_cam_j = ex1_.q_b_c.conjugate() * (pts_imu - ex1_.t_b_c);
  const Matrix3d R_c1_c0 = ex1_.q_b_c.conjugate().toRotationMatrix() * ex0_.q_b_c.toRotationMatrix();
  Eigen::Map<Vector2d> J(jacobians[1]);
  J = reduceJacobian(pts_cam_j, sqrt_info) * R_c1_c0 * (-velocity3(left_) / inv_dep) + sqrt_info * right_.velocity;
  return true;
}

AnchorRayObservation::AnchorRayObservation(const Vector2d& xy, const ProjectionWeight& weight)
    : xy_(xy), weight_(weight) {}

bool AnchorRayObservation::Evaluate(double const* const* parameters, double* residuals, double** jacobians) const {
  const double sqrt_info = weight_.sqrtInfo();
  Eigen::Map<Vector2d> r(residuals);
  r = sqrt_info * (Eigen::Map<const Vector2d>(parameters[0]) - xy_);
  if (jacobians && jacobians[0]) {
    Eigen::Map<Eigen::Matrix<double, 2, 3, Eigen::RowMajor>> J(jacobians[0]);
    J.setZero();
    J(0, 0) = J(1, 1) = sqrt_info;
  }
  return true;
}

ProjectionTwoFrameRay::ProjectionTwoFrameRay(const Vector2d& xy_j, const Extrinsic& T_b_c0, const Extrinsic& T_b_cb,
                                             const ProjectionWeight& weight)
    : pts_j_(homogeneous(xy_j)), ex0_(T_b_c0), exb_(T_b_cb), weight_(weight) {}

bool ProjectionTwoFrameRay::Evaluate(double const* const* parameters, double* residuals, double** jacobians) const {
  // The fixed-ray factor at the current ray: its inverse-depth Jacobian is the block's third
  // column, the x and y columns of its anchor-point Jacobian the ray's.
  const Vector3d pts_i(parameters[2][0], parameters[2][1], 1.0);
  const double* fixed_ray[3] = {parameters[0], parameters[1], parameters[2] + 2};
  const bool want_ray = jacobians && jacobians[2];
  Vector2d J_rho;
  Eigen::Matrix<double, 2, 3> J_pts_i;
  double* fixed_jac[3] = {jacobians ? jacobians[0] : nullptr, jacobians ? jacobians[1] : nullptr,
                          want_ray ? J_rho.data() : nullptr};
  if (!evaluateTwoFrame(pts_i, pts_j_, ex0_, exb_, weight_, fixed_ray, residuals, jacobians ? fixed_jac : nullptr,
                        want_ray ? &J_pts_i : nullptr))
    return false;
  if (!want_ray) return true;
  Eigen::Map<Eigen::Matrix<double, 2, 3, Eigen::RowMajor>> J(jacobians[2]);
  J.leftCols<2>() = J_pts_i.leftCols<2>();
  J.col(2) = J_rho;
  return true;
}

ProjectionOneFrameTwoCamRay::ProjectionOneFrameTwoCamRay(const Vector2d& xy_right, const Extrinsic& T_b_c0,
                                                         const Extrinsic& T_b_c1, const ProjectionWeight& weight)
    : pts_j_(homogeneous(xy_right)), ex0_(T_b_c0), ex1_(T_b_c1), weight_(weight) {}

bool ProjectionOneFrameTwoCamRay::Evaluate(double const* const* parameters, double* residuals,
                                           double** jacobians) const {
  const Vector3d pts_i(parameters[0][0], parameters[0][1], 1.0);
  const double* fixed_ray[1] = {parameters[0] + 2};
  const bool want_ray = jacobians && jacobians[0];
  Vector2d J_rho;
  Eigen::Matrix<double, 2, 3> J_pts_i;
  double* fixed_jac[1] = {want_ray ? J_rho.data() : nullptr};
  if (!evaluateOneFrameTwoCam(pts_i, pts_j_, ex0_, ex1_, weight_, fixed_ray, residuals, want_ray ? fixed_jac : nullptr,
                              want_ray ? &J_pts_i : nullptr))
    return false;
  if (!want_ray) return true;
  Eigen::Map<Eigen::Matrix<double, 2, 3, Eigen::RowMajor>> J(jacobians[0]);
  J.leftCols<2>() = J_pts_i.leftCols<2>();
  J.col(2) = J_rho;
  return true;
}

}  // namespace idyvins::backend
