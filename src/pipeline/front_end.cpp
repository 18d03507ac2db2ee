#include "pipeline/front_end.h"

#include <algorithm>

#include "config/modes.h"
#include "core/error.h"

namespace idyvins::pipeline {

bool usesIdyFilter(Mode mode) { return traitsOf(mode).filter == FilterKind::kIdy; }

std::unique_ptr<frontend::FeatureFilter> makeFilter(const Config& c) {
  const FilterKind kind = traitsOf(c.mode).filter;
  if (kind == FilterKind::kRansac) return std::make_unique<frontend::RansacFilter>(c.tracker.f_threshold);
  if (kind == FilterKind::kSeg) return std::make_unique<frontend::SegFilter>();
  if (kind != FilterKind::kIdy) return nullptr;
  return std::make_unique<dynamic::IdyFilter>(optionsFor(c).idy, optionsFor(c).eliminate);
}

FrontEnd::FrontEnd(const Config& config)
    : mode_(config.mode),
      tracker_(config.rig(), optionsFor(config).tracker),
      filter_(makeFilter(config)),
      dropout_permille_(config.tracker.track_dropout_permille),  // config keys; no mode sets them
      dropout_seed_(config.tracker.track_dropout_seed) {
  idy_ = dynamic_cast<const dynamic::IdyFilter*>(filter_.get());
}

StereoFrame leftFirst(const StereoFrame& frame) {
  StereoFrame f = frame;
  std::swap(f.left, f.right);
  f.left_mask = cv::Mat();
  return f;
}

bool withheldTrack(std::uint64_t id, int seed, int permille) {
  if (permille <= 0) return false;
  // splitmix64 of id and seed: tracks spread evenly whatever their ids' order.
  std::uint64_t h = id + 0x9e3779b97f4a7c15ULL * (static_cast<std::uint64_t>(seed) + 1);
  h = (h ^ (h >> 30)) * 0xbf58476d1ce4e5b9ULL;
  h = (h ^ (h >> 27)) * 0x94d049bb133111ebULL;
  h ^= h >> 31;
  return h % 1000 < static_cast<std::uint64_t>(permille);
}

frontend::FeatureFrame FrontEnd::track(const StereoFrame& frame, const frontend::MotionPrior& prior) {
  const bool masks = traitsOf(mode_).needs_masks;
  if (masks && frame.left_mask.empty())
    throw InputError("frame " + std::to_string(frame.t_ns),
                     std::string("mode ") + toString(mode_) + " needs the left image's ground-truth mask");
  frontend::FeatureFrame out = tracker_.track(frame, prior, filter_.get(), masks ? &frame.left_mask : nullptr);
  if (dropout_permille_ > 0) {
    auto& f = out.features;
    f.erase(std::remove_if(
                f.begin(), f.end(),
                [&](const frontend::Feature& x) { return withheldTrack(x.id, dropout_seed_, dropout_permille_); }),
            f.end());
  }
  return out;
}

std::optional<dynamic::FrameStats> FrontEnd::idyStats() const {
  if (!idy_) return std::nullopt;
  return idy_->lastStats();
}

}  // namespace idyvins::pipeline
