// Sliding the window: the oldest keyframe marginalized into the prior (with its IMU factor and
// its landmarks' projections) or the second newest frame dropped; the keyframe that leaves, for
// the loop closer; the IMU samples no longer needed.

#include <ceres/loss_function.h>

#include <deque>
#include <unordered_map>

#include "backend/estimator.h"
#include "backend/imu_factor.h"
#include "backend/landmark_factors.h"

namespace idyvins::backend {

using Eigen::Isometry3d;
using Eigen::Quaterniond;
using Eigen::Vector2d;
using Eigen::Vector3d;

void Estimator::slide(bool keyframe) {
  if (w_.count < kWindowSize) return;
  // Before the initialization a stereo window slides its oldest frame out, a monocular one
  // keeps its keyframes (the parallax its structure from motion needs).
  if (keyframe || (!w_.initialized && rig_.stereo))
    marginalizeOldest();
  else
    dropSecondNewest();
  // Keep the IMU samples still needed (from the oldest window frame on, and from the last
  // good state while a new segment must continue from it).
  TimeNs keep_from = seg_.reanchor_pending ? std::min(w_.frames[0].t_ns, seg_.last_good_t_ns) : w_.frames[0].t_ns;
  if (!seg_.td_times.empty())  // the offset's search shifts its intervals by up to kTdInitSearchS
    keep_from = std::min(keep_from, seg_.td_times.front() - static_cast<TimeNs>(2e9 * kTdInitSearchS));
  std::size_t first = 0;
  while (first + 1 < w_.imu.size() && w_.imu[first + 1].t_ns <= keep_from) ++first;
  if (first > 0) w_.imu.erase(w_.imu.begin(), w_.imu.begin() + static_cast<std::ptrdiff_t>(first));
}

LeavingKeyframe Estimator::leavingKeyframe() const {
  LeavingKeyframe k;
  const Isometry3d T = w_.frames[0].T_w_b();
  k.t_ns = w_.frames[0].t_ns;
  k.p_w_b = T.translation();
  k.q_w_b = Quaterniond(T.linear()).normalized();
  for (const auto& [id, lm] : w_.fm.landmarks()) {
    if (lm.start_frame != 0) continue;  // frame 0 is the oldest: its landmarks start there
    KeyframeObservation o;
    o.id = id;
    o.label = lm.label;
    o.has_position = lm.usable();
    if (o.has_position) o.p_w = landmarkWorld(lm);
    o.uv = lm.obs.front().uv;
    o.xy = lm.obs.front().xy;
    k.observations.push_back(o);
  }
  return k;
}

void Estimator::marginalizeOldest() {
  if (w_.initialized) {
    Marginalizer m;
    double* pose0 = w_.frames[0].pose.data();
    double* sb0 = w_.frames[0].sb.data();
    if (w_.prior) {
      std::vector<int> drop;
      for (std::size_t k = 0; k < w_.prior->blocks.size(); ++k)
        if (w_.prior->blocks[k] == pose0 || w_.prior->blocks[k] == sb0) drop.push_back(static_cast<int>(k));
      // Carried into the new prior even when it does not touch frame 0.
      m.add({std::make_shared<MarginalizationFactor>(w_.prior), nullptr, w_.prior->blocks, drop});
    }
    if (w_.frames[1].pre && w_.frames[1].pre->sumDt() <= 10.0)
      m.add({std::make_shared<ImuFactor>(w_.frames[1].pre.get()),
             nullptr,
             {pose0, sb0, w_.frames[1].pose.data(), w_.frames[1].sb.data()},
             {0, 1}});
    auto huber = std::make_shared<ceres::HuberLoss>(options_.huber_px);
    const ProjectionWeight w{rig_.focal_px, options_.sigma_px, nullptr};
    std::deque<double> shares;  // the projection weights point at them until marginalize()
    for (auto& [id, lm] : w_.fm.landmarks()) {
      if (lm.start_frame != 0 || !lm.usable()) continue;
      std::map<int, const double*> share_of_frame;
      if (options_.prior_landmark_share && lm.priorShare() < 1.0) {
        shares.push_back(lm.priorShare());
        for (int j = 0; j <= lm.endFrame(); ++j) share_of_frame[j] = &shares.back();
      }
      // The prior keeps no information on the time offset: the marginalized observations are
      // moved to the current estimate (a prior that kept it would hold td near its first values).
      const TdUse td = estimatesTd() ? TdUse{false, w_.td_s} : TdUse{};
      const int depth_at = estimatesExtrinsic() ? 3 : 2;  // after the poses (and T_b_c0)
      for (const auto& lf : landmarkFactors(lm, rig_, w, td, share_of_frame, estimatesRays(), extrinsicUse()))
        m.add({lf.cost, huber, factorBlocks(lm, lf.frame, false),
               lf.frame < 0 ? std::vector<int>{0} : std::vector<int>{0, depth_at}});
    }
    w_.prior = std::make_shared<MarginalizationPrior>(m.marginalize());
    if (options_.prior_fading < 1.0) w_.prior->scaleInformation(options_.prior_fading);
    if (w_.prior->blocks.empty()) w_.prior.reset();
    if (w_.prior && estimatesExtrinsic()) ex_.sigma = marginalSigma(*w_.prior, ex_.block.data());
  }
  if (w_.initialized) leaving_ = leavingKeyframe();
  for (const auto& [id, lm] : w_.fm.landmarks())
    if (lm.start_frame == 0 && lm.endFrame() < w_.count) addToStaticMap(lm);  // leaves the window
  std::vector<Isometry3d> T_w_b;                                              // before the slide
  for (int i = 0; i <= kWindowSize; ++i) T_w_b.push_back(w_.frames[i].T_w_b());
  std::unordered_map<double*, double*> remap;
  for (int i = 0; i < kWindowSize; ++i) {
    w_.frames[i].t_ns = w_.frames[i + 1].t_ns;
    w_.frames[i].pose = w_.frames[i + 1].pose;
    w_.frames[i].sb = w_.frames[i + 1].sb;
    w_.frames[i].pre = std::move(w_.frames[i + 1].pre);
    remap[w_.frames[i + 1].pose.data()] = w_.frames[i].pose.data();
    remap[w_.frames[i + 1].sb.data()] = w_.frames[i].sb.data();
  }
  w_.frames[0].pre.reset();
  w_.fm.removeOldest(T_w_b, rig_, options_.reanchor_triangulate, estimatesRays());
  if (w_.prior) w_.prior->remap(remap);
  w_.count = kWindowSize - 1;
}

void Estimator::dropSecondNewest() {
  const int k = kWindowSize - 1, newest = kWindowSize;
  if (w_.prior) {
    std::vector<int> drop;
    for (std::size_t i = 0; i < w_.prior->blocks.size(); ++i)
      if (w_.prior->blocks[i] == w_.frames[k].pose.data() || w_.prior->blocks[i] == w_.frames[k].sb.data())
        drop.push_back(static_cast<int>(i));
    if (!drop.empty()) {
      Marginalizer m;
      m.add({std::make_shared<MarginalizationFactor>(w_.prior), nullptr, w_.prior->blocks, drop});
      w_.prior = std::make_shared<MarginalizationPrior>(m.marginalize());
      if (w_.prior->blocks.empty()) w_.prior.reset();
    }
  }
  // One preintegration from frame k-1 to the newest frame; none across an IMU gap (either part missing).
  const bool across_gap = !w_.frames[k].pre || !w_.frames[newest].pre;
  auto merged = across_gap ? nullptr : integrate(w_.frames[k - 1].t_ns, w_.frames[newest].t_ns, w_.frames[k - 1].nav());
  w_.frames[k].t_ns = w_.frames[newest].t_ns;
  w_.frames[k].pose = w_.frames[newest].pose;
  w_.frames[k].sb = w_.frames[newest].sb;
  w_.frames[k].pre = merged || across_gap ? std::move(merged) : std::move(w_.frames[newest].pre);
  w_.frames[newest].pre.reset();
  w_.fm.removeFrame(k);
  if (w_.prior)
    w_.prior->remap({{w_.frames[newest].pose.data(), w_.frames[k].pose.data()},
                     {w_.frames[newest].sb.data(), w_.frames[k].sb.data()}});
  w_.count = kWindowSize - 1;
}
}  // namespace idyvins::backend
