#pragma once
// The ROS 2 messages idyvins reads and writes, in CDR: sensor_msgs/msg/Image, CompressedImage and
// Imu, nav_msgs/msg/Odometry, geometry_msgs/msg/TransformStamped, PoseStamped and PointStamped.
// Pure functions over bytes (no files), and the message definitions an MCAP schema carries.

#include <cstdint>
#include <string>
#include <vector>

#include "io/bag_file.h"

namespace idyvins::io {

/// An Image (kImage) or CompressedImage; `data` points into `cdr`. Throws BagMessageError.
BagImage decodeRos2Image(const std::uint8_t* cdr, std::size_t size, BagMessageKind kind);
/// An Imu. Throws BagMessageError.
ImuSample decodeRos2Imu(const std::uint8_t* cdr, std::size_t size);
/// Odometry, TransformStamped, PoseStamped or PointStamped (`kind`). Throws BagMessageError.
BagPose decodeRos2Pose(const std::uint8_t* cdr, std::size_t size, BagMessageKind kind);

/// A mono8 / rgb8 Image of `height` rows of `step` bytes.
std::vector<std::uint8_t> encodeRos2Image(TimeNs t, const std::string& frame_id, std::uint32_t width,
                                          std::uint32_t height, const std::string& encoding, std::uint32_t step,
                                          const std::uint8_t* data);
/// An Imu without orientation (orientation_covariance[0] = -1, as REP 145 says).
std::vector<std::uint8_t> encodeRos2Imu(const ImuSample& s, const std::string& frame_id);
/// An Odometry with the pose (T_w_b) and zero twist.
std::vector<std::uint8_t> encodeRos2Odometry(TimeNs t, const std::string& frame_id, const std::string& child_frame_id,
                                             const Eigen::Vector3d& p, const Eigen::Quaterniond& q);

/// The ros2msg definition of `type` (sensor_msgs/msg/Image, sensor_msgs/msg/Imu, nav_msgs/msg/Odometry)
/// with its dependencies, as ROS 2's MCAP writer stores it.
std::string ros2MessageDefinition(const std::string& type);

}  // namespace idyvins::io
