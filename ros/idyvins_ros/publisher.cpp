#include "publisher.h"

#include <geometry_msgs/TransformStamped.h>
#include <nav_msgs/Odometry.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/PointCloud2.h>
#include <sensor_msgs/point_cloud2_iterator.h>
#include <std_msgs/Float64MultiArray.h>

#include <cstring>

#include "frontend/feature_tracker.h"

namespace idyvins::ros_node {
namespace {

ros::Time rosTime(TimeNs t_ns) {
  ros::Time t;
  t.fromNSec(static_cast<std::uint64_t>(t_ns));
  return t;
}

/// x, y, z (float32) and label (uint8: FeatureLabel) per point.
sensor_msgs::PointCloud2 cloud(const std::vector<backend::MapPoint>& points, const std::string& frame,
                               const ros::Time& stamp) {
  sensor_msgs::PointCloud2 msg;
  msg.header.stamp = stamp;
  msg.header.frame_id = frame;
  sensor_msgs::PointCloud2Modifier modifier(msg);
  modifier.setPointCloud2Fields(4, "x", 1, sensor_msgs::PointField::FLOAT32, "y", 1, sensor_msgs::PointField::FLOAT32,
                                "z", 1, sensor_msgs::PointField::FLOAT32, "label", 1, sensor_msgs::PointField::UINT8);
  modifier.resize(points.size());
  sensor_msgs::PointCloud2Iterator<float> x(msg, "x"), y(msg, "y"), z(msg, "z");
  sensor_msgs::PointCloud2Iterator<std::uint8_t> label(msg, "label");
  for (const auto& p : points) {
    *x = static_cast<float>(p.p_w.x());
    *y = static_cast<float>(p.p_w.y());
    *z = static_cast<float>(p.p_w.z());
    *label = static_cast<std::uint8_t>(p.label);
    ++x, ++y, ++z, ++label;
  }
  return msg;
}

}  // namespace

Publisher::Publisher(ros::NodeHandle& nh, const PublisherOptions& options, std::function<SteadyTime(TimeNs)> arrival,
                     LoopCorrection loop_correction)
    : options_(options), arrival_(std::move(arrival)), loop_correction_(std::move(loop_correction)) {
  if (loop_correction_) {
    odometry_loop_ = nh.advertise<nav_msgs::Odometry>("odometry_loop", 100);
    path_loop_ = nh.advertise<nav_msgs::Path>("path_loop", 10);
    map_static_loop_ = nh.advertise<sensor_msgs::PointCloud2>("map_static_loop", 2, /*latch=*/true);
    path_loop_msg_.header.frame_id = options_.world_frame;
  }
  odometry_ = nh.advertise<nav_msgs::Odometry>("odometry", 100);
  path_ = nh.advertise<nav_msgs::Path>("path", 10);
  map_static_ = nh.advertise<sensor_msgs::PointCloud2>("map_static", 2, /*latch=*/true);
  map_dynamic_ = nh.advertise<sensor_msgs::PointCloud2>("map_dynamic", 2, /*latch=*/true);
  image_ = nh.advertise<sensor_msgs::Image>("feature_image", 10);
  timing_ = nh.advertise<std_msgs::Float64MultiArray>("timing", 100);
  path_msg_.header.frame_id = options_.world_frame;
}

void Publisher::onFrame(const StereoFrame& input, const pipeline::FrameOutput& out) {
  const ros::Time stamp = rosTime(out.t_ns);
  if (out.estimate.initialized) publishPose(stamp, out.estimate.state);
  Eigen::Vector3d p_loop;
  Eigen::Quaterniond q_loop;
  if (out.estimate.initialized && loop_correction_ && loop_correction_(out.estimate.state, p_loop, q_loop))
    publishLoopPose(stamp, p_loop, q_loop);
  const double latency_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - arrival_(input.t_ns)).count();
  latencies_.push_back({input.t_ns, latency_ms});
  publishTiming(stamp, out, latency_ms);
  static_map_.insert(static_map_.end(), out.new_static_points.begin(), out.new_static_points.end());
  dynamic_map_.insert(dynamic_map_.end(), out.eliminated_points.begin(), out.eliminated_points.end());
  dynamic_map_.insert(dynamic_map_.end(), out.estimate.confirmed_points.begin(), out.estimate.confirmed_points.end());
  if (image_.getNumSubscribers() > 0) publishImage(input, out, stamp);
  ++frames_;
  if (options_.map_every_frames > 0 && frames_ % static_cast<std::size_t>(options_.map_every_frames) == 0)
    publishMaps(stamp);
}

