#pragma once
// Projection models: pinhole + radial-tangential, equidistant (Kannala-Brandt)
// fisheye and the unified omnidirectional model (Mei). Points are in the camera frame (x right, y down, z forward);
// pixels are distorted image coordinates; "normalized" means undistorted (x/z, y/z).

#include <Eigen/Core>
#include <memory>

#include "camera/camera_params.h"

namespace idyvins::camera {

/// A calibrated camera: project, lift, and the projection Jacobian.
class CameraModel {
 public:
  explicit CameraModel(const CameraParams& params) : params_(params) {}
  virtual ~CameraModel() = default;

  /// Projects p_c to pixels; false when the point cannot be imaged (behind, or
  /// past the model's field of view). d_uv_d_p (2x3) is filled when non-null.
  virtual bool project(const Eigen::Vector3d& p_c, Eigen::Vector2d& uv,
                       Eigen::Matrix<double, 2, 3>* d_uv_d_p = nullptr) const = 0;

  /// Lifts a pixel to undistorted normalized coordinates (x/z, y/z), iterating
  /// to 1e-10 or better; false if it does not converge or the ray is not in front.
  virtual bool liftToNormalized(const Eigen::Vector2d& uv, Eigen::Vector2d& xy) const = 0;

  /// Lifts a pixel to its unit ray, also past 90° off the axis where the model images such rays
  /// (a lens wider than 180°); false where liftToNormalized fails and the model has no such ray.
  virtual bool liftToRay(const Eigen::Vector2d& uv, Eigen::Vector3d& ray) const {
    Eigen::Vector2d xy;
    if (!liftToNormalized(uv, xy)) return false;
    ray = Eigen::Vector3d(xy.x(), xy.y(), 1.0).normalized();
    return true;
  }

  /// Distorted pixel of a normalized point (x/z, y/z) in front of the camera.
  bool projectNormalized(const Eigen::Vector2d& xy, Eigen::Vector2d& uv) const {
    return project(Eigen::Vector3d(xy.x(), xy.y(), 1.0), uv);
  }

  const CameraParams& params() const { return params_; }
  /// Mean pixels per normalized unit at the principal point (for pixel-unit thresholds on
  /// normalized errors): the mean focal length of a pinhole (pixelsPerNormalized).
  double focal() const {
    const auto f = pixelsPerNormalized(params_);
    return 0.5 * (f[0] + f[1]);
  }

 protected:
  CameraParams params_;
};

/// Pinhole with radial-tangential distortion (camodocal PINHOLE, OpenCV plumb_bob k1 k2 p1 p2).
class PinholeRadtan final : public CameraModel {
 public:
  using CameraModel::CameraModel;
  bool project(const Eigen::Vector3d& p_c, Eigen::Vector2d& uv,
               Eigen::Matrix<double, 2, 3>* d_uv_d_p = nullptr) const override;
  bool liftToNormalized(const Eigen::Vector2d& uv, Eigen::Vector2d& xy) const override;
  /// Distorts a normalized point; d_xyd_d_xy (2x2) when non-null.
  Eigen::Vector2d distort(const Eigen::Vector2d& xy, Eigen::Matrix2d* d_xyd_d_xy = nullptr) const;
};

/// Equidistant fisheye (camodocal KANNALA_BRANDT): r(θ) = θ + k2 θ³ + k3 θ⁵ + k4 θ⁷ + k5 θ⁹.
class KannalaBrandt final : public CameraModel {
 public:
  using CameraModel::CameraModel;
  bool project(const Eigen::Vector3d& p_c, Eigen::Vector2d& uv,
               Eigen::Matrix<double, 2, 3>* d_uv_d_p = nullptr) const override;
  bool liftToNormalized(const Eigen::Vector2d& uv, Eigen::Vector2d& xy) const override;
  /// θ up to project's limit (90° + 0.4 rad), so a 185° lens's rim too.
  bool liftToRay(const Eigen::Vector2d& uv, Eigen::Vector3d& ray) const override;
  /// Distorted radius r(θ) and its derivative.
  double radius(double theta, double* d_r_d_theta = nullptr) const;

 private:
  /// θ with radius(θ) = r (Newton from θ = r); false when it does not converge.
  bool angleOf(double r, double& theta) const;
};

/// Unified omnidirectional model (Mei 2007; camodocal MEI): the point goes onto the unit sphere,
/// then through a pinhole ξ behind the sphere's centre, m_u = (x, y) / (z + ξ ‖p‖); m_u is
/// distorted by radtan (k1 k2 p1 p2) and scaled by γ1 γ2 about u0 v0. Rays with
/// z / ‖p‖ ≤ −1/ξ (beyond the model's fold, ξ > 1) are not imaged.
class Mei final : public CameraModel {
 public:
  using CameraModel::CameraModel;
  bool project(const Eigen::Vector3d& p_c, Eigen::Vector2d& uv,
               Eigen::Matrix<double, 2, 3>* d_uv_d_p = nullptr) const override;
  bool liftToNormalized(const Eigen::Vector2d& uv, Eigen::Vector2d& xy) const override;
  /// The ray of a pixel on the unit sphere (also behind the camera, z ≤ 0); false when the
  /// undistortion does not converge or the pixel is outside the model's image.
  bool liftToSphere(const Eigen::Vector2d& uv, Eigen::Vector3d& ray) const;
  bool liftToRay(const Eigen::Vector2d& uv, Eigen::Vector3d& ray) const override { return liftToSphere(uv, ray); }
};

/// Builds the model the parameters name.
std::unique_ptr<CameraModel> makeCamera(const CameraParams& params);

}  // namespace idyvins::camera
