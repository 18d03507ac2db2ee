#pragma once
// What idyvins_ros publishes for each frame the system finishes (a pipeline::FrameObserver):
// odometry, path and TF, the static and dynamic maps, the labelled feature image and the
// frame's timing. Topic names and types: docs/ros.md.

#include <nav_msgs/Path.h>
#include <ros/ros.h>
#include <tf2_ros/transform_broadcaster.h>

#include <array>
#include <chrono>
#include <functional>
#include <string>
#include <vector>

#include "pipeline/system.h"

namespace idyvins::ros_node {

using SteadyTime = std::chrono::steady_clock::time_point;

struct PublisherOptions {
  std::string world_frame = "world";
  std::string body_frame = "body";
  int map_every_frames = 10;  ///< the map clouds are published every this many frames (and at the end)
  /// The odometry's covariance, a documented model (not the window's marginal): position sigma
  /// position_sigma_m + drift_fraction x the path travelled so far (odometry drifts with the
  /// distance), orientation sigma orientation_sigma_rad + drift_rad_per_m x path, velocity sigma
  /// velocity_sigma_mps (diagonal, REP 103 axes); the twist's angular part is not published: its
  /// variance is kUnknownVariance.
  double position_sigma_m = 0.02, drift_fraction = 0.01;
  double orientation_sigma_rad = 0.005, drift_rad_per_m = 1e-4;
  double velocity_sigma_mps = 0.05;
};

/// The odometry's 6x6 pose covariance (row-major; x, y, z, then rotation about x, y, z) after
/// `path_m` metres, as PublisherOptions says.
std::array<double, 36> poseCovariance(const PublisherOptions& o, double path_m);

/// The variance of what the odometry does not estimate (the twist's angular rate, published as 0).
constexpr double kUnknownVariance = 1e6;

/// The loop closer's live correction of an odometry pose (pipeline::System::loopCorrected).
using LoopCorrection = std::function<bool(const imu::NavState&, Eigen::Vector3d&, Eigen::Quaterniond&)>;

/// Per-frame latency: from the arrival of the frame's second image to its odometry.
struct LatencyRecord {
  TimeNs t_ns = 0;
  double latency_ms = 0;
};

class Publisher final : public pipeline::FrameObserver {
 public:
  /// `arrival(t_ns)` gives when the frame with image stamp t_ns arrived (steady clock).
  /// `loop_correction` (loop closure on): also odometry_loop, path_loop and map_static_loop.
  Publisher(ros::NodeHandle& nh, const PublisherOptions& options, std::function<SteadyTime(TimeNs)> arrival,
            LoopCorrection loop_correction = {});
  void onFrame(const StereoFrame& input, const pipeline::FrameOutput& out) override;
  /// The complete maps of finish() (latched topics); with loop closure, path_loop is replaced by
  /// the final pose graph's trajectory and map_static_loop published.
  void publishFinalMaps(const pipeline::Result& result);
  const std::vector<LatencyRecord>& latencies() const { return latencies_; }
  std::size_t published() const { return frames_; }

 private:
  void publishPose(const ros::Time& stamp, const imu::NavState& s);
  void publishLoopPose(const ros::Time& stamp, const Eigen::Vector3d& p, const Eigen::Quaterniond& q);
  void publishImage(const StereoFrame& input, const pipeline::FrameOutput& out, const ros::Time& stamp);
  void publishTiming(const ros::Time& stamp, const pipeline::FrameOutput& out, double latency_ms);
  void publishMaps(const ros::Time& stamp);

  PublisherOptions options_;
  double path_m_ = 0;  ///< the odometry's path so far (its covariance grows with it)
  Eigen::Vector3d last_position_ = Eigen::Vector3d::Zero();
  bool has_last_position_ = false;
  std::function<SteadyTime(TimeNs)> arrival_;
  LoopCorrection loop_correction_;
  ros::Publisher odometry_, path_, map_static_, map_dynamic_, image_, timing_;
  ros::Publisher odometry_loop_, path_loop_, map_static_loop_;
  nav_msgs::Path path_loop_msg_;
  tf2_ros::TransformBroadcaster tf_;
  nav_msgs::Path path_msg_;
  std::vector<backend::MapPoint> static_map_, dynamic_map_;
  std::vector<LatencyRecord> latencies_;
  std::size_t frames_ = 0;
};

}  // namespace idyvins::ros_node
