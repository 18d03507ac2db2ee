#include "backend/landmark_factors.h"

#include <ceres/cost_function.h>

namespace idyvins::backend {

using Eigen::Vector2d;

namespace {

/// The factors of a landmark whose anchor ray is estimated (block: ray x, y, inverse depth):
/// the anchor observation is a residual like the others.
std::vector<LandmarkFactor> rayLandmarkFactors(const Landmark& lm, const Rig& rig, const ProjectionWeight& w_static,
                                               const std::map<int, const double*>& scale_of_frame) {
  std::vector<LandmarkFactor> out{{std::make_shared<AnchorRayObservation>(lm.obs.front().xy, w_static), -1}};
  for (std::size_t k = 0; k < lm.obs.size(); ++k) {
    const Observation& o = lm.obs[k];
    const int frame = lm.start_frame + static_cast<int>(k);
    ProjectionWeight w = w_static;
    const auto it = scale_of_frame.find(frame);
    if (it != scale_of_frame.end()) w.info_scale = it->second;
    if (k > 0) out.push_back({std::make_shared<ProjectionTwoFrameRay>(o.xy, rig.T_b_c0, rig.T_b_c0, w), frame});
    if (!rig.stereo || !o.has_right) continue;
    if (k > 0)
      out.push_back({std::make_shared<ProjectionTwoFrameRay>(o.xy_right, rig.T_b_c0, rig.T_b_c1, w), frame});
    else
      out.push_back({std::make_shared<ProjectionOneFrameTwoCamRay>(o.xy_right, rig.T_b_c0, rig.T_b_c1, w_static), -1});
  }
  return out;
}

}  // namespace

std::vector<LandmarkFactor> landmarkFactors(const Landmark& lm, const Rig& rig, const ProjectionWeight& w_static,
                                            const TdUse& td, const std::map<int, const double*>& scale_of_frame,
                                            bool ray, const ExtrinsicUse& ex) {
  if (ray) return rayLandmarkFactors(lm, rig, w_static, scale_of_frame);
  std::vector<LandmarkFactor> out;
  const Observation& a = lm.obs.front();
  auto at = [&](const TimedObservation& o) -> Vector2d {
    return td.moved_to ? Vector2d(o.xy - (*td.moved_to - o.td_obs) * o.velocity) : o.xy;
  };
  const TimedObservation a_left = TimedObservation{a.xy, a.velocity, a.td_s};
  auto twoFrame = [&](const TimedObservation& target, bool right,
                      const ProjectionWeight& w) -> std::shared_ptr<ceres::CostFunction> {
    const Extrinsic& cam = right ? rig.T_b_c1 : rig.T_b_c0;
    if (ex.block) {
      const Extrinsic rel = right ? ex.T_c0_c1 : Extrinsic{};
      if (td.block) return std::make_shared<ProjectionTwoFrameExTd>(a_left, target, rel, w);
      return std::make_shared<ProjectionTwoFrameEx>(at(a_left), at(target), rel, w);
    }
    if (td.block) return std::make_shared<ProjectionTwoFrameTd>(a_left, target, rig.T_b_c0, cam, w);
    return std::make_shared<ProjectionTwoFrame>(at(a_left), at(target), rig.T_b_c0, cam, w);
  };
  for (std::size_t k = 0; k < lm.obs.size(); ++k) {
    const Observation& o = lm.obs[k];
    const int frame = lm.start_frame + static_cast<int>(k);
    ProjectionWeight w = w_static;  // stereo factors within one frame keep the static weight
    const auto it = scale_of_frame.find(frame);
    if (it != scale_of_frame.end()) w.info_scale = it->second;
    if (k > 0) out.push_back({twoFrame(TimedObservation{o.xy, o.velocity, o.td_s}, false, w), frame});
    if (!rig.stereo || !o.has_right) continue;
    const TimedObservation right = TimedObservation{o.xy_right, o.velocity_right, o.td_s};
    if (k > 0) {
      out.push_back({twoFrame(right, true, w), frame});
    } else if (td.block) {
      out.push_back(
          {std::make_shared<ProjectionOneFrameTwoCamTd>(a_left, right, rig.T_b_c0, rig.T_b_c1, w_static), -1});
    } else {
      out.push_back(
          {std::make_shared<ProjectionOneFrameTwoCam>(at(a_left), at(right), rig.T_b_c0, rig.T_b_c1, w_static), -1});
    }
  }
  return out;
}

bool inSolve(const Landmark& lm) { return lm.usable() && std::isfinite(lm.inv_depth); }

}  // namespace idyvins::backend
