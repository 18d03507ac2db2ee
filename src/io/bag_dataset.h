#pragma once
// Bags as datasets (DESIGN §2: one time-ordered stream, wherever the data comes from): ROS1 bags
// (Debian's rosbag_storage and the ROS message definitions) and ROS 2 bags (MCAP or sqlite3, CDR),
// both without a ROS installation, master or environment, through one BagFile (bag_file.h).
// This header does not include ROS headers.
//
// A bag is indexed once (IMU samples, ground truth and the header stamps of every
// image are kept; image pixels are not), then streamed: images are decoded as the
// frames are consumed, so memory stays bounded by a few frames whatever the bag's size.

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

#include "io/bag_file.h"
#include "io/data_source.h"
#include "io/euroc_dataset.h"

namespace idyvins::io {

/// Topics to read (VINS-Fusion's config keys imu_topic, image0_topic, image1_topic;
/// groundtruth_topic is idyvins' own). Empty image1: monocular; empty groundtruth:
/// none. Ground truth may be nav_msgs/Odometry (VIODE: /odometry),
/// geometry_msgs/TransformStamped or PoseStamped (EuRoC Vicon rooms:
/// /vicon/firefly_sbx/firefly_sbx) or PointStamped (EuRoC Leica: /leica/position,
/// position only, identity orientation).
struct BagTopics {
  std::string imu = "/imu0";
  std::string image0 = "/cam0/image_raw";
  std::string image1 = "/cam1/image_raw";
  std::string groundtruth;
  /// Left-camera segmentation in colour (VIODE: /cam0/segmentation), empty = none;
  /// read only for masks (seg mode, classification metrics).
  std::string segmentation;
};

/// VIODE's segmentation colours: RGB -> object id (rgb_ids.txt), and which ids are
/// moving vehicles (vehicle_ids_*.txt, names containing "dynamic"). A moving vehicle's
/// mask value is 1 + its position in that list; every other colour is static (0).
struct SegmentationColors {
  std::unordered_map<std::uint32_t, std::uint8_t> label_of_rgb;  ///< (r << 16 | g << 8 | b) -> mask value
};

/// Reads rgb_ids.txt (`id,r,g,b`) and vehicle_ids_*.txt (`id, name`). Throws InputError
/// naming file and line.
SegmentationColors readSegmentationColors(const std::string& rgb_ids_path, const std::string& vehicle_ids_path);

/// The CV_8UC1 mask (moving-object labels, 0 = static) of a CV_8UC3 image in RGB order.
cv::Mat labelsFromColors(const cv::Mat& rgb, const SegmentationColors& colors);

/// A bag's index: every topic, and the streams of `topics` in the EuRoC dataset's
/// form (image records carry the message's header stamp; `path` names the bag and
/// topic, `csv_line` the message's position on its topic, 1-based).
struct BagIndex {
  std::string path;
  BagTopics topics;
  std::vector<BagTopicInfo> all_topics;
  EurocDataset dataset;
  std::vector<ImageRecord> segmentation;   ///< stamps of the segmentation topic (when named)
  std::vector<long> segmentation_of_pair;  ///< per pair: the segmentation image with cam0's stamp, -1 = none
  std::string format;                      ///< BagFile::format(): "ROS1 bag", "ROS 2 bag (mcap, chunks zstd)"
};

/// True when `path` names a bag of either format (bagFormat): a ROS1 bag file, a rosbag2 folder
/// (metadata.yaml), an .mcap or rosbag2 .db3 file; false for EuRoC folders and other files.
bool isBagFile(const std::string& path);

/// Indexes a bag: IMU (sensor_msgs/Imu), images (sensor_msgs/Image or
/// CompressedImage) and ground truth are read and validated (stamps strictly
/// increasing per topic, topics present with a supported type, encodings supported,
/// image sizes equal to expected_width x expected_height when those are > 0); stereo
/// pairs are formed by header stamp as for EuRoC folders. Throws InputError with
/// one clear line: a truncated or unindexed bag (`rosbag reindex`), a missing topic
/// (with the image and IMU topics the bag has), an unsupported message type or
/// encoding, a size mismatch, stamps going backwards, an empty bag.
BagIndex indexBag(const std::string& path, const BagTopics& topics, int expected_width = 0, int expected_height = 0,
                  const EurocOptions& options = {});

/// Streams an indexed bag: IMU samples and stereo frames in time order, as
/// EurocSource does for folders. Images are converted to 8-bit gray as OpenCV does
/// (cv::cvtColor for rgb8, bgr8, rgba8, bgra8; cv::imdecode for png and jpeg).
class BagSource : public DataSource {
 public:
  /// With `masks`, every frame's left_mask comes from the segmentation topic (an
  /// InputError for a frame without one).
  BagSource(BagIndex index, int expected_width, int expected_height,
            std::optional<SegmentationColors> masks = std::nullopt);
  ~BagSource() override;
  std::optional<Measurement> next() override;
  std::size_t frameCount() const override { return index_.dataset.pairs.size(); }
  const BagIndex& index() const { return index_; }

 private:
  struct Reader;  // the open bag and its view (ROS types stay in the .cpp)
  bool nextPairImages(cv::Mat& left, cv::Mat& right, cv::Mat& mask);
  void takeMessage();
  BagIndex index_;
  std::optional<SegmentationColors> masks_;
  int width_, height_;
  std::unique_ptr<Reader> reader_;
  std::size_t next_imu_ = 0, next_pair_ = 0;
};

}  // namespace idyvins::io
