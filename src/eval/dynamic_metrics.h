#pragma once
// Dynamic-feature classification and map cleanliness against ground-truth masks
// (DESIGN §5). Pure functions: the run loop records the observations, these count.

#include <cstddef>
#include <cstdint>
#include <unordered_map>
#include <unordered_set>
#include <vector>

namespace idyvins::eval {

/// One tracked left-image observation: its front-end track (landmark) id, whether the
/// ground-truth mask puts it on a moving object, and whether the front end
/// eliminated the track at this observation.
struct MaskedObservation {
  std::uint64_t id = 0;
  bool on_moving = false;
  bool eliminated = false;
};

struct DynamicClassification {
  std::size_t observations_on_moving = 0, observations_static = 0;
  std::size_t true_positives = 0, false_positives = 0;
  double recall = 0;          ///< share of moving observations flagged dynamic
  double static_flagged = 0;  ///< share of static observations flagged dynamic
  double precision = 0, f1 = 0;
  /// The same recall over observations of tracks seen in at least two frames (the
  /// ones a two-view test can judge; a track seen once never reaches the estimator's
  /// pose constraints).
  std::size_t observations_on_moving_tracked = 0;
  double recall_tracked = 0;
  std::size_t static_map_points = 0;
  std::size_t static_map_on_moving = 0;       ///< most of the point's observations on moving objects
  std::size_t static_map_ever_on_moving = 0;  ///< at least one observation on a moving object
  double static_map_fraction_on_moving = 0, static_map_fraction_ever_on_moving = 0;
};

/// What the classification needs of one track: how many observations it has, how many
/// of them the masks put on a moving object, and whether it was eliminated at any of them.
/// A run keeps one of these per track instead of one record per observation.
struct TrackCounts {
  std::size_t observations = 0, on_moving = 0;
  bool eliminated = false;
};

/// Adds one observation to its track's counts.
void addObservation(std::unordered_map<std::uint64_t, TrackCounts>& tracks, const MaskedObservation& o);

/// The classification from per-track counts; equal to classifyDynamic over the
/// observations the counts were made from.
DynamicClassification classifyTracks(const std::unordered_map<std::uint64_t, TrackCounts>& tracks,
                                     const std::unordered_set<std::uint64_t>& confirmed_ids,
                                     const std::vector<std::uint64_t>& static_map_ids);

/// Labels belong to landmarks (DESIGN §4.4): an observation counts as flagged dynamic
/// when its track was eliminated (at any observation) or confirmed dynamic.
/// `static_map_ids` are the landmark ids of the static-map points.
DynamicClassification classifyDynamic(const std::vector<MaskedObservation>& observations,
                                      const std::unordered_set<std::uint64_t>& confirmed_ids,
                                      const std::vector<std::uint64_t>& static_map_ids);

}  // namespace idyvins::eval
