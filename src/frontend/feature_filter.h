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
  bool prev_has_right = false;                              ///< previous observation had a right match
  Eigen::Vector2d prev_xy_right = Eigen::Vector2d::Zero();  ///< its right normalized coordinates
  // The current observation's right match (feature->has_right, xy_right) is set before the filter.
  bool remove = false;  ///< set by the filter: drop the feature (it stops being tracked)
};

/// Frame-level inputs a filter may use.
struct FilterContext {
  const camera::CameraModel* camera = nullptr;  ///< left camera
  const MotionPrior* prior = nullptr;           ///< may be invalid
  const cv::Mat* mask = nullptr;                ///< ground-truth object ids of the left image, or null
  TimeNs t_prev_ns = 0, t_cur_ns = 0;
};

/// A new corner lost in its second frame, as the tracker last saw it (the previous frame):
/// left pixel and normalized coordinates and its right match.
struct LostCorner {
  Eigen::Vector2d uv = Eigen::Vector2d::Zero(), xy = Eigen::Vector2d::Zero(), xy_right = Eigen::Vector2d::Zero();
};

/// Where a filter asks the tracker to look for a lost corner in the current frame.
struct LostCornerSearch {
  std::size_t corner = 0;                             ///< index into the lost corners
  Eigen::Vector2d uv_pred = Eigen::Vector2d::Zero();  ///< left pixel to look at
  Eigen::Vector3d p_pred = Eigen::Vector3d::Zero();   ///< the point expected there, current left camera (m)
  double tol_px = 0;                                  ///< how far from uv_pred a find counts
};

/// What the tracker measured at a search.
struct LostCornerFinding {
  bool found = false;     ///< the corner's first patch aligned within tol_px (KLT from uv_pred, then the patch)
  double best_zncc = -1;  ///< the best ZNCC of the first patch within tol_px (-1: none)
};

/// The tracker's measurements for the lost-corner test (its images, pyramids and first
/// patches); the judgement is the filter's (dynamic::IdyFilter).
class LostCornerProbe {
 public:
  virtual ~LostCornerProbe() = default;
  /// Whether a first patch centred at `uv` lies in the image (a search there is possible).
  virtual bool searchable(const Eigen::Vector2d& uv) const = 0;
  /// Looks for each searched corner near its predicted pixel.
  virtual std::vector<LostCornerFinding> find(const std::vector<LostCornerSearch>& searches) = 0;
  /// The stereo depth (left camera, m) of the surface now at each search's uv_pred (the
  /// right image searched from where p_pred projects); 0 when unmatched or mono.
  virtual std::vector<double> depthAt(const std::vector<LostCornerSearch>& searches) = 0;
};

/// The judgement of the lost corners of a frame.
struct LostCornerJudgement {
  std::size_t tested = 0;           ///< corners the static hypothesis could be tested on
  std::vector<std::size_t> moving;  ///< indices of the corners judged moving, ascending
};

/// Interface of a rejection mode.
class FeatureFilter {
 public:
  virtual ~FeatureFilter() = default;
  virtual void apply(const FilterContext& context, std::vector<FilterItem>& items) = 0;
  /// Judges the new corners lost in this frame (TrackerParams::lost_track_test);
  /// by default none is judged.
  virtual LostCornerJudgement judgeLost(const FilterContext& /*context*/, const std::vector<LostCorner>& /*lost*/,
                                        LostCornerProbe& /*probe*/) {
    return {};
  }
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
