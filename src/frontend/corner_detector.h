#pragma once
// Shi-Tomasi corners (minimum eigenvalue of the 3x3 structure tensor) where a
// mask allows them, with the selection rule of OpenCV's goodFeaturesToTrack:
// quality threshold relative to the strongest response inside the mask, 3x3
// non-maximum suppression, strongest first (ties: later raster position first),
// minimum distance between corners. The responses are computed only on the
// image tiles the mask opens (plus a one-pixel ring for the suppression): a
// tracker's mask is mostly closed around its existing features (about 70 % of a
// 752x480 image at 150 features, 30 px apart), so most of the full-image work
// of goodFeaturesToTrack is saved. Pixel convention: (u, v) = (column, row).

#include <opencv2/core/mat.hpp>
#include <vector>

#include "camera/camera_model.h"

namespace idyvins::frontend {

/// Options of detectCorners.
struct CornerOptions {
  int max_corners = 150;        ///< at most this many (strongest first); <= 0: none
  double quality_level = 0.01;  ///< response threshold, relative to the strongest response in the mask
  double min_distance = 30.0;   ///< px between any two returned corners
  int tile = 16;                ///< px; responses are computed per tile the mask opens
};

/// Corners of a CV_8UC1 image at integer pixels, strongest first. `mask` (CV_8UC1,
/// same size, non-zero = allowed) may be empty (whole image).
std::vector<cv::Point2f> detectCorners(const cv::Mat& image, const cv::Mat& mask, const CornerOptions& options);

/// Where a lens images rays in front of the camera within `max_angle_deg` of its axis: CV_8UC1 of
/// width x height, 255 where a pixel lifts to the normalized plane (CameraModel::liftToNormalized)
/// with a ray at most max_angle_deg off the axis (90 and above: any in front) and lies more than
/// `margin_px` from every pixel that does not (a wide fisheye's rim, a lens circle's dark
/// outside), 0 elsewhere. Empty for a pinhole and when every pixel passes: no mask needed.
cv::Mat lensMask(const camera::CameraModel& camera, int width, int height, int margin_px, double max_angle_deg);

}  // namespace idyvins::frontend
