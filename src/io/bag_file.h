#pragma once
// One opened bag, whatever its format (a ROS1 bag, a ROS 2 bag in MCAP or sqlite3): its topics,
// and a cursor over the messages of some of them in the file's order, each read as one of the
// message types idyvins takes (images, IMU, ground truth). The dataset reader (bag_dataset.h)
// sits on this and never sees a format.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/measurements.h"

namespace idyvins::io {

/// One topic of a bag, as its index lists it (type in the bag's own spelling:
/// sensor_msgs/Image in ROS1, sensor_msgs/msg/Image in ROS 2).
struct BagTopicInfo {
  std::string topic, type;
  std::size_t count = 0;
};

/// The message types idyvins reads.
enum class BagMessageKind { kImage, kCompressedImage, kImu, kOdometry, kTransform, kPose, kPoint, kOther };

/// The kind of a type name in either spelling ("sensor_msgs/Image", "sensor_msgs/msg/Image").
BagMessageKind messageKind(const std::string& type);

/// The ROS1 spelling of a kind ("sensor_msgs/Image"); "" for kOther.
const char* kindName(BagMessageKind kind);

/// A sensor_msgs/Image or CompressedImage; `data` points into the cursor's current message and
/// is valid until its next().
struct BagImage {
  TimeNs stamp_ns = 0;
  bool compressed = false;
  std::string encoding;  ///< Image
  std::uint32_t width = 0, height = 0, step = 0;
  std::string format;  ///< CompressedImage
  const std::uint8_t* data = nullptr;
  std::size_t size = 0;
};

/// A stamped pose of any ground-truth type (a point has the identity orientation).
struct BagPose {
  TimeNs stamp_ns = 0;
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();  ///< as stored (not normalized)
};

/// A message that does not read as its type (the reader adds file, topic and ordinal).
class BagMessageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Messages of some topics in the file's order (per topic: the order of recording).
class BagCursor {
 public:
  virtual ~BagCursor() = default;
  /// Moves to the next message; false at the end. Throws InputError for a damaged file.
  virtual bool next() = 0;
  /// The current message's topic.
  virtual const std::string& topic() const = 0;
  /// The current message as an image of `kind` (kImage or kCompressedImage). Throws BagMessageError.
  virtual BagImage image(BagMessageKind kind) = 0;
  /// The current message as sensor_msgs/Imu (t_ns from its header). Throws BagMessageError.
  virtual ImuSample imu() = 0;
  /// The current message as a ground-truth type (kOdometry, kTransform, kPose, kPoint). Throws BagMessageError.
  virtual BagPose pose(BagMessageKind kind) = 0;
};

/// An opened bag.
class BagFile {
 public:
  virtual ~BagFile() = default;
  /// Every topic, in name order.
  virtual const std::vector<BagTopicInfo>& topics() const = 0;
  /// A cursor over the messages of `topics`.
  virtual std::unique_ptr<BagCursor> read(const std::vector<std::string>& topics) = 0;
  /// What the file is: "ROS1 bag", "ROS 2 bag (mcap, zstd chunks)", ...
  virtual std::string format() const = 0;
};

/// The bag formats `openBagFile` tells apart.
enum class BagFormat { kNone, kRos1, kRos2 };

/// What `path` is: a ROS1 bag file ("#ROSBAG V2.0"), a ROS 2 bag (a folder with metadata.yaml, an
/// .mcap file, a rosbag2 .db3 file) or neither.
BagFormat bagFormat(const std::string& path);

/// Opens a bag of either format. Throws InputError: a damaged file (with its byte offset where
/// the format has one), a format this build does not read.
std::unique_ptr<BagFile> openBagFile(const std::string& path);

/// A ROS1 bag (Debian's rosbag_storage).
std::unique_ptr<BagFile> openRos1Bag(const std::string& path);

/// A ROS 2 bag: a rosbag2 folder (metadata.yaml and its .mcap or .db3 files) or one .mcap or .db3 file.
std::unique_ptr<BagFile> openRos2Bag(const std::string& path);

}  // namespace idyvins::io
