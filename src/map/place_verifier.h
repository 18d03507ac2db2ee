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
  /// The query's body pose in the candidate's world frame (valid when accepted).
  Eigen::Vector3d p_w_b = Eigen::Vector3d::Zero();
  Eigen::Quaterniond q_w_b = Eigen::Quaterniond::Identity();
};

/// Matches the query to `candidate`'s landmarks and solves PnP RANSAC; T_b_c is the left camera in the body.
PlaceVerification verifyPlace(const Keyframe& candidate, const PlaceQuery& query, const Eigen::Isometry3d& T_b_c,
                              const VerifyOptions& options = {});

}  // namespace idyvins::map
