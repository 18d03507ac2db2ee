#pragma once
// Every file a run writes, in one piece for every embedder (`idyvins run`, the ROS node, a
// library user): the staged output folder, stats.json written while the run goes, the result
// files, the summary with its extras, the ghost map, the saved map, run.json and the ground
// truth over the run's span. docs/cli.md lists the files.

#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/measurements.h"
#include "io/output_folder.h"
#include "pipeline/system.h"

namespace idyvins::pipeline {

/// Where a run writes, and what it writes beside the result files.
struct RunOutputsOptions {
  std::vector<std::string> inputs;       ///< never an output, nor inside one (dataset, config, loaded map)
  bool force = false;                    ///< write into a folder holding files idyvins did not write (none removed)
  std::vector<std::string> extra_names;  ///< files the embedder writes beside the run's (the node's latency.csv)
  bool masks = false;                    ///< ground-truth masks: classification and map_static_on_moving.ply
  std::string dump_observations;         ///< where the observation CSV goes ("": none; io::OutputFolder::extraFile)
  std::string save_map;                  ///< where the map is saved ("": none; io::OutputFolder::extraFolder)
};

/// How a run was made, for run.json (what `idyvins report` shows).
struct RunRecord {
  std::string command_line;  ///< as typed
  std::string dataset;       ///< the dataset as given
};

/// What the finished run is written with beside its result.
struct RunEnd {
  double wall_s = 0;                                 ///< wall-clock seconds of the run (0: not measured)
  nlohmann::json extras = nlohmann::json::object();  ///< keys the embedder adds to the summary
  std::vector<StampedPose> groundtruth;              ///< reference poses: ATE in the summary, groundtruth.tum
  const RunRecord* record = nullptr;                 ///< run.json (not written without)
};

/// The output folder of one run and every file it writes. Construct before the run (the
/// folder is refused then, not at the end), attach to the system, write after finish(),
/// publish.
class RunOutputs {
 public:
  /// Opens the staged folder for `out` (runFolderOptions) and stats.json's staging file.
  /// Throws InputError when `out` is refused or cannot be written.
  RunOutputs(const std::string& out, RunOutputsOptions options);
  ~RunOutputs();
  RunOutputs(const RunOutputs&) = delete;
  RunOutputs& operator=(const RunOutputs&) = delete;

  /// The observers that record the run (stats.json; with masks or a dump, the observations),
  /// to attach to the system before its first frame.
  std::vector<FrameObserver*> observers();
  /// Attaches observers() to `system`.
  void attach(System& system);
  /// Writes every file of the finished run into the staging folder and returns stats.json's
  /// summary: summaryJson with the threads, feedback delay, build, config checksum,
  /// classification (masks), `end.extras` and the ATE (ground truth); the result files
  /// (writeResultFiles), the observation CSV, map_static_on_moving.ply (masks), the saved map
  /// (with the rig's fingerprint), run.json (with a record) and groundtruth.tum (the reference
  /// from 1 s before the first to 1 s after the last frame). Throws InputError.
  nlohmann::json write(const System& system, const Result& result, const RunEnd& end);
  /// The staging folder, where the embedder writes files of its own (extra_names).
  const std::string& path() const;
  /// Moves the folder into place (io::OutputFolder::publish); returns its warnings.
  std::vector<std::string> publish();

 private:
  struct Files;
  RunOutputsOptions options_;
  std::unique_ptr<Files> files_;
};

}  // namespace idyvins::pipeline
