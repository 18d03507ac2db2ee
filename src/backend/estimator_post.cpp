// After each solve (DESIGN §4.6, §4.7): candidates confirmed dynamic or cleared, outlier
// landmarks removed (confirmed dynamic with confirm_outliers), right observations that do not
// fit dropped, and the static map of the landmarks that leave the window.

#include "backend/estimator.h"
#include "backend/landmark_factors.h"
#include "backend/projection_factors.h"

namespace idyvins::backend {

using Eigen::Isometry3d;
using Eigen::Quaterniond;
using Eigen::Vector2d;
using Eigen::Vector3d;

Vector3d Estimator::landmarkWorld(const Landmark& lm) const {
  return cameraPose(w_.frames[lm.start_frame].T_w_b(), rig_.T_b_c0) * lm.anchorPoint();
}

void Estimator::addToStaticMap(const Landmark& lm) {
  if (!w_.initialized || !lm.usable() || lm.label != FeatureLabel::kStatic || lm.obs.size() < 3) return;
  if (!map_.mapped.insert(lm.id).second) return;
  map_.static_points.push_back({landmarkWorld(lm), FeatureLabel::kStatic, lm.id});
}

void Estimator::flushMap() {
  if (!w_.initialized) return;
  for (const auto& [id, lm] : w_.fm.landmarks()) addToStaticMap(lm);
}

double Estimator::meanReprojectionErrorPx(const Landmark& lm, int last_n) const {
  const Vector3d pts_i(lm.anchorRay().x(), lm.anchorRay().y(), 1.0);
  const imu::NavState si = w_.frames[lm.start_frame].nav();
  const std::size_t first =
      last_n > 0 ? std::max<std::size_t>(1, lm.obs.size() - std::min<std::size_t>(last_n, lm.obs.size())) : 1;
  double sum = 0;
  for (std::size_t k = first; k < lm.obs.size(); ++k) {
    const imu::NavState sj = w_.frames[lm.start_frame + k].nav();
    const Vector3d p =
        transferPoint(pts_i, lm.inv_depth, si.p_w_b, si.q_w_b, sj.p_w_b, sj.q_w_b, rig_.T_b_c0, rig_.T_b_c0);
    sum += (p.head<2>() / p.z() - lm.obs[k].xy).norm() * rig_.focal_px;
  }
  return lm.obs.size() > first ? sum / static_cast<double>(lm.obs.size() - first) : 0.0;
}

void Estimator::postProcess(FrameResult& r) {
  std::vector<std::uint64_t> confirmed;
  for (auto& [id, lm] : w_.fm.landmarks()) {
    if (lm.label != FeatureLabel::kCandidate || !lm.usable() || lm.obs.size() < 2) continue;
    // The error of the observations made since the landmark was marked: a long static
    // history must not dilute an object that has just started to move.
    if (meanReprojectionErrorPx(lm, lm.candidate_obs) > options_.outlier_px) {
      confirmed.push_back(id);
      map_.dynamic_ids.insert(id);
      if (map_.mapped.insert(id).second)
        r.confirmed_points.push_back({landmarkWorld(lm), FeatureLabel::kConfirmedDynamic, id});
    } else if (lm.candidate_obs >= options_.clear_after_observations) {
      lm.label = FeatureLabel::kStatic;
      lm.candidate_obs = 0;
      ++r.cleared;
    }
  }
  r.confirmed_dynamic = static_cast<int>(confirmed.size());
  w_.fm.remove(confirmed);
}

void Estimator::removeOutliers(FrameResult& r) {
  std::vector<std::uint64_t>& bad = r.outlier_ids;
  for (const auto& [id, lm] : w_.fm.landmarks())
    if (lm.usable() && lm.obs.size() > 1 && meanReprojectionErrorPx(lm) > options_.outlier_px) bad.push_back(id);
  if (options_.post_process && options_.confirm_outliers) {
    for (std::uint64_t id : bad) {
      if (!map_.dynamic_ids.insert(id).second) continue;
      ++r.outliers_confirmed;
      if (map_.mapped.insert(id).second)
        r.confirmed_points.push_back({landmarkWorld(w_.fm.landmarks().at(id)), FeatureLabel::kConfirmedDynamic, id});
    }
  }
  w_.fm.remove(bad);
  // Not while estimating td: with it the PipelineTimeOffset test's run falls short of the run
  // with td known (docs/results.md), also with the observations moved to the estimated offset
  // as the factors move them. Why is not settled.
  if (options_.stereo_outlier_px > 0 && !estimatesTd()) r.right_outliers = dropRightOutliers();
}

int Estimator::dropRightOutliers() {
  int dropped = 0;
  for (auto& [id, lm] : w_.fm.landmarks()) {
    if (!inSolve(lm)) continue;
    const Vector3d pts_i(lm.anchorRay().x(), lm.anchorRay().y(), 1.0);
    const imu::NavState si = w_.frames[lm.start_frame].nav();
    for (std::size_t k = 0; k < lm.obs.size(); ++k) {
      Observation& o = lm.obs[k];
      if (!o.has_right) continue;
      const imu::NavState sj = w_.frames[lm.start_frame + static_cast<int>(k)].nav();
      const Vector3d p =
          transferPoint(pts_i, lm.inv_depth, si.p_w_b, si.q_w_b, sj.p_w_b, sj.q_w_b, rig_.T_b_c0, rig_.T_b_c1);
      if (p.z() > 0 && (p.head<2>() / p.z() - o.xy_right).norm() * rig_.focal_px <= options_.stereo_outlier_px)
        continue;
      o.has_right = false;
      ++dropped;
    }
  }
  return dropped;
}
}  // namespace idyvins::backend
