// Place recognition and its geometric check on rendered frames of a street: a place seen
// again is ranked first and its pose recovered by PnP; another place is refused.

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>

#include "camera/camera_model.h"
#include "map/keyframe_database.h"
#include "map/place_verifier.h"
#include "sim_scenes.h"

namespace idyvins::map {
namespace {

struct Rendered {
  Keyframe keyframe;  // with landmarks from the renderer's depth
  PlaceQuery query;
  Eigen::Isometry3d T_w_b;
};

Rendered render(const sim::Scene& scene, std::size_t k) {
  const sim::SceneFrame f = scene.renderFrame(k);
  const auto cam = camera::makeCamera(scene.rig().cams[0]);
  const Eigen::Isometry3d T_w_c = f.T_w_b * scene.rig().T_b_c[0];
  std::vector<cv::Point2f> corners = recognitionCorners(f.cam[0].image, 500);
  const std::vector<Descriptor> desc = describeCorners(f.cam[0].image, corners);
  Rendered r;
  r.T_w_b = f.T_w_b;
  r.keyframe.t_ns = f.t_ns;
  r.keyframe.p_w_b = f.T_w_b.translation();
  r.keyframe.q_w_b = Eigen::Quaterniond(f.T_w_b.linear());
  r.keyframe.descriptors = desc;
  for (std::size_t i = 0; i < corners.size(); ++i) {
    Eigen::Vector2d xy;
    if (!cam->liftToNormalized({corners[i].x, corners[i].y}, xy)) continue;
    r.query.xy.push_back(xy);
    r.query.descriptors.push_back(desc[i]);
    const float z = f.cam[0].depth.at<float>(cvRound(corners[i].y), cvRound(corners[i].x));
    if (z <= 0 || z > 60) continue;  // sky or far
    r.keyframe.landmarks.push_back({i, T_w_c * Eigen::Vector3d(xy.x() * z, xy.y() * z, z), xy, desc[i]});
  }
  return r;
}

class PlaceRecognition : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { scene_ = new sim::Scene(test::options("city", sim::Level::kNone, 12.0)); }
  static void TearDownTestSuite() { delete scene_; }
  static sim::Scene* scene_;
};
sim::Scene* PlaceRecognition::scene_ = nullptr;

TEST_F(PlaceRecognition, APlaceSeenAgainIsRankedFirstAndItsPoseRecovered) {
  KeyframeDatabase db, again;
  for (std::size_t k = 0; k <= 200; k += 20) {
    const Keyframe kf = render(*scene_, k).keyframe;
    db.add(kf);
    again.add(kf);
  }
  const Rendered now = render(*scene_, 83);
  const auto candidates = db.query(now.query.descriptors, now.keyframe.t_ns);
  ASSERT_FALSE(candidates.empty());
  const auto candidates_again = again.query(now.query.descriptors, now.keyframe.t_ns);  // deterministic
  ASSERT_EQ(candidates.size(), candidates_again.size());
  for (std::size_t i = 0; i < candidates.size(); ++i) {
    EXPECT_EQ(candidates[i].keyframe, candidates_again[i].keyframe);
    EXPECT_EQ(candidates[i].votes, candidates_again[i].votes);
  }
  EXPECT_EQ(db.keyframe(candidates[0].keyframe).t_ns, render(*scene_, 80).keyframe.t_ns)
      << "votes " << candidates[0].votes;
  const PlaceVerification v = verifyPlace(db.keyframe(candidates[0].keyframe), now.query, scene_->rig().T_b_c[0]);
  ASSERT_TRUE(v.accepted) << v.matches << " matches, " << v.inliers << " inliers";
  EXPECT_LT((v.p_w_b - now.T_w_b.translation()).norm(), 0.05);
  EXPECT_LT(Eigen::AngleAxisd(v.q_w_b.conjugate() * Eigen::Quaterniond(now.T_w_b.linear())).angle(), 0.01);
  // only keyframes before the given time are candidates
  for (const auto& c : db.query(now.query.descriptors, render(*scene_, 40).keyframe.t_ns))
    EXPECT_LT(db.keyframe(c.keyframe).t_ns, render(*scene_, 40).keyframe.t_ns);
}

TEST_F(PlaceRecognition, AnotherPlaceIsRefusedByTheGeometricCheck) {
  const Rendered old = render(*scene_, 0), now = render(*scene_, 220);
  ASSERT_GT((old.T_w_b.translation() - now.T_w_b.translation()).norm(), 5.0);
  const PlaceVerification v = verifyPlace(old.keyframe, now.query, scene_->rig().T_b_c[0]);
  EXPECT_FALSE(v.accepted) << v.matches << " matches, " << v.inliers << " inliers";
}

}  // namespace
}  // namespace idyvins::map

