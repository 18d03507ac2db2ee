#pragma once
// Observers of the per-frame output of pipeline::System: the evaluation of labels against
// ground-truth masks (and its raw material, the observation dump) and the per-frame
// statistics written as stats.json. Neither changes what the system computes.

#include <nlohmann/json.hpp>
#include <string>
#include <unordered_set>
#include <vector>

#include "eval/dynamic_metrics.h"
#include "pipeline/system.h"

namespace idyvins::pipeline {

/// Records every tracked left-image observation with the front end's label, d_s, the
/// stereo-test χ² and (when the frames carry masks) whether the ground-truth mask puts it
/// on a moving object; evaluates the labels against the masks at the end (DESIGN §5).
class ObservationRecorder final : public FrameObserver {
 public:
  /// `has_masks`: the frames' left_mask holds the ground-truth object ids.
  explicit ObservationRecorder(bool has_masks) : has_masks_(has_masks) {}
  void onFrame(const StereoFrame& input, const FrameOutput& output) override;

  /// Classification and map cleanliness against the masks, with the run's final maps.
  eval::DynamicClassification classify(const Result& result);
  /// One CSV row per observation: front-end label, d_s, Σ, stereo χ², mask verdict, and the
  /// landmark's fate (confirmed dynamic, in the static map, ever removed as an outlier).
  /// Throws InputError if the file cannot be written.
  void writeCsv(const std::string& path, const Result& result);
  std::size_t size() const { return observations_.size(); }

 private:
  struct Record {
    std::uint64_t id;
    bool on_moving;
    TimeNs t_ns;
    float u, v, d_s, credibility, stereo_chi2;
    frontend::FeatureLabel label;
    int track_length;
  };
  /// A lost new corner judged moving: its one observation counts as eliminated.
  void relabelLostMoving();

  bool has_masks_;
  std::vector<Record> observations_;
  std::unordered_set<std::uint64_t> lost_moving_ids_;
  std::unordered_set<std::uint64_t> outlier_ids_;  ///< landmarks the outlier test removed at least once
};

/// The classification as the "classification" object of stats.json.
nlohmann::json toJson(const eval::DynamicClassification& c);

/// Per-frame statistics (the "frames" array of stats.json): timing, feature counts,
/// estimator status, and the IDY filter's figures in the idy modes.
class StatsRecorder final : public FrameObserver {
 public:
  void onFrame(const StereoFrame& input, const FrameOutput& output) override;
  const nlohmann::json& frames() const { return frames_; }

 private:
  nlohmann::json frames_ = nlohmann::json::array();
};

/// Whether a stats.json key measures time (ends in `_ms`, or wall_s, realtime_factor,
/// threads): the only fields that may differ between runs of the same input and config.
bool isTimingField(const std::string& key);

}  // namespace idyvins::pipeline
