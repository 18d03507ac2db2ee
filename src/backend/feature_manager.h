#pragma once
// Landmarks of the sliding window: observations per frame (left, right), inverse
// depth in the anchor (first observing) frame's left camera, labels, triangulation.

#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <map>
#include <optional>
#include <set>
#include <vector>

#include "backend/projection_factors.h"
#include "frontend/feature_frame.h"

namespace idyvins::backend {

/// One observation of a landmark in one window frame.
struct Observation {
  Eigen::Vector2d xy = Eigen::Vector2d::Zero();  ///< left normalized
  Eigen::Vector2d uv = Eigen::Vector2d::Zero();  ///< left pixel
  bool has_right = false;
  Eigen::Vector2d xy_right = Eigen::Vector2d::Zero();        ///< right normalized
  Eigen::Vector2d velocity = Eigen::Vector2d::Zero();        ///< left, normalized plane, 1/s
  Eigen::Vector2d velocity_right = Eigen::Vector2d::Zero();  ///< right, normalized plane, 1/s
  double td_s = 0;  ///< time offset the frame was stamped with (FeatureFrame::td_s)
};

/// A landmark: observations in consecutive window frames start_frame, start_frame + 1, ...
struct Landmark {
  std::uint64_t id = 0;
  int start_frame = 0;
  std::vector<Observation> obs;
  double inv_depth = -1.0;  ///< ≤ 0: not triangulated
  FeatureLabel label = FeatureLabel::kStatic;
  int candidate_obs = 0;  ///< observations since it was (last) marked candidate (DESIGN §4.4, §4.6)
  /// With estimate_anchor_ray: the anchor ray's point on the normalized plane, an estimate
  /// (ray_estimated) once a solve or a re-anchoring has set it; else the anchor observation.
  bool ray_estimated = false;
  Eigen::Vector2d ray_xy = Eigen::Vector2d::Zero();
  /// The solver's block (ray x, y, inverse depth) while a solve with estimated rays runs.
  std::array<double, 3> ray_block{};
  Eigen::Vector2d anchorRay() const { return ray_estimated ? ray_xy : obs.front().xy; }
  /// The point in the anchor (left) camera.
  Eigen::Vector3d anchorPoint() const { return Eigen::Vector3d(anchorRay().x(), anchorRay().y(), 1.0) / inv_depth; }
  int endFrame() const { return start_frame + static_cast<int>(obs.size()) - 1; }
  bool usable() const { return inv_depth > 0 && (obs.size() >= 2 || obs.front().has_right); }
  /// Whether, anchored in the leaving keyframe, it lives on re-anchored in the next frame
  /// (FeatureManager::removeOldest erases the others).
  bool livesOnReanchored() const { return obs.size() >= 2; }
  /// The share of its information a landmark anchored in the leaving keyframe brings into
  /// the marginalization prior under EstimatorOptions::prior_landmark_share: 1/m when it lives
  /// on re-anchored (m window observations), since the window goes on using m − 1 of them;
  /// all of it when it leaves with the keyframe.
  double priorShare() const { return livesOnReanchored() ? 1.0 / static_cast<double>(obs.size()) : 1.0; }
};

/// Stereo rig extrinsics and the intrinsic scale used to weight residuals.
struct Rig {
  Extrinsic T_b_c0, T_b_c1;
  bool stereo = true;
  double focal_px = 460.0;
  double fx = 460.0, fy = 460.0;  ///< left camera, for pixel-unit errors
};

/// Owns the landmarks of the window.
class FeatureManager {
 public:
  /// Adds the features of window frame `frame`; returns true if it should be a keyframe
  /// (VINS-Fusion's rule: few tracked / many new features, or mean parallax to the
  /// previous frames ≥ keyframe_parallax_px).
  /// Features whose id is in `excluded` (confirmed-dynamic tracks) are skipped.
  bool addFrame(int frame, const frontend::FeatureFrame& features, double keyframe_parallax_px, double focal_px,
                const std::set<std::uint64_t>& excluded = {});

  /// Triangulates landmarks without depth: stereo in the anchor frame first, else two
  /// views of the window. T_w_b holds the window's body poses.
  void triangulate(const std::vector<Eigen::Isometry3d>& T_w_b, const Rig& rig);

  /// After the oldest frame left the window: re-anchors its landmarks in the next frame
  /// and shifts the rest. T_w_b: the window's body poses before the slide (T_w_b[0] left).
  /// As VINS-Fusion (retriangulate false), a landmark moves onto its next observation's ray
  /// at its estimated depth; with retriangulate it keeps the point that best fits all its
  /// window observations (triangulateViews), so the new anchor ray is an estimate, not the
  /// one noisy measurement (docs/results.md: re-anchoring and the scale).
  /// With ray_estimates the point stays where it is and the new anchor ray is its direction,
  /// an estimate the next solve refines against the new anchor's observation (a residual).
  void removeOldest(const std::vector<Eigen::Isometry3d>& T_w_b, const Rig& rig, bool retriangulate = false,
                    bool ray_estimates = false);
  /// After the second newest frame (index `frame`) was dropped: removes its observations.
  void removeFrame(int frame);
  /// Drops landmarks by id (outliers, confirmed dynamic).
  void remove(const std::vector<std::uint64_t>& ids);
  /// Drops landmarks whose depth became invalid after a solve.
  void removeFailures();
  void clear() { landmarks_.clear(); }

  std::map<std::uint64_t, Landmark>& landmarks() { return landmarks_; }
  const std::map<std::uint64_t, Landmark>& landmarks() const { return landmarks_; }
  /// Number of usable landmarks observed in `frame`.
  int trackedIn(int frame) const;

 private:
  std::map<std::uint64_t, Landmark> landmarks_;
};

/// Linear (DLT) triangulation of a point seen at normalized xy0 by camera T_w_c0 and xy1
/// by T_w_c1; returns the point in the world.
Eigen::Vector3d triangulateTwoViews(const Eigen::Isometry3d& T_w_c0, const Eigen::Vector2d& xy0,
                                    const Eigen::Isometry3d& T_w_c1, const Eigen::Vector2d& xy1);

/// The point seen at normalized xy[k] by cameras T_w_c[k] (k ≥ 2): Gauss-Newton on the
/// normalized-plane errors from `start` (default: the linear solution), errors above
/// `huber` (normalized units, 0: none) down-weighted as by a Huber loss. Nullopt when the
/// views do not fix it or it ends up behind one of them.
std::optional<Eigen::Vector3d> triangulateViews(const std::vector<Eigen::Isometry3d>& T_w_c,
                                                const std::vector<Eigen::Vector2d>& xy,
                                                const std::optional<Eigen::Vector3d>& start = std::nullopt,
                                                double huber = 0.0);

/// T_w_c of a body pose and an extrinsic.
Eigen::Isometry3d cameraPose(const Eigen::Isometry3d& T_w_b, const Extrinsic& T_b_c);

}  // namespace idyvins::backend
