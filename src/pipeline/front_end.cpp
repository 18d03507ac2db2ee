#include "pipeline/front_end.h"

#include "core/error.h"
#include "pipeline/modes.h"

namespace idyvins::pipeline {

bool usesIdyFilter(Mode mode) { return traitsOf(mode).filter == FilterKind::kIdy; }

std::unique_ptr<frontend::FeatureFilter> makeFilter(const Config& c) {
  const FilterKind kind = traitsOf(c.mode).filter;
  if (kind == FilterKind::kRansac) return std::make_unique<frontend::RansacFilter>(c.tracker.f_threshold);
  if (kind == FilterKind::kSeg) return std::make_unique<frontend::SegFilter>();
  if (kind != FilterKind::kIdy) return nullptr;
  return std::make_unique<dynamic::IdyFilter>(optionsFor(c).idy);
}

FrontEnd::FrontEnd(const Config& config)
    : mode_(config.mode), tracker_(config.rig(), optionsFor(config).tracker), filter_(makeFilter(config)) {
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
