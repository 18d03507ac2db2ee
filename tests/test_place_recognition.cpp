// Place recognition and its geometric check on rendered frames of a street: a place seen
// again is ranked first and its pose recovered by PnP; another place is refused.

#include <gtest/gtest.h>

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
