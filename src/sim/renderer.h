#pragma once
// Ray-cast rasterizer: for each quad, the pixels of its (distortion-aware) bounding
// box are intersected with its plane; the nearest hit wins (z-buffer); hits are
// shaded from mipmapped textures by their footprint. Deterministic.

#include <Eigen/Geometry>
#include <cmath>
#include <cstdint>
#include <opencv2/core/mat.hpp>
#include <vector>

#include "camera/camera_model.h"
#include "sim/textures.h"
#include "sim/world.h"

namespace idyvins::sim {

/// What one render returns.
struct RenderOutput {
  cv::Mat image;  ///< CV_8UC1 intensity (renderRadiance: CV_32F)
  cv::Mat mask;   ///< CV_8UC1 object id (0 static, k moving object k)
  cv::Mat depth;  ///< CV_32F z in the camera frame (0 = sky; below 0 past 90° off the axis)
};

/// Renders one camera. Holds a per-pixel ray table; const methods are thread-safe.
class Renderer {
 public:
  /// Rays more than `max_ray_angle_rad` off the axis see nothing (dark): a circular fisheye's
  /// lens circle. Rays past 90° are rendered where the lens model images them.
  Renderer(const camera::CameraParams& params, const TextureBank& textures, double max_ray_angle_rad = M_PI);
  /// Renders quads seen from T_w_c (camera pose in the world). `noise_sigma` adds
  /// Gaussian pixel noise drawn from `noise_seed`.
  RenderOutput render(const std::vector<Quad>& quads, const Eigen::Isometry3d& T_w_c, bool sky, double noise_sigma,
                      std::uint64_t noise_seed) const;
  /// The same scene as scene radiance before the sensor: `image` is CV_32F in gray levels
  /// (unclipped, no noise); mask and depth as render().
  RenderOutput renderRadiance(const std::vector<Quad>& quads, const Eigen::Isometry3d& T_w_c, bool sky) const;
  const camera::CameraParams& params() const { return params_; }

 private:
  /// The nearest quad at each pixel: its index (-1: none), depth, surface coordinates and
  /// the pixel's footprint on it.
  struct Hits {
    std::vector<float> zbuf;
    std::vector<int> quad;
    std::vector<float> s, t, footprint;
  };
  /// Z-buffer pass: every quad rasterized through the per-pixel rays.
  Hits rasterize(const std::vector<Quad>& quads, const Eigen::Isometry3d& T_w_c) const;
  /// The pixel box [u0, u1] x [v0, v1] (clipped to the image) that holds the image of a
  /// polygon in front of the camera; `margin` widens a pinhole's normalized box.
  void pixelBox(const std::vector<Eigen::Vector3d>& poly, double margin, int& u0, int& u1, int& v0, int& v1) const;
  /// Texture, albedo and contrast at each hit (sky or dark background elsewhere).
  RenderOutput shade(const std::vector<Quad>& quads, const Hits& hits, bool sky) const;
  camera::CameraParams params_;
  std::unique_ptr<camera::CameraModel> model_;
  const TextureBank& textures_;
  /// Per pixel: (x/z, y/z, 1), whose ray parameter at a hit is its depth; the unit ray, whose
  /// parameter is the distance, for every pixel of a lens that sees past 90°; NaN outside the lens.
  std::vector<Eigen::Vector3f> rays_;
  bool past_90_deg_ = false;      ///< some rays look behind the camera's plane (no near clipping then)
  double max_distortion_px_ = 0;  ///< max |distorted − pinhole| pixel shift in the image
};

}  // namespace idyvins::sim
