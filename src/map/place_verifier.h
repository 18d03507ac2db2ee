#pragma once
// From images to loop edges: ORB descriptors at corners, and the geometric check of a
// recognised place: the query's corners matched to the candidate keyframe's static
// landmarks by descriptor, then 3D-2D PnP RANSAC (OpenCV) for the query's pose in the
// map. Few inliers: no loop.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>
#include <vector>

#include "map/keyframe_database.h"
#include "map/loop_options.h"

namespace idyvins::map {

/// ORB (oriented rBRIEF) descriptors at `corners` (left-image pixels). Corners too close to
/// the border for a descriptor are removed from `corners`; the rest keep their order, and
/// `kept` (when given) receives the index each had in the input.
std::vector<Descriptor> describeCorners(const cv::Mat& gray, std::vector<cv::Point2f>& corners,
                                        std::vector<int>* kept = nullptr);
/// Up to `count` FAST corners with the best Harris scores (ORB's detector, one scale), for recognition.
std::vector<cv::Point2f> recognitionCorners(const cv::Mat& gray, int count);

/// The current keyframe as a query: its corners (normalized undistorted left camera) and descriptors.
struct PlaceQuery {
  std::vector<Eigen::Vector2d> xy;
  std::vector<Descriptor> descriptors;
};

struct PlaceVerification {
  bool accepted = false;
  int matches = 0, inliers = 0;
  /// Standard deviation (m) of the query camera's position along its worst axis, propagated from
  /// pixel noise and the candidate landmarks' stereo depth uncertainty (positionSigma).
  double sigma_position_m = 0;
  /// The query's body pose in the candidate's world frame (valid when accepted).
  Eigen::Vector3d p_w_b = Eigen::Vector3d::Zero();
  Eigen::Quaterniond q_w_b = Eigen::Quaterniond::Identity();
};

/// The worst-axis standard deviation (m) of a camera position solved by PnP from these landmarks
/// (world) and the camera pose T_c_w: first-order propagation of `sigma_px` pixel noise and of
/// each landmark's uncertainty as triangulated from `seen_from` (camera centre, world) with a
/// stereo baseline `baseline_m` (depth sigma d² σ / (f b), lateral d σ / f). Infinite if singular.
double positionSigma(const std::vector<Eigen::Vector3d>& landmarks_w, const Eigen::Isometry3d& T_c_w,
                     const Eigen::Vector3d& seen_from, double focal_px, double baseline_m, double sigma_px);

/// Matches the query to `candidate`'s landmarks, solves PnP RANSAC and refines the pose on the
/// inliers (Levenberg-Marquardt); refused when the position is too uncertain
/// (VerifyOptions::max_sigma_position_m). T_b_c is the left camera in the body.
PlaceVerification verifyPlace(const Keyframe& candidate, const PlaceQuery& query, const Eigen::Isometry3d& T_b_c,
                              const VerifyOptions& options = {});

}  // namespace idyvins::map
