#include "pipeline/front_end.h"

#include "core/error.h"
#include "pipeline/modes.h"

namespace idyvins::pipeline {

bool usesIdyFilter(Mode mode) { return traitsOf(mode).filter == FilterKind::kIdy; }

std::unique_ptr<frontend::FeatureFilter> makeFilter(Mode mode, const Config& c) {
  const ModeTraits& m = traitsOf(mode);
  if (m.filter == FilterKind::kRansac) return std::make_unique<frontend::RansacFilter>(c.tracker.f_threshold);
  if (m.filter == FilterKind::kSeg) return std::make_unique<frontend::SegFilter>();
  if (m.filter != FilterKind::kIdy) return nullptr;
  dynamic::IdyOptions o;
  o.lambda_dy = c.dynamic.lambda_dy;
  o.lambda_dy_c = c.dynamic.lambda_dy_c;
  o.eliminate = m.eliminate;
  o.stereo = c.dynamic.stereo;
  o.stereo.enabled = o.stereo.enabled && c.num_cam == 2 && c.T_b_c.size() >= 2;
  if (o.stereo.enabled) o.T_r_l = c.T_b_c[1].inverse() * c.T_b_c[0];
  return std::make_unique<dynamic::IdyFilter>(o);
}

frontend::TrackerParams trackerParamsFor(Mode mode, const Config& config) {
  frontend::TrackerParams p;
  // Eliminated features never reach the estimator again, but the tracker keeps following
  // them so that no new corner is seeded on the same moving object (DESIGN §4.9).
  p.keep_following_eliminated = traitsOf(mode).follow_eliminated;
  p.judge_lost_new_tracks = p.keep_following_eliminated && config.dynamic.lost_track_test;
  return p;
}

FrontEnd::FrontEnd(const Config& config, Mode mode)
    : mode_(mode), tracker_(config, trackerParamsFor(mode, config)), filter_(makeFilter(mode, config)) {
  idy_ = dynamic_cast<const dynamic::IdyFilter*>(filter_.get());
}

frontend::FeatureFrame FrontEnd::track(const StereoFrame& frame, const frontend::MotionPrior& prior) {
  const bool masks = traitsOf(mode_).needs_masks;
  if (masks && frame.left_mask.empty())
    throw InputError("frame " + std::to_string(frame.t_ns),
                     std::string("mode ") + toString(mode_) + " needs the left image's ground-truth mask");
  return tracker_.track(frame, prior, filter_.get(), masks ? &frame.left_mask : nullptr);
}

std::optional<dynamic::FrameStats> FrontEnd::idyStats() const {
  if (!idy_) return std::nullopt;
  return idy_->lastStats();
}

}  // namespace idyvins::pipeline
