#pragma once
// A run as `idyvins run` and the ROS node make one, for any embedder: the rules that turn a
// request (mode, maps, threads) into the system's config and run options, opening a dataset
// for a config, and feeding it to the system. What the run writes: pipeline/run_outputs.h.

#include <atomic>
#include <functional>
#include <stdexcept>
#include <string>

#include "config/config.h"
#include "io/open_dataset.h"
#include "pipeline/system.h"

namespace idyvins::pipeline {

/// A run option that contradicts another or the config (a usage error, not bad data). Options
/// are named in the config's spelling ("localization_only"; the command line writes it
/// --localization-only, the ROS node ~localization_only): option() is the one at fault, and
/// the message, which reads after it ("needs load_map"), names the others in braces
/// ("needs {load_map}"); text() spells them as the embedder does, what() as they are.
class OptionError : public std::invalid_argument {
 public:
  OptionError(std::string option, std::string message);
  const std::string& option() const { return option_; }
  /// The message with each {name} replaced by spell(name).
  std::string text(const std::function<std::string(const std::string&)>& spell) const;

 private:
  std::string option_, message_;
};

/// What a run asks for beyond its config (`idyvins run`'s flags, the ROS node's parameters).
struct RunRequest {
  std::string mode;                ///< overrides config.mode when not empty (a mode name)
  int threads = 2;                 ///< 1: sequential; 2: pipelined (RunOptions::twoThreads)
  int feedback_delay = -1;         ///< 0 or 1 frames; -1: the threads' (1 with 2 threads, 0 with 1)
  bool solver_time_limit = false;  ///< cap each solve at max_solver_time (as solver_time_limit: 1)
  bool load_map = false;           ///< the run starts in a saved map
  bool save_map = false;           ///< the run saves its map
  bool localization_only = false;  ///< with load_map: the map stays as loaded
  bool masks_available = true;     ///< false for a live source: modes that need masks are refused
};

/// Applies the run rules of `request` to `config` and returns the system's run options: the
/// mode; a map, saved or loaded, turns loop closure on (the map is the loop closer's database);
/// localization_only needs load_map and excludes save_map; 2 threads means feedback delay 1;
/// solver_time_limit; a mode that needs masks is refused without them. Throws OptionError.
RunOptions applyRunRequest(const RunRequest& request, Config& config);

/// What opening a dataset for `config` reads: its topics (image1 only with two cameras;
/// `groundtruth_topic`, when not empty, overrides the config's), image size, rig, colour tables.
io::DatasetRequest datasetRequest(const Config& config, const std::string& groundtruth_topic = "", bool masks = true);

/// Opens `path` (a EuRoC folder or a ROS1 bag) for `config` (io::openDataset with
/// datasetRequest); masks are read when it has them and `masks` is true. Throws InputError for
/// what the readers refuse, and when config.mode needs masks the dataset does not have.
io::OpenedDataset openDataset(const std::string& path, const Config& config, const std::string& groundtruth_topic = "",
                              bool masks = true);

/// FNV-1a 64 (hex) of a config file and its camera files, in that order: stats.json's
/// config_fnv1a64, and what bench --plan / --collect compare. Throws InputError.
std::string configChecksum(const Config& config);

/// Gives `source`'s measurements to `system` in order (read ahead on a thread: images decode
/// while the system works) until the source ends, `max_frames` frames were given or `stop`
/// (when given) is non-zero; returns the frames given.
std::size_t feed(io::DataSource& source, System& system, std::size_t max_frames,
                 const std::atomic<int>* stop = nullptr);

}  // namespace idyvins::pipeline
