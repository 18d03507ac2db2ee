#include "map/place_verifier.h"

#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>
#include <opencv2/features2d.hpp>

#include <limits>

namespace idyvins::map {

std::vector<Descriptor> describeCorners(const cv::Mat& gray, std::vector<cv::Point2f>& corners,
                                        std::vector<int>* kept_index) {
  std::vector<cv::KeyPoint> keypoints;
  for (std::size_t i = 0; i < corners.size(); ++i)
    keypoints.emplace_back(corners[i], 31.f, -1.f, 0.f, 0, static_cast<int>(i));
  cv::Mat desc;
  cv::ORB::create()->compute(gray, keypoints, desc);  // drops keypoints too near the border
  std::vector<Descriptor> out(keypoints.size());
  std::vector<cv::Point2f> kept(keypoints.size());
  for (std::size_t i = 0; i < keypoints.size(); ++i) {
    std::copy(desc.ptr<std::uint8_t>(static_cast<int>(i)), desc.ptr<std::uint8_t>(static_cast<int>(i)) + 32,
              out[i].begin());
    kept[i] = corners[static_cast<std::size_t>(keypoints[i].class_id)];
  }
  corners = std::move(kept);
  if (kept_index) {
    kept_index->clear();
    for (const auto& k : keypoints) kept_index->push_back(k.class_id);
  }
  return out;
}

std::vector<cv::Point2f> recognitionCorners(const cv::Mat& gray, int count) {
  std::vector<cv::KeyPoint> keypoints;
  cv::ORB::create(count, 1.2f, /*nlevels=*/1)->detect(gray, keypoints);  // one scale: revisits are seen at similar distances
  std::vector<cv::Point2f> out;
  for (const auto& k : keypoints) out.push_back(k.pt);
  return out;
}

namespace {
/// For each query descriptor, the candidate landmark it matches (or -1): near and unambiguous.
std::vector<int> matchLandmarks(const Keyframe& candidate, const PlaceQuery& query, const VerifyOptions& o) {
  std::vector<int> match(query.descriptors.size(), -1);
  for (std::size_t q = 0; q < query.descriptors.size(); ++q) {
    int best = std::numeric_limits<int>::max(), second = best, best_l = -1;
    for (std::size_t l = 0; l < candidate.landmarks.size(); ++l) {
      const int d = hamming(query.descriptors[q], candidate.landmarks[l].descriptor);
      if (d < best) second = best, best = d, best_l = static_cast<int>(l);
      else if (d < second) second = d;
    }
    if (best <= o.max_hamming && best < o.ratio * second) match[q] = best_l;
  }
  return match;
}
}  // namespace

PlaceVerification verifyPlace(const Keyframe& candidate, const PlaceQuery& query, const Eigen::Isometry3d& T_b_c,
                              const VerifyOptions& o) {
  PlaceVerification v;
  const std::vector<int> match = matchLandmarks(candidate, query, o);
  std::vector<cv::Point3d> object;
  std::vector<cv::Point2d> image;
  for (std::size_t q = 0; q < match.size(); ++q) {
    if (match[q] < 0) continue;
    const Eigen::Vector3d& p = candidate.landmarks[static_cast<std::size_t>(match[q])].p_w;
    object.emplace_back(p.x(), p.y(), p.z());
    image.emplace_back(query.xy[q].x(), query.xy[q].y());
  }
  v.matches = static_cast<int>(object.size());
  if (v.matches < std::max(o.min_inliers, 6)) return v;
  cv::Mat rvec, tvec, inliers;
  const bool ok = cv::solvePnPRansac(object, image, cv::Mat::eye(3, 3, CV_64F), cv::noArray(), rvec, tvec, false,
                                     o.iterations, o.reprojection_px / o.focal_px, 0.99, inliers, cv::SOLVEPNP_EPNP);
  v.inliers = ok ? inliers.rows : 0;
  if (!ok || v.inliers < o.min_inliers) return v;
  cv::Mat R_cv;
  cv::Rodrigues(rvec, R_cv);
  Eigen::Matrix3d R_c_w;
  Eigen::Vector3d t_c_w;
  cv::cv2eigen(R_cv, R_c_w);
  cv::cv2eigen(tvec, t_c_w);
  Eigen::Isometry3d T_w_c = Eigen::Isometry3d::Identity();
  T_w_c.linear() = R_c_w.transpose();
  T_w_c.translation() = -R_c_w.transpose() * t_c_w;
  const Eigen::Isometry3d T_w_b = T_w_c * T_b_c.inverse();
  v.accepted = true;
  v.p_w_b = T_w_b.translation();
  v.q_w_b = Eigen::Quaterniond(T_w_b.linear()).normalized();
  return v;
}

}  // namespace idyvins::map
