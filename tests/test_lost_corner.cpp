// The lost-corner test (extension of DESIGN §4.3): the tracker's measurements judged by
// the IDY filter on a rendered sequence with a fast crossing truck.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <map>
#include <set>

#include "dynamic/dynamic.h"
#include "frontend/feature_tracker.h"
#include "sim_scenes.h"

namespace idyvins::dynamic {
namespace {

using Eigen::Vector3d;
using test::crossingVehicleScene;
using test::stereo;
using test::truePrior;

TEST(LostCornerTest, LostNewCornersAwayFromTheirStaticPredictionAreJudgedMoving) {
  // A car crosses 7-9 m ahead at 20 m/s: about 1 m per frame, too fast for KLT, so most of
  // its new corners are lost in their second frame. Static corners lost at the same time
  // (leaving the image, hidden by the truck) must mostly be found where the prior puts them
  // or be recognised as hidden (something nearer stands there now).
  const sim::Scene scene = crossingVehicleScene(3.0, "truck", Vector3d(8.0, 2.5, 3.0), Vector3d(9.0, -30.0, 0.0), 20.0);
  for (const bool judge : {true, false}) {
    const Config& rig = scene.rig();
    frontend::TrackerParams params = rig.tracker;
    params.lost_track_test = judge;
    frontend::FeatureTracker tracker(rig.rig(), params);
    // The IDY filter as the judge of lost corners only: no elimination, no marking, no
    // stereo motion test (the tracks stay those of the tracker alone).
    IdyOptions judge_only = rig.idy;
    judge_only.lambda_dy = judge_only.lambda_dy_c = 1e12;
    judge_only.stereo.enabled = false;
    judge_only.T_r_l = rig.T_b_c[1].inverse() * rig.T_b_c[0];
    IdyFilter filter(judge_only);
    std::map<std::uint64_t, bool> new_on_vehicle;  // new corners of the previous frame
    std::size_t lost_vehicle = 0, lost_static = 0, judged_vehicle = 0, judged_static = 0, tested = 0;
    sim::SceneFrame prev = scene.renderFrame(0);
    for (std::size_t k = 0; k < 61; ++k) {
      const sim::SceneFrame f = k == 0 ? prev : scene.renderFrame(k);
      const frontend::FeatureFrame out =
          tracker.track(stereo(f), k == 0 ? frontend::MotionPrior{} : truePrior(prev, f, rig), &filter);
      std::set<std::uint64_t> alive;
      for (const auto& ft : out.features) alive.insert(ft.id);
      for (const auto& [id, on_vehicle] : new_on_vehicle)
        if (!alive.count(id)) (on_vehicle ? lost_vehicle : lost_static) += 1;
      for (const auto& ft : out.lost_moving) {
        ASSERT_TRUE(new_on_vehicle.count(ft.id)) << "only new corners of the previous frame are judged";
        EXPECT_FALSE(alive.count(ft.id));
        EXPECT_EQ(ft.label, FeatureLabel::kEliminated);
        (new_on_vehicle[ft.id] ? judged_vehicle : judged_static) += 1;
      }
      tested += out.lost_tested;
      new_on_vehicle.clear();
      for (const auto& ft : out.features) {
        if (ft.track_length != 1) continue;
        new_on_vehicle[ft.id] = f.cam[0].mask.at<std::uint8_t>(static_cast<int>(std::lround(ft.uv.y())),
                                                               static_cast<int>(std::lround(ft.uv.x()))) != 0;
      }
      prev = f;
    }
    std::printf(
        "judge %d: new corners lost in their second frame: %zu on the car (%zu judged moving), %zu static "
        "(%zu judged moving); %zu tested\n",
        judge, lost_vehicle, judged_vehicle, lost_static, judged_static, tested);
    if (!judge) {
      EXPECT_EQ(judged_vehicle + judged_static + tested, 0u);
      continue;
    }
    // Measured at 2d6b296: 440 of 642 on the truck, 19 of 509 static. Without the ZNCC
    // ceiling (moved = any mismatch) 577 and 57: corners on the truck's silhouette over the
    // background half match and are left alone now. Since no corner is detected where its
    // first patch cannot be cut (near the border): 434 of 629 and 20 of 332 (the border
    // corners were lost often and never judged moving).
    ASSERT_GT(lost_vehicle, 100u);
    EXPECT_GT(judged_vehicle, lost_vehicle * 6 / 10);
    EXPECT_LT(judged_static, lost_static * 7 / 100);
  }
}

}  // namespace
}  // namespace idyvins::dynamic
