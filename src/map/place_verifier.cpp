#include "map/place_verifier.h"

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <cmath>
#include <limits>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>
#include <opencv2/features2d.hpp>

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
  cv::ORB::create(count, 1.2f, /*nlevels=*/1)
      ->detect(gray, keypoints);  // one scale: revisits are seen at similar distances
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
      if (d < best)
        second = best, best = d, best_l = static_cast<int>(l);
      else if (d < second)
        second = d;
    }
    if (best <= o.max_hamming && best < o.ratio * second) match[q] = best_l;
  }
  return match;
}
}  // namespace

double positionSigma(const std::vector<Eigen::Vector3d>& landmarks_w, const Eigen::Isometry3d& T_c_w,
                     const Eigen::Vector3d& seen_from, double focal_px, double baseline_m, double sigma_px) {
  const Eigen::Matrix3d R = T_c_w.linear();
  const Eigen::Vector3d t = T_c_w.translation();
  const double s = sigma_px / focal_px;  // normalized image units
  Eigen::Matrix<double, 6, 6> info = Eigen::Matrix<double, 6, 6>::Zero();
  for (const Eigen::Vector3d& p : landmarks_w) {
    const Eigen::Vector3d X = R * p + t;
    if (X.z() <= 1e-6) continue;
    Eigen::Matrix<double, 2, 3> J_proj;
    J_proj << 1 / X.z(), 0, -X.x() / (X.z() * X.z()), 0, 1 / X.z(), -X.y() / (X.z() * X.z());
    // pose perturbation [theta; dt] on the left of T_c_w: dX = -[X]x theta + dt
    Eigen::Matrix<double, 3, 6> dX;
    dX.leftCols<3>() << 0, X.z(), -X.y(), -X.z(), 0, X.x(), X.y(), -X.x(), 0;
    dX.rightCols<3>().setIdentity();
    const Eigen::Matrix<double, 2, 6> J = J_proj * dX;
    // the landmark as stereo triangulated it from `seen_from`
    const Eigen::Vector3d ray = p - seen_from;
    const double d = ray.norm();
    const Eigen::Vector3d r = ray / std::max(d, 1e-9);
    const double sd = d * d * s / baseline_m, sl = d * s;
    const Eigen::Matrix3d cov_w =
        sd * sd * r * r.transpose() + sl * sl * (Eigen::Matrix3d::Identity() - r * r.transpose());
    const Eigen::Matrix2d cov_uv =
        s * s * Eigen::Matrix2d::Identity() + J_proj * R * cov_w * R.transpose() * J_proj.transpose();
    info += J.transpose() * cov_uv.inverse() * J;
  }
  Eigen::FullPivLU<Eigen::Matrix<double, 6, 6>> lu(info);
  if (!lu.isInvertible()) return std::numeric_limits<double>::infinity();
  const Eigen::Matrix<double, 6, 6> cov = lu.inverse();
  // camera centre c = -R^T t: dc = -R^T ([t]x theta + dt)
  Eigen::Matrix3d t_hat;
  t_hat << 0, -t.z(), t.y(), t.z(), 0, -t.x(), -t.y(), t.x(), 0;
  Eigen::Matrix<double, 3, 6> G;
  G.leftCols<3>() = -R.transpose() * t_hat;
  G.rightCols<3>() = -R.transpose();
  const Eigen::Matrix3d cov_c = G * cov * G.transpose();
  return std::sqrt(std::max(0.0, Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(cov_c).eigenvalues().maxCoeff()));
}

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
  std::vector<cv::Point3d> object_in;
  std::vector<cv::Point2d> image_in;
  std::vector<Eigen::Vector3d> landmarks_in;
  for (int i = 0; i < inliers.rows; ++i) {
    const auto k = static_cast<std::size_t>(inliers.at<int>(i));
    object_in.push_back(object[k]);
    image_in.push_back(image[k]);
    landmarks_in.emplace_back(object[k].x, object[k].y, object[k].z);
  }
  cv::solvePnPRefineLM(object_in, image_in, cv::Mat::eye(3, 3, CV_64F), cv::noArray(), rvec, tvec);
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
  const Eigen::Isometry3d T_w_c_old =
      Eigen::Translation3d(candidate.p_w_b) * candidate.q_w_b * T_b_c;  // where the landmarks were seen from
  v.sigma_position_m =
      positionSigma(landmarks_in, T_w_c.inverse(), T_w_c_old.translation(), o.focal_px, o.stereo_baseline_m, 1.0);
  if (v.sigma_position_m > o.max_sigma_position_m) return v;
  v.accepted = true;
  v.p_w_b = T_w_b.translation();
  v.q_w_b = Eigen::Quaterniond(T_w_b.linear()).normalized();
  return v;
}

}  // namespace idyvins::map
