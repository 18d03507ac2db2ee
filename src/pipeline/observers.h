#pragma once
// Observers of the per-frame output of pipeline::System: the evaluation of labels against
// ground-truth masks (and its raw material, the observation dump) and the per-frame
// statistics written as stats.json. Neither changes what the system computes.

#include <nlohmann/json.hpp>
#include <ostream>
#include <string>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "eval/dynamic_metrics.h"
#include "pipeline/system.h"

namespace idyvins::pipeline {

/// Counts every tracked left-image observation per track (how many, how many on a moving
/// object by the ground-truth mask, eliminated or not) and evaluates the labels against
/// the masks at the end (DESIGN §5). Memory grows with the number of tracks, not of
/// observations. With `keep_observations` it also keeps one record per observation
/// (front-end label, d_s, stereo χ², mask verdict) for writeCsv.
class ObservationRecorder final : public FrameObserver {
 public:
  /// `has_masks`: the frames' left_mask holds the ground-truth object ids.
  explicit ObservationRecorder(bool has_masks, bool keep_observations = false)
      : has_masks_(has_masks), keep_observations_(keep_observations) {}
  void onFrame(const StereoFrame& input, const FrameOutput& output) override;

  /// Classification and map cleanliness against the masks, with the run's final maps.
  eval::DynamicClassification classify(const Result& result);
  /// The static map's "ghosts": its points whose track was mostly on moving objects by the masks
  /// (what classify counts as static_map_points_on_moving). Empty without masks.
  std::vector<backend::MapPoint> staticMapOnMoving(const Result& result) const;
  /// One CSV row per observation: front-end label, d_s, Σ, stereo χ², mask verdict, and the
  /// landmark's fate (confirmed dynamic, in the static map, ever removed as an outlier).
  /// Needs `keep_observations`; throws InputError if the file cannot be written.
  void writeCsv(const std::string& path, const Result& result);
  std::size_t size() const { return observations_seen_; }

 private:
  struct Record {
    std::uint64_t id;
    bool on_moving;
    TimeNs t_ns;
    float u, v, d_s, credibility, stereo_chi2, stereo_depth;
    float u_right, v_right;  ///< the right match, pixels; negative without one
    frontend::FeatureLabel label;
    int track_length;
  };
  /// A lost new corner judged moving: its one observation counts as eliminated.
  void relabelLostMoving();

  bool has_masks_;
  bool keep_observations_;
  std::size_t observations_seen_ = 0;
  std::unordered_map<std::uint64_t, eval::TrackCounts> tracks_;
  std::vector<Record> observations_;  ///< only with keep_observations
  std::unordered_set<std::uint64_t> lost_moving_ids_;
  std::unordered_set<std::uint64_t> outlier_ids_;  ///< landmarks the outlier test removed at least once
};

/// The classification as the "classification" object of stats.json.
nlohmann::json toJson(const eval::DynamicClassification& c);

/// Writes stats.json while the run goes: `{"frames": [...], "summary": {...}}` with one
/// line per frame (timing, feature counts, estimator status, and the IDY filter's figures
/// in the idy modes), so memory does not grow with the run's length. finish() adds the
/// summary and closes the document; until then the stream holds an unfinished one.
class StatsRecorder final : public FrameObserver {
 public:
  explicit StatsRecorder(std::ostream& out);
  void onFrame(const StereoFrame& input, const FrameOutput& output) override;
  /// Writes the summary and closes the JSON document.
  void finish(const nlohmann::json& summary);
  std::size_t frames() const { return frames_; }

  /// One frame's entry of the "frames" array.
  static nlohmann::json frameJson(const FrameOutput& output);

 private:
  std::ostream& out_;
  std::size_t frames_ = 0;
};

/// Whether a stats.json key measures time (ends in `_ms`, or wall_s, realtime_factor,
/// threads): the only fields that may differ between runs of the same input and config.
bool isTimingField(const std::string& key);

}  // namespace idyvins::pipeline
