// ROS1 bags through Debian's rosbag_storage and the ROS message definitions (no ROS installation,
// master or environment), behind BagFile.

#include <geometry_msgs/PointStamped.h>
#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/TransformStamped.h>
#include <nav_msgs/Odometry.h>
#include <rosbag/bag.h>
#include <rosbag/exceptions.h>
#include <rosbag/view.h>
#include <sensor_msgs/CompressedImage.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/Imu.h>

#include <filesystem>
#include <fstream>
#include <map>

#include "core/error.h"
#include "io/bag_file.h"
#include "io/bag_structure.h"

namespace idyvins::io {
namespace {

TimeNs stampNs(const ros::Time& t) { return static_cast<TimeNs>(t.sec) * 1'000'000'000 + t.nsec; }

void openChecked(rosbag::Bag& bag, const std::string& path) {
  if (!std::filesystem::is_regular_file(path)) throw InputError(path, "no such bag file");
  {  // rosbag_storage trusts the lengths in the file: check them first
    std::ifstream in(path, std::ios::binary);
    std::error_code ec;
    const auto size = std::filesystem::file_size(path, ec);
    if (!in || ec) throw InputError(path, "cannot open");
    if (const auto problem = bagStructureProblem(in, size))
      throw InputError(path, "not a readable ROS1 bag (truncated or damaged?): " + *problem);
  }
  try {
    bag.open(path, rosbag::bagmode::Read);
  } catch (const rosbag::BagUnindexedException&) {
    throw InputError(path, "the bag has no index (recording interrupted?): run `rosbag reindex` on it first");
  } catch (const rosbag::BagException& e) {
    throw InputError(path, std::string("not a readable ROS1 bag (truncated or damaged?): ") + e.what());
  }
}

template <typename Msg>
boost::shared_ptr<Msg> as(const rosbag::MessageInstance& m, BagMessageKind kind) {
  auto msg = m.instantiate<Msg>();
  if (!msg) throw BagMessageError(std::string("cannot be read as ") + kindName(kind));
  return msg;
}

BagPose poseOf(TimeNs t, double px, double py, double pz, double qw, double qx, double qy, double qz) {
  BagPose p;
  p.stamp_ns = t;
  p.p = {px, py, pz};
  p.q = Eigen::Quaterniond(qw, qx, qy, qz);
  return p;
}

class Ros1Cursor : public BagCursor {
 public:
  Ros1Cursor(const rosbag::Bag& bag, const std::string& path, const std::vector<std::string>& topics)
      : path_(path), view_(bag, rosbag::TopicQuery(topics)), it_(view_.begin()) {}

  bool next() override {
    try {
      if (started_) ++it_;
      started_ = true;
      if (it_ == view_.end()) return false;
      topic_ = it_->getTopic();
      return true;
    } catch (const rosbag::BagException& e) {
      throw InputError(path_, std::string("reading the bag failed (truncated or damaged?): ") + e.what());
    }
  }
  const std::string& topic() const override { return topic_; }

  BagImage image(BagMessageKind kind) override {
    BagImage out;
    if (kind == BagMessageKind::kImage) {
      image_ = as<sensor_msgs::Image>(*it_, kind);
      out.stamp_ns = stampNs(image_->header.stamp);
      out.encoding = image_->encoding;
      out.width = image_->width;
      out.height = image_->height;
      out.step = image_->step;
      out.data = image_->data.data();
      out.size = image_->data.size();
    } else {
      compressed_ = as<sensor_msgs::CompressedImage>(*it_, kind);
      out.compressed = true;
      out.stamp_ns = stampNs(compressed_->header.stamp);
      out.format = compressed_->format;
      out.data = compressed_->data.data();
      out.size = compressed_->data.size();
    }
    return out;
  }

  ImuSample imu() override {
    const auto msg = as<sensor_msgs::Imu>(*it_, BagMessageKind::kImu);
    ImuSample s;
    s.t_ns = stampNs(msg->header.stamp);
    s.gyr_b = {msg->angular_velocity.x, msg->angular_velocity.y, msg->angular_velocity.z};
    s.acc_b = {msg->linear_acceleration.x, msg->linear_acceleration.y, msg->linear_acceleration.z};
    return s;
  }

  BagPose pose(BagMessageKind kind) override {
    if (kind == BagMessageKind::kOdometry) {
      const auto o = as<nav_msgs::Odometry>(*it_, kind);
      const auto& p = o->pose.pose;
      return poseOf(stampNs(o->header.stamp), p.position.x, p.position.y, p.position.z, p.orientation.w,
                    p.orientation.x, p.orientation.y, p.orientation.z);
    }
    if (kind == BagMessageKind::kTransform) {
      const auto o = as<geometry_msgs::TransformStamped>(*it_, kind);
      const auto& tr = o->transform;
      return poseOf(stampNs(o->header.stamp), tr.translation.x, tr.translation.y, tr.translation.z, tr.rotation.w,
                    tr.rotation.x, tr.rotation.y, tr.rotation.z);
    }
    if (kind == BagMessageKind::kPose) {
      const auto o = as<geometry_msgs::PoseStamped>(*it_, kind);
      const auto& p = o->pose;
      return poseOf(stampNs(o->header.stamp), p.position.x, p.position.y, p.position.z, p.orientation.w,
                    p.orientation.x, p.orientation.y, p.orientation.z);
    }
    const auto o = as<geometry_msgs::PointStamped>(*it_, BagMessageKind::kPoint);
    return poseOf(stampNs(o->header.stamp), o->point.x, o->point.y, o->point.z, 1, 0, 0, 0);
  }

 private:
  std::string path_, topic_;
  rosbag::View view_;
  rosbag::View::iterator it_;
  bool started_ = false;
  boost::shared_ptr<sensor_msgs::Image> image_;  // the current image, alive until the next one
  boost::shared_ptr<sensor_msgs::CompressedImage> compressed_;
};

class Ros1Bag : public BagFile {
 public:
  explicit Ros1Bag(const std::string& path) : path_(path) {
    openChecked(bag_, path);
    try {
      rosbag::View all(bag_);
      std::map<std::string, std::string> types;
      for (const rosbag::ConnectionInfo* c : all.getConnections()) types[c->topic] = c->datatype;
      for (const auto& [topic, type] : types) {
        rosbag::View v(bag_, rosbag::TopicQuery(topic));
        topics_.push_back({topic, type, v.size()});
      }
    } catch (const rosbag::BagException& e) {
      throw InputError(path, std::string("reading the bag failed (truncated or damaged?): ") + e.what());
    }
  }
  const std::vector<BagTopicInfo>& topics() const override { return topics_; }
  std::unique_ptr<BagCursor> read(const std::vector<std::string>& topics) override {
    return std::make_unique<Ros1Cursor>(bag_, path_, topics);
  }
  std::string format() const override { return "ROS1 bag"; }

 private:
  std::string path_;
  rosbag::Bag bag_;
  std::vector<BagTopicInfo> topics_;
};

}  // namespace

std::unique_ptr<BagFile> openRos1Bag(const std::string& path) { return std::make_unique<Ros1Bag>(path); }

}  // namespace idyvins::io