std::array<double, 36> poseCovariance(const PublisherOptions& o, double path_m) {
  const double sp = o.position_sigma_m + o.drift_fraction * path_m;
  const double sr = o.orientation_sigma_rad + o.drift_rad_per_m * path_m;
  std::array<double, 36> c{};
  for (int k = 0; k < 6; ++k) c[static_cast<std::size_t>(7 * k)] = k < 3 ? sp * sp : sr * sr;
  return c;
}

void Publisher::publishPose(const ros::Time& stamp, const imu::NavState& s) {
  if (has_last_position_) path_m_ += (s.p_w_b - last_position_).norm();
  last_position_ = s.p_w_b;
  has_last_position_ = true;
  nav_msgs::Odometry odom;
  odom.header.stamp = stamp;
  odom.header.frame_id = options_.world_frame;
  odom.child_frame_id = options_.body_frame;
  odom.pose.pose.position.x = s.p_w_b.x();
  odom.pose.pose.position.y = s.p_w_b.y();
  odom.pose.pose.position.z = s.p_w_b.z();
  odom.pose.pose.orientation.w = s.q_w_b.w();
  odom.pose.pose.orientation.x = s.q_w_b.x();
  odom.pose.pose.orientation.y = s.q_w_b.y();
  odom.pose.pose.orientation.z = s.q_w_b.z();
  const Eigen::Vector3d v_b = s.q_w_b.conjugate() * s.v_w;  // REP 105: twist in the child frame
  odom.twist.twist.linear.x = v_b.x();
  odom.twist.twist.linear.y = v_b.y();
  odom.twist.twist.linear.z = v_b.z();
  const std::array<double, 36> pose_cov = poseCovariance(options_, path_m_);
  std::copy(pose_cov.begin(), pose_cov.end(), odom.pose.covariance.begin());
  for (int k = 0; k < 6; ++k) {
    odom.twist.covariance[static_cast<std::size_t>(7 * k)] =
        k < 3 ? options_.velocity_sigma_mps * options_.velocity_sigma_mps : kUnknownVariance;
  }
  odometry_.publish(odom);

  geometry_msgs::PoseStamped pose;
  pose.header = odom.header;
  pose.pose = odom.pose.pose;
  path_msg_.header.stamp = stamp;
  path_msg_.poses.push_back(pose);
  path_.publish(path_msg_);

  geometry_msgs::TransformStamped tf;
  tf.header = odom.header;
  tf.child_frame_id = options_.body_frame;
  tf.transform.translation.x = s.p_w_b.x();
  tf.transform.translation.y = s.p_w_b.y();
  tf.transform.translation.z = s.p_w_b.z();
  tf.transform.rotation = odom.pose.pose.orientation;
  tf_.sendTransform(tf);
}

