#pragma once
// Reprojection factors with inverse depth (VINS-Fusion's three): residuals on the
// normalized image plane, weighted by focal/σ_px (σ_px: EstimatorOptions::sigma_px) and by
// a per-observation information scale that may change at run time.

#include <ceres/sized_cost_function.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace idyvins::backend {

/// Camera-to-body extrinsic T_b_c.
struct Extrinsic {
  Eigen::Quaterniond q_b_c = Eigen::Quaterniond::Identity();
  Eigen::Vector3d t_b_c = Eigen::Vector3d::Zero();
};

/// Weighting of a projection residual: sqrt_info = focal/σ_px · sqrt(*info_scale).
/// info_scale points at a value the estimator owns and may change between solver
/// iterations (dynamic-candidate weights 1/m_j, DESIGN §4.5); null means 1.
struct ProjectionWeight {
  double focal_px;  ///< the camera's focal length, px
  double sigma_px;  ///< pixel noise, px (EstimatorOptions::sigma_px)
  const double* info_scale = nullptr;
  double sqrtInfo() const;
};

/// Anchor (left) camera in frame i to camera b in frame j (i != j): the left
/// camera (T_b_cb = T_b_c0, VINS' "two frames one camera") or the right camera
/// (T_b_cb = T_b_c1, "two frames two cameras"). Blocks: pose_i (7), pose_j (7), inv_depth (1).
class ProjectionTwoFrame final : public ceres::SizedCostFunction<2, 7, 7, 1> {
 public:
  ProjectionTwoFrame(const Eigen::Vector2d& xy_i, const Eigen::Vector2d& xy_j, const Extrinsic& T_b_c0,
                     const Extrinsic& T_b_cb, const ProjectionWeight& weight);
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;

 private:
  Eigen::Vector3d pts_i_, pts_j_;
  Extrinsic ex0_, exb_;
  ProjectionWeight weight_;
};

/// Left camera to right camera in the same frame. Block: inv_depth (1).
class ProjectionOneFrameTwoCam final : public ceres::SizedCostFunction<2, 1> {
 public:
  ProjectionOneFrameTwoCam(const Eigen::Vector2d& xy_left, const Eigen::Vector2d& xy_right, const Extrinsic& T_b_c0,
                           const Extrinsic& T_b_c1, const ProjectionWeight& weight);
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;

 private:
  Eigen::Vector3d pts_i_, pts_j_;
  Extrinsic ex0_, ex1_;
  ProjectionWeight weight_;
};

/// What a time-offset factor needs of one observation: its velocity on the normalized
/// plane (1/s) and the offset td_obs (s) its frame was stamped with. With the current
/// offset td the observation is moved to xy − (td − td_obs)·velocity (VINS-Fusion's model:
/// the feature moves at constant image velocity over the small offset change).
struct TimedObservation {
  Eigen::Vector2d xy = Eigen::Vector2d::Zero();
  Eigen::Vector2d velocity = Eigen::Vector2d::Zero();
  double td_obs = 0;
};

/// ProjectionTwoFrame with the camera–IMU time offset as a fifth block. Blocks: pose_i (7),
/// pose_j (7), inv_depth (1), td (1, seconds).
class ProjectionTwoFrameTd final : public ceres::SizedCostFunction<2, 7, 7, 1, 1> {
 public:
  ProjectionTwoFrameTd(const TimedObservation& obs_i, const TimedObservation& obs_j, const Extrinsic& T_b_c0,
                       const Extrinsic& T_b_cb, const ProjectionWeight& weight);
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;

 private:
  TimedObservation i_, j_;
  Extrinsic ex0_, exb_;
  ProjectionWeight weight_;
};

/// ProjectionOneFrameTwoCam with the time offset. Blocks: inv_depth (1), td (1, seconds).
class ProjectionOneFrameTwoCamTd final : public ceres::SizedCostFunction<2, 1, 1> {
 public:
  ProjectionOneFrameTwoCamTd(const TimedObservation& left, const TimedObservation& right, const Extrinsic& T_b_c0,
                             const Extrinsic& T_b_c1, const ProjectionWeight& weight);
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;

 private:
  TimedObservation left_, right_;
  Extrinsic ex0_, ex1_;
  ProjectionWeight weight_;
};

