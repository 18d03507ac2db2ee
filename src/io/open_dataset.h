#pragma once
// Opening a dataset to drive the system with: a EuRoC folder or a ROS1 bag, detected, with its
// ground truth and (where present and wanted) ground-truth masks, checked against the rig it is
// opened for. What `idyvins run`, `track` and a library user open their data with.

#include <memory>
#include <string>
#include <vector>

#include "core/measurements.h"
#include "io/bag_dataset.h"
#include "io/data_source.h"
#include "io/dataset_summary.h"

namespace idyvins::io {

/// What opening a dataset reads beside the files themselves (pipeline::datasetRequest makes it
/// from a Config).
struct DatasetRequest {
  BagTopics topics;                       ///< bag only: the topics to read
  int image_width = 0, image_height = 0;  ///< expected image size (0: any)
  ExpectedRig rig;                        ///< what the streams are checked against (checkPlausible)
  bool masks = true;                      ///< read ground-truth masks where the dataset has them
  /// Bag only: VIODE's colour tables for the segmentation topic (readSegmentationColors).
  std::string segmentation_rgb_ids, segmentation_vehicle_ids;
};

/// An opened dataset and what it offers.
struct OpenedDataset {
  std::unique_ptr<DataSource> source;
  bool is_bag = false;
  std::string root;  ///< the folder read (a EuRoC folder's mav0/) or the bag
  std::vector<StampedPose> groundtruth;
  bool has_masks = false;  ///< the frames carry ground-truth masks (left_mask)
  /// Left / right images without a partner within the pairing tolerance (not processed).
  std::size_t unpaired_cam0 = 0, unpaired_cam1 = 0;
  /// checkPlausible's warnings, one line each.
  std::vector<std::string> warnings;
};

/// Opens `path` (a EuRoC folder or a ROS1 bag). Throws InputError for anything the readers or
/// checkPlausible refuse.
OpenedDataset openDataset(const std::string& path, const DatasetRequest& request);

/// A reference trajectory: a TUM or EuRoC CSV file, or a EuRoC folder's ground truth
/// (mav0/state_groundtruth_estimate0/data.csv). Throws InputError.
std::vector<StampedPose> readReference(const std::string& path);

}  // namespace idyvins::io