void Publisher::publishLoopPose(const ros::Time& stamp, const Eigen::Vector3d& p, const Eigen::Quaterniond& q) {
  geometry_msgs::PoseStamped pose;
  pose.header.stamp = stamp;
  pose.header.frame_id = options_.world_frame;
  pose.pose.position.x = p.x();
  pose.pose.position.y = p.y();
  pose.pose.position.z = p.z();
  pose.pose.orientation.w = q.w();
  pose.pose.orientation.x = q.x();
  pose.pose.orientation.y = q.y();
  pose.pose.orientation.z = q.z();
  nav_msgs::Odometry odom;
  odom.header = pose.header;
  odom.child_frame_id = options_.body_frame;
  odom.pose.pose = pose.pose;
  const std::array<double, 36> pose_cov = poseCovariance(options_, path_m_);  // loops bound it: the same model
  std::copy(pose_cov.begin(), pose_cov.end(), odom.pose.covariance.begin());
  for (int k = 0; k < 6; ++k) odom.twist.covariance[static_cast<std::size_t>(7 * k)] = kUnknownVariance;  // no twist
  odometry_loop_.publish(odom);
  path_loop_msg_.header.stamp = stamp;
  path_loop_msg_.poses.push_back(pose);
  path_loop_.publish(path_loop_msg_);
}

void Publisher::publishImage(const StereoFrame& input, const pipeline::FrameOutput& out, const ros::Time& stamp) {
  const cv::Mat drawn = frontend::drawTracks(input.left, out.features);  // BGR, colours by label
  sensor_msgs::Image img;
  img.header.stamp = stamp;
  img.header.frame_id = "cam0";
  img.height = static_cast<std::uint32_t>(drawn.rows);
  img.width = static_cast<std::uint32_t>(drawn.cols);
  img.encoding = "bgr8";
  img.step = static_cast<std::uint32_t>(drawn.cols * 3);
  img.data.resize(static_cast<std::size_t>(img.step) * img.height);
  for (int r = 0; r < drawn.rows; ++r)
    std::memcpy(&img.data[static_cast<std::size_t>(r) * img.step], drawn.ptr(r), img.step);
  image_.publish(img);
}

void Publisher::publishTiming(const ros::Time& stamp, const pipeline::FrameOutput& out, double latency_ms) {
  std_msgs::Float64MultiArray msg;
  msg.layout.dim.resize(1);
  msg.layout.dim[0].label = "stamp_s,latency_ms,tracking_ms,filter_ms,optimization_ms,marginalization_ms,initialized";
  msg.layout.dim[0].size = 7;
  msg.layout.dim[0].stride = 7;
  msg.data = {stamp.toSec(),
              latency_ms,
              out.features.tracking_ms,
              out.features.filter_ms,
              out.estimate.optimization_ms,
              out.estimate.marginalization_ms,
              out.estimate.initialized ? 1.0 : 0.0};
  timing_.publish(msg);
}

void Publisher::publishMaps(const ros::Time& stamp) {
  map_static_.publish(cloud(static_map_, options_.world_frame, stamp));
  map_dynamic_.publish(cloud(dynamic_map_, options_.world_frame, stamp));
}

void Publisher::publishFinalMaps(const pipeline::Result& result) {
  const ros::Time stamp = rosTime(result.summary.last_t_ns);
  static_map_ = result.static_map;
  dynamic_map_ = result.dynamic_map;
  publishMaps(stamp);
  if (!loop_correction_ || !result.loop_enabled) return;
  map_static_loop_.publish(cloud(result.loop_static_map, options_.world_frame, stamp));
  if (result.loop_stats.map_keyframes > 0 && !result.loop_stats.relocalized) return;  // no map frame
  path_loop_msg_.poses.clear();
  for (const StampedPose& s : result.loop_trajectory) {
    geometry_msgs::PoseStamped pose;
    pose.header.stamp = rosTime(s.t_ns);
    pose.header.frame_id = options_.world_frame;
    pose.pose.position.x = s.p_w_b.x();
    pose.pose.position.y = s.p_w_b.y();
    pose.pose.position.z = s.p_w_b.z();
    pose.pose.orientation.w = s.q_w_b.w();
    pose.pose.orientation.x = s.q_w_b.x();
    pose.pose.orientation.y = s.q_w_b.y();
    pose.pose.orientation.z = s.q_w_b.z();
    path_loop_msg_.poses.push_back(pose);
  }
  path_loop_msg_.header.stamp = stamp;
  path_loop_.publish(path_loop_msg_);
}

}  // namespace idyvins::ros_node
