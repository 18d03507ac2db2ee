#include "io/bag_file.h"

#include <cstring>
#include <filesystem>
#include <fstream>

#include "core/error.h"

namespace idyvins::io {

namespace {
struct KindName {
  BagMessageKind kind;
  const char* ros1;
  const char* ros2;
};
constexpr KindName kKinds[] = {
    {BagMessageKind::kImage, "sensor_msgs/Image", "sensor_msgs/msg/Image"},
    {BagMessageKind::kCompressedImage, "sensor_msgs/CompressedImage", "sensor_msgs/msg/CompressedImage"},
    {BagMessageKind::kImu, "sensor_msgs/Imu", "sensor_msgs/msg/Imu"},
    {BagMessageKind::kOdometry, "nav_msgs/Odometry", "nav_msgs/msg/Odometry"},
    {BagMessageKind::kTransform, "geometry_msgs/TransformStamped", "geometry_msgs/msg/TransformStamped"},
    {BagMessageKind::kPose, "geometry_msgs/PoseStamped", "geometry_msgs/msg/PoseStamped"},
    {BagMessageKind::kPoint, "geometry_msgs/PointStamped", "geometry_msgs/msg/PointStamped"},
};

/// The first `n` bytes of a regular file ("" when shorter or not a file).
std::string head(const std::string& path, std::size_t n) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) return {};
  std::ifstream in(path, std::ios::binary);
  std::string b(n, '\0');
  in.read(b.data(), static_cast<std::streamsize>(n));
  return in.gcount() == static_cast<std::streamsize>(n) ? b : std::string();
}
}  // namespace

BagMessageKind messageKind(const std::string& type) {
  for (const KindName& k : kKinds)
    if (type == k.ros1 || type == k.ros2) return k.kind;
  return BagMessageKind::kOther;
}

const char* kindName(BagMessageKind kind) {
  for (const KindName& k : kKinds)
    if (k.kind == kind) return k.ros1;
  return "";
}

BagFormat bagFormat(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (fs::is_directory(path, ec))
    return fs::is_regular_file(fs::path(path) / "metadata.yaml", ec) ? BagFormat::kRos2 : BagFormat::kNone;
  if (head(path, 13) == "#ROSBAG V2.0\n") return BagFormat::kRos1;
  if (head(path, 8) == std::string("\x89MCAP0\r\n", 8)) return BagFormat::kRos2;
  if (head(path, 16) == std::string("SQLite format 3\0", 16)) return BagFormat::kRos2;
  return BagFormat::kNone;
}

std::unique_ptr<BagFile> openBagFile(const std::string& path) {
  switch (bagFormat(path)) {
    case BagFormat::kRos1:
      return openRos1Bag(path);
    case BagFormat::kRos2:
      return openRos2Bag(path);
    case BagFormat::kNone:
      break;
  }
  throw InputError(path,
                   "not a bag: expected a ROS1 bag ('#ROSBAG V2.0'), a ROS 2 bag folder (metadata.yaml), an .mcap or "
                   "a rosbag2 .db3 file");
}

}  // namespace idyvins::io