/// A projection factor with the left camera's mount T_b_c0 as a block (estimate_extrinsic): the
/// anchor left camera in frame i to camera b in frame j, camera b's pose in the left camera
/// T_c0_cb fixed (identity for the left camera; the stereo pair is rigid). Blocks: pose_i (7),
/// pose_j (7), T_b_c0 (7, a pose block: t, q xyzw), inv_depth (1).
class ProjectionTwoFrameEx final : public ceres::SizedCostFunction<2, 7, 7, 7, 1> {
 public:
  ProjectionTwoFrameEx(const Eigen::Vector2d& xy_i, const Eigen::Vector2d& xy_j, const Extrinsic& T_c0_cb,
                       const ProjectionWeight& weight);
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;

 private:
  Eigen::Vector3d pts_i_, pts_j_;
  Extrinsic rel_;
  ProjectionWeight weight_;
};

/// ProjectionTwoFrameEx with the time offset. Blocks: pose_i (7), pose_j (7), T_b_c0 (7),
/// inv_depth (1), td (1, seconds).
class ProjectionTwoFrameExTd final : public ceres::SizedCostFunction<2, 7, 7, 7, 1, 1> {
 public:
  ProjectionTwoFrameExTd(const TimedObservation& obs_i, const TimedObservation& obs_j, const Extrinsic& T_c0_cb,
                         const ProjectionWeight& weight);
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;

 private:
  TimedObservation i_, j_;
  Extrinsic rel_;
  ProjectionWeight weight_;
};

/// T_b_c0 ∘ T_c0_cb: camera b's mount from the left camera's and the pair's relative pose.
Extrinsic compose(const Extrinsic& T_b_c0, const Extrinsic& T_c0_cb);
/// T_c0_c1 of a stereo rig.
Extrinsic relative(const Extrinsic& T_b_c0, const Extrinsic& T_b_c1);

/// Landmarks whose anchor ray is estimated (EstimatorOptions::estimate_anchor_ray): one block
/// of 3, the ray's point (x, y) on the anchor left camera's normalized plane and the inverse
/// depth along it, so no observation is taken as exact. The anchor observation's own
/// residual: sqrt_info · (ray − xy). Block: landmark (3).
class AnchorRayObservation final : public ceres::SizedCostFunction<2, 3> {
 public:
  AnchorRayObservation(const Eigen::Vector2d& xy, const ProjectionWeight& weight);
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;

 private:
  Eigen::Vector2d xy_;
  ProjectionWeight weight_;
};

/// ProjectionTwoFrame of a landmark with an estimated anchor ray. Blocks: pose_i (7),
/// pose_j (7), landmark (3: ray x, y, inverse depth).
class ProjectionTwoFrameRay final : public ceres::SizedCostFunction<2, 7, 7, 3> {
 public:
  ProjectionTwoFrameRay(const Eigen::Vector2d& xy_j, const Extrinsic& T_b_c0, const Extrinsic& T_b_cb,
                        const ProjectionWeight& weight);
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;

 private:
  Eigen::Vector3d pts_j_;
  Extrinsic ex0_, exb_;
  ProjectionWeight weight_;
};

/// ProjectionOneFrameTwoCam of a landmark with an estimated anchor ray. Block: landmark (3).
class ProjectionOneFrameTwoCamRay final : public ceres::SizedCostFunction<2, 3> {
 public:
  ProjectionOneFrameTwoCamRay(const Eigen::Vector2d& xy_right, const Extrinsic& T_b_c0, const Extrinsic& T_b_c1,
                              const ProjectionWeight& weight);
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;

 private:
  Eigen::Vector3d pts_j_;
  Extrinsic ex0_, ex1_;
  ProjectionWeight weight_;
};

/// Normalized-plane reprojection of the anchor observation (xy_i, inverse depth)
/// from pose_i/camera a into pose_j/camera b; the pure math shared by the factors
/// and by outlier checks. Returns the 3D point in camera b.
Eigen::Vector3d transferPoint(const Eigen::Vector3d& pts_i, double inv_depth, const Eigen::Vector3d& p_i,
                              const Eigen::Quaterniond& q_i, const Eigen::Vector3d& p_j, const Eigen::Quaterniond& q_j,
                              const Extrinsic& cam_a, const Extrinsic& cam_b);

}  // namespace idyvins::backend
