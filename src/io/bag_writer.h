#pragma once
// Writes a EuRoC folder as a ROS1 bag or a ROS 2 bag (a rosbag2 folder: metadata.yaml and one
// .mcap) with VIODE's topics and message types (what `idyvins simulate --format bag` and
// `--format mcap` produce): /imu0 (sensor_msgs/Imu),
// /cam0/image_raw and /cam1/image_raw (sensor_msgs/Image, mono8), /odometry
// (nav_msgs/Odometry, from the ground truth) and, when the folder has masks,
// /cam0/segmentation (sensor_msgs/Image, rgb8, coloured with VIODE's tables).

#include <opencv2/core.hpp>
#include <string>

#include "io/euroc_dataset.h"

namespace idyvins::io {

/// Options of writeViodeBag.
struct BagWriteOptions {
  std::string format = "ros1";       ///< ros1 (a .bag) | mcap (a rosbag2 folder)
  std::string compression = "none";  ///< ros1: none | bz2 | lz4; mcap (chunks): none | zstd | lz4
  /// VIODE's rgb_ids.txt and vehicle_ids_<environment>.txt: mask id k (1..) is coloured
  /// as the k-th moving vehicle of the list (cyclically), 0 as the first id that is not
  /// a vehicle. Empty: no segmentation topic.
  std::string rgb_ids, vehicle_ids;
};

/// Writes `dataset` (read by readEurocDataset; masks from mav0/cam0/mask/) to `bag_path` (for mcap:
/// the folder to create). Throws InputError on unreadable input or an unwritable output.
void writeViodeBag(const EurocDataset& dataset, const std::string& bag_path, const BagWriteOptions& options);

/// Where writeViode puts the messages, in time order.
class ViodeSink {
 public:
  virtual ~ViodeSink() = default;
  virtual void imu(const ImuSample& s) = 0;
  virtual void odometry(const GroundTruthState& g) = 0;
  /// A mono8 (CV_8UC1) or rgb8 (CV_8UC3, RGB order) image.
  virtual void image(const std::string& topic, const cv::Mat& image, TimeNs t, const std::string& frame_id) = 0;
  virtual void close() = 0;
};

/// The messages of `dataset` into `sink` (the segmentation topic when `rgb_ids` is set).
void writeViode(const EurocDataset& dataset, ViodeSink& sink, const std::string& rgb_ids,
                const std::string& vehicle_ids);

/// The ROS 2 form of writeViodeBag: `folder`/metadata.yaml and `folder`/<name>_0.mcap.
void writeViodeRos2(const EurocDataset& dataset, const std::string& folder, const BagWriteOptions& options);

}  // namespace idyvins::io