namespace idyvins::map {
namespace {

/// Monte Carlo: landmarks triangulated with stereo noise from `seen_from`, observed with pixel
/// noise from T_c_w, PnP (LM from the truth): the worst-axis std of the solved camera centre.
double monteCarloSigma(const std::vector<Eigen::Vector3d>& pts, const Eigen::Isometry3d& T_c_w,
                       const Eigen::Vector3d& seen_from, double f, double b, int runs) {
  cv::RNG rng(7);
  std::vector<Eigen::Vector3d> centres;
  for (int k = 0; k < runs; ++k) {
    std::vector<cv::Point3d> object;
    std::vector<cv::Point2d> image;
    for (const Eigen::Vector3d& p : pts) {
      const Eigen::Vector3d ray = p - seen_from;
      const double d = ray.norm();
      const Eigen::Vector3d r = ray / d, u = r.unitOrthogonal(), w = r.cross(u);
      const Eigen::Vector3d noisy =
          p + r * rng.gaussian(d * d / (f * b)) + u * rng.gaussian(d / f) + w * rng.gaussian(d / f);
      object.emplace_back(noisy.x(), noisy.y(), noisy.z());
      const Eigen::Vector3d X = T_c_w * p;
      image.emplace_back(X.x() / X.z() + rng.gaussian(1 / f), X.y() / X.z() + rng.gaussian(1 / f));
    }
    cv::Mat rvec, tvec;
    const Eigen::AngleAxisd aa(T_c_w.linear());
    rvec =
        (cv::Mat_<double>(3, 1) << aa.axis().x() * aa.angle(), aa.axis().y() * aa.angle(), aa.axis().z() * aa.angle());
    tvec = (cv::Mat_<double>(3, 1) << T_c_w.translation().x(), T_c_w.translation().y(), T_c_w.translation().z());
    cv::solvePnP(object, image, cv::Mat::eye(3, 3, CV_64F), cv::noArray(), rvec, tvec, true, cv::SOLVEPNP_ITERATIVE);
    cv::Mat R_cv;
    cv::Rodrigues(rvec, R_cv);
    Eigen::Matrix3d R;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) R(i, j) = R_cv.at<double>(i, j);
    centres.push_back(-R.transpose() * Eigen::Vector3d(tvec.at<double>(0), tvec.at<double>(1), tvec.at<double>(2)));
  }
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& c : centres) mean += c / runs;
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const auto& c : centres) cov += (c - mean) * (c - mean).transpose() / (runs - 1);
  return std::sqrt(Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(cov).eigenvalues().maxCoeff());
}

TEST(PlaceVerification, PnpPositionSigmaMatchesMonteCarloAndGrowsWithDistance) {
  // A camera looking along +z at 40 landmarks spread over the view; the map saw them from 1.5 m aside.
  // First-order propagation of stereo depth noise that is 12 % (5 m) to 60 % (25 m) of the depth:
  // within a factor 2.5 of the Monte Carlo spread (measured 0.058 vs 0.128 m at 5 m, 0.26 vs 0.20 m
  // at 25 m), and growing with the landmarks' distance, which is what the loop gate needs.
  const double f = 380, b = 0.11;
  cv::RNG rng(3);
  double near_sigma = 0;
  for (double depth : {5.0, 25.0}) {
    std::vector<Eigen::Vector3d> pts;
    for (int i = 0; i < 40; ++i)
      pts.emplace_back(rng.uniform(-0.6, 0.6) * depth, rng.uniform(-0.4, 0.4) * depth, depth * rng.uniform(0.7, 1.3));
    const Eigen::Isometry3d T_c_w = Eigen::Isometry3d::Identity();
    const Eigen::Vector3d seen_from(1.5, 0.0, -0.5);
    const double predicted = positionSigma(pts, T_c_w, seen_from, f, b, 1.0);
    const double measured = monteCarloSigma(pts, T_c_w, seen_from, f, b, 400);
    std::printf("landmarks at %.0f m: sigma predicted %.4f m, Monte Carlo %.4f m\n", depth, predicted, measured);
    EXPECT_GT(predicted, measured / 2.5) << depth;
    EXPECT_LT(predicted, measured * 2.5) << depth;
    if (depth == 5.0) {
      near_sigma = predicted;
      EXPECT_LT(predicted, 0.1);
    } else {
      EXPECT_GT(predicted, 3 * near_sigma);
      EXPECT_GT(predicted, 0.1);
    }
  }
}

}  // namespace
}  // namespace idyvins::map
