#pragma once
// Opening a dataset for the commands that drive the system: a EuRoC folder or a ROS1 bag,
// detected, with its ground truth and (where present and wanted) ground-truth masks.

#include <memory>
#include <string>
#include <vector>

#include "core/measurements.h"
#include "io/config.h"
#include "io/data_source.h"

namespace idyvins::app {

/// The opened dataset and what it offers.
struct Input {
  std::unique_ptr<io::DataSource> source;
  std::vector<StampedPose> groundtruth;
  bool has_masks = false;  ///< the frames carry ground-truth masks (left_mask)
  /// Left / right images without a partner within the pairing tolerance (not processed).
  std::size_t unpaired_cam0 = 0, unpaired_cam1 = 0;
  /// io::checkPlausible's warnings (the config's own are in Config::warnings).
  std::vector<std::string> warnings;
};

/// Opens `dataset` (a EuRoC folder or a ROS1 bag) for `config`. Masks are read when the
/// dataset has them and `masks` is true; config.mode seg without masks throws
/// InputError, as does anything the readers refuse or io::checkPlausible refuses.
Input openInput(const std::string& dataset, const Config& config, const std::string& groundtruth_topic,
                bool masks = true);

/// A reference trajectory: a TUM or EuRoC CSV file, or a EuRoC folder's ground truth
/// (mav0/state_groundtruth_estimate0/data.csv). Throws InputError.
std::vector<StampedPose> readReference(const std::string& path);

}  // namespace idyvins::app
