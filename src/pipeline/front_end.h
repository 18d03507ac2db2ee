#pragma once
// The front end as the system runs it for a mode (DESIGN §4.8): the stereo KLT tracker
// with the mode's tracker settings and rejection filter (none, F-RANSAC, ground-truth
// masks, or the IDY filter). `idyvins track` and pipeline::System share it.

#include <cstdint>
#include <memory>
#include <optional>

#include "config/config.h"
#include "dynamic/dynamic.h"
#include "frontend/feature_filter.h"
#include "frontend/feature_tracker.h"

namespace idyvins::pipeline {

/// True for the modes that run the IDY front-end filter (idy, idy-pre, idy-ba).
bool usesIdyFilter(Mode mode);

/// The rejection filter of config.mode: null for baseline.
std::unique_ptr<frontend::FeatureFilter> makeFilter(const Config& config);

/// Whether the track `id` is withheld from the back end (TrackerParams::track_dropout_permille):
/// a hash of id and seed below permille of 1000. Pure; the same answer in every frame.
bool withheldTrack(std::uint64_t id, int seed, int permille);

/// The pair left image first for a rig whose cam0 is the right camera (Config::cam0_right):
/// the images swapped (reference-counted, no copy) and cam0's mask, the right image's, dropped.
StereoFrame leftFirst(const StereoFrame& frame);

/// Tracker + filter of one mode; one instance per sequence.
class FrontEnd {
 public:
  explicit FrontEnd(const Config& config);
  /// Tracks one stereo frame. `prior` is used by the IDY filter (invalid: frame unfiltered);
  /// in seg mode the frame's left_mask must be set (InputError otherwise).
  frontend::FeatureFrame track(const StereoFrame& frame, const frontend::MotionPrior& prior);
  /// The IDY filter's statistics of the last frame (idy modes), else nullopt.
  std::optional<dynamic::FrameStats> idyStats() const;
  /// Drops every track (after an estimator reset).
  void reset() { tracker_.reset(); }
  Mode mode() const { return mode_; }

 private:
  Mode mode_;
  frontend::FeatureTracker tracker_;
  std::unique_ptr<frontend::FeatureFilter> filter_;
  const dynamic::IdyFilter* idy_ = nullptr;      ///< filter_ when it is the IDY filter
  int dropout_permille_ = 0, dropout_seed_ = 0;  ///< TrackerParams::track_dropout_*
};

}  // namespace idyvins::pipeline
