#pragma once
// Writes a EuRoC folder as a ROS1 bag with VIODE's topics and message types
// (what `idyvins simulate --format bag` produces): /imu0 (sensor_msgs/Imu),
// /cam0/image_raw and /cam1/image_raw (sensor_msgs/Image, mono8), /odometry
// (nav_msgs/Odometry, from the ground truth) and, when the folder has masks,
// /cam0/segmentation (sensor_msgs/Image, rgb8, coloured with VIODE's tables).

#include <string>

#include "io/euroc_dataset.h"

namespace idyvins::io {

/// Options of writeViodeBag.
struct BagWriteOptions {
  std::string compression = "none";  ///< none | bz2 | lz4
  /// VIODE's rgb_ids.txt and vehicle_ids_<environment>.txt: mask id k (1..) is coloured
  /// as the k-th moving vehicle of the list (cyclically), 0 as the first id that is not
  /// a vehicle. Empty: no segmentation topic.
  std::string rgb_ids, vehicle_ids;
};

/// Writes `dataset` (read by readEurocDataset; masks from mav0/cam0/mask/) to `bag_path`.
/// Throws InputError on unreadable input or an unwritable output.
void writeViodeBag(const EurocDataset& dataset, const std::string& bag_path, const BagWriteOptions& options);

}  // namespace idyvins::io
