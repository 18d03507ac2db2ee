#pragma once
// Rejection hooks of the front end: a filter sees every feature of the current
// frame (with its previous observation when it was tracked) and removes or labels
// them before they are handed on. The tracker knows nothing of a filter's method.

#include <memory>
#include <opencv2/core/mat.hpp>
#include <vector>

#include "camera/camera_model.h"
#include "frontend/feature_frame.h"

namespace idyvins::frontend {

/// A feature as a filter sees it.
struct FilterItem {
  Feature* feature = nullptr;  ///< current observation (label and score may be set)
  bool tracked = false;        ///< has a previous observation
  Eigen::Vector2d prev_uv = Eigen::Vector2d::Zero(), prev_xy = Eigen::Vector2d::Zero();
  bool prev_has_right = false;                           ///< previous observation had a right match
  Eigen::Vector2d prev_xy_right = Eigen::Vector2d::Zero();  ///< its right normalized coordinates
  // The current observation's right match (feature->has_right, xy_right) is set before the filter.
  bool remove = false;         ///< set by the filter: drop the feature (it stops being tracked)
};

/// Frame-level inputs a filter may use.
struct FilterContext {
  const camera::CameraModel* camera = nullptr;  ///< left camera
  const MotionPrior* prior = nullptr;           ///< may be invalid
  const cv::Mat* mask = nullptr;                ///< ground-truth object ids of the left image, or null
  TimeNs t_prev_ns = 0, t_cur_ns = 0;
};

/// Interface of a rejection mode.
class FeatureFilter {
 public:
  virtual ~FeatureFilter() = default;
  virtual void apply(const FilterContext& context, std::vector<FilterItem>& items) = 0;
};

/// `ransac`: fundamental-matrix RANSAC between consecutive left frames on
/// undistorted pixels (as VINS-Fusion's rejectWithF), threshold in pixels.
class RansacFilter final : public FeatureFilter {
 public:
  explicit RansacFilter(double threshold_px) : threshold_px_(threshold_px) {}
  void apply(const FilterContext& context, std::vector<FilterItem>& items) override;

 private:
  double threshold_px_;
};

/// `seg`: drops every feature whose (rounded) pixel lies on a moving object of the
/// ground-truth mask (simulator masks, VIODE segmentation turned into ids).
class SegFilter final : public FeatureFilter {
 public:
  void apply(const FilterContext& context, std::vector<FilterItem>& items) override;
};

}  // namespace idyvins::frontend
