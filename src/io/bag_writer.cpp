#include "io/bag_writer.h"

#include <nav_msgs/Odometry.h>
#include <rosbag/bag.h>
#include <rosbag/exceptions.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/Imu.h>

#include <algorithm>
#include <array>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <set>
#include <sstream>

#include "core/error.h"

namespace idyvins::io {

namespace {

ros::Time rosTime(TimeNs t) {
  return ros::Time(static_cast<std::uint32_t>(t / 1'000'000'000), static_cast<std::uint32_t>(t % 1'000'000'000));
}

/// Lines of a small table file after its header, split at commas (spaces dropped).
std::vector<std::vector<std::string>> tableRows(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path, "cannot open");
  std::vector<std::vector<std::string>> rows;
  std::string line;
  std::getline(in, line);  // header
  while (std::getline(in, line)) {
    std::vector<std::string> cells{""};
    for (char c : line) {
      if (c == ',')
        cells.emplace_back();
      else if (c != ' ' && c != '\t' && c != '\r')
        cells.back() += c;
    }
    if (!(cells.size() == 1 && cells[0].empty())) rows.push_back(cells);
  }
  return rows;
}

/// Colour (RGB) of each mask id: 0 -> a non-vehicle id's colour, k -> the ((k-1) mod n)-th moving vehicle's.
std::array<cv::Vec3b, 256> maskColours(const std::string& rgb_ids, const std::string& vehicle_ids) {
  std::map<int, cv::Vec3b> colour_of_id;
  for (const auto& r : tableRows(rgb_ids)) {
    if (r.size() != 4) throw InputError(rgb_ids, "expected rows 'id,r,g,b'");
    colour_of_id[std::stoi(r[0])] = cv::Vec3b(static_cast<uchar>(std::stoi(r[1])), static_cast<uchar>(std::stoi(r[2])),
                                              static_cast<uchar>(std::stoi(r[3])));
  }
  std::vector<int> moving;
  std::set<int> vehicles;
  for (const auto& r : tableRows(vehicle_ids)) {
    if (r.size() != 2) throw InputError(vehicle_ids, "expected rows 'id, name'");
    vehicles.insert(std::stoi(r[0]));
    if (r[1].find("dynamic") != std::string::npos) moving.push_back(std::stoi(r[0]));
  }
  if (moving.empty()) throw InputError(vehicle_ids, "lists no moving (dynamic) vehicle");
  int background = -1;
  for (const auto& [id, c] : colour_of_id)
    if (!vehicles.count(id)) {
      background = id;
      break;
    }
  std::array<cv::Vec3b, 256> colours;
  if (background < 0) throw InputError(rgb_ids, "every id is a vehicle: no colour left for the static scene");
  colours[0] = colour_of_id.at(background);
  for (int k = 1; k < 256; ++k) {
    const int id = moving[static_cast<std::size_t>(k - 1) % moving.size()];
    if (!colour_of_id.count(id)) throw InputError(rgb_ids, "has no colour for vehicle id " + std::to_string(id));
    colours[k] = colour_of_id.at(id);
  }
  return colours;
}

sensor_msgs::Image imageMsg(const cv::Mat& image, TimeNs t, const std::string& frame_id) {
  sensor_msgs::Image m;
  m.header.stamp = rosTime(t);
  m.header.frame_id = frame_id;
  m.height = static_cast<std::uint32_t>(image.rows);
  m.width = static_cast<std::uint32_t>(image.cols);
  m.encoding = image.channels() == 1 ? "mono8" : "rgb8";
  m.step = static_cast<std::uint32_t>(image.cols * image.channels());
  m.data.resize(static_cast<std::size_t>(m.step) * m.height);
  for (int y = 0; y < image.rows; ++y)
    std::copy(image.ptr<uchar>(y), image.ptr<uchar>(y) + m.step,
              m.data.begin() + static_cast<std::ptrdiff_t>(y) * m.step);
  return m;
}

sensor_msgs::Imu imuMsg(const ImuSample& s) {
  sensor_msgs::Imu m;
  m.header.stamp = rosTime(s.t_ns);
  m.header.frame_id = "imu";
  m.angular_velocity.x = s.gyr_b.x();
  m.angular_velocity.y = s.gyr_b.y();
  m.angular_velocity.z = s.gyr_b.z();
  m.linear_acceleration.x = s.acc_b.x();
  m.linear_acceleration.y = s.acc_b.y();
  m.linear_acceleration.z = s.acc_b.z();
  m.orientation_covariance[0] = -1;  // no orientation
  return m;
}

nav_msgs::Odometry odometryMsg(const GroundTruthState& g) {
  nav_msgs::Odometry m;
  m.header.stamp = rosTime(g.t_ns);
  m.header.frame_id = "world";
  m.child_frame_id = "body";
  m.pose.pose.position.x = g.p_w_b.x();
  m.pose.pose.position.y = g.p_w_b.y();
  m.pose.pose.position.z = g.p_w_b.z();
  m.pose.pose.orientation.w = g.q_w_b.w();
  m.pose.pose.orientation.x = g.q_w_b.x();
  m.pose.pose.orientation.y = g.q_w_b.y();
  m.pose.pose.orientation.z = g.q_w_b.z();
  m.twist.twist.linear.x = g.v_w.x();
  m.twist.twist.linear.y = g.v_w.y();
  m.twist.twist.linear.z = g.v_w.z();
  return m;
}

/// The segmentation image of a left frame (its mask/ PNG of object ids) in VIODE's colours.
cv::Mat segmentationRgb(const EurocDataset& ds, const StereoPair& p, const std::string& csv0, const cv::Size& size,
                        const std::array<cv::Vec3b, 256>& colours) {
  const std::filesystem::path image(ds.cam0[p.i0].path);
  ImageRecord mask_record = ds.cam0[p.i0];
  mask_record.path = (image.parent_path().parent_path() / "mask" / image.filename()).string();
  const cv::Mat ids = loadGrayImage(mask_record, csv0, size.width, size.height);
  cv::Mat rgb(ids.size(), CV_8UC3);
  for (int y = 0; y < ids.rows; ++y)
    for (int x = 0; x < ids.cols; ++x) rgb.at<cv::Vec3b>(y, x) = colours[ids.at<uchar>(y, x)];
  return rgb;
}

/// The ROS1 bag's messages (rosbag_storage).
class Ros1Sink : public ViodeSink {
 public:
  Ros1Sink(const std::string& path, const std::string& compression) : path_(path) {
    try {
      bag_.open(path, rosbag::bagmode::Write);
    } catch (const rosbag::BagException& e) {
      throw InputError(path, std::string("cannot write the bag: ") + e.what());
    }
    if (compression == "bz2")
      bag_.setCompression(rosbag::compression::BZ2);
    else if (compression == "lz4")
      bag_.setCompression(rosbag::compression::LZ4);
    else if (compression != "none")
      throw InputError(path, "unknown compression '" + compression + "' (none, bz2, lz4)");
  }
  void imu(const ImuSample& s) override {
    guarded([&] { bag_.write("/imu0", rosTime(s.t_ns), imuMsg(s)); });
  }
  void odometry(const GroundTruthState& g) override {
    guarded([&] { bag_.write("/odometry", rosTime(g.t_ns), odometryMsg(g)); });
  }
  void image(const std::string& topic, const cv::Mat& image, TimeNs t, const std::string& frame_id) override {
    guarded([&] { bag_.write(topic, rosTime(t), imageMsg(image, t, frame_id)); });
  }
  void close() override {
    guarded([&] { bag_.close(); });
  }

 private:
  template <typename F>
  void guarded(F f) {
    try {
      f();
    } catch (const rosbag::BagException& e) {
      throw InputError(path_, std::string("cannot write the bag: ") + e.what());
    }
  }
  std::string path_;
  rosbag::Bag bag_;
};

}  // namespace

void writeViode(const EurocDataset& ds, ViodeSink& sink, const std::string& rgb_ids, const std::string& vehicle_ids) {
  const bool segmentation = !rgb_ids.empty();
  std::array<cv::Vec3b, 256> colours{};
  if (segmentation) colours = maskColours(rgb_ids, vehicle_ids);
  // Messages in time order: IMU and ground truth with a stamp up to a frame's come first.
  std::size_t i_imu = 0, i_gt = 0;
  auto flushUntil = [&](TimeNs t) {
    for (; i_imu < ds.imu.size() && ds.imu[i_imu].t_ns <= t; ++i_imu) sink.imu(ds.imu[i_imu]);
    for (; i_gt < ds.groundtruth.size() && ds.groundtruth[i_gt].t_ns <= t; ++i_gt) sink.odometry(ds.groundtruth[i_gt]);
  };
  const std::string csv0 = (std::filesystem::path(ds.root) / "cam0" / "data.csv").string();
  const std::string csv1 = (std::filesystem::path(ds.root) / "cam1" / "data.csv").string();
  for (const StereoPair& p : ds.pairs) {
    flushUntil(p.t_ns);
    const cv::Mat left = loadGrayImage(ds.cam0[p.i0], csv0, 0, 0);
    sink.image("/cam0/image_raw", left, ds.cam0[p.i0].t_ns, "cam0");
    if (ds.stereo())
      sink.image("/cam1/image_raw", loadGrayImage(ds.cam1[p.i1], csv1, left.cols, left.rows), ds.cam1[p.i1].t_ns,
                 "cam1");
    if (segmentation)
      sink.image("/cam0/segmentation", segmentationRgb(ds, p, csv0, left.size(), colours), ds.cam0[p.i0].t_ns, "cam0");
  }
  flushUntil(std::numeric_limits<TimeNs>::max());
  sink.close();
}

void writeViodeBag(const EurocDataset& ds, const std::string& bag_path, const BagWriteOptions& options) {
  if (options.format == "mcap") {
    writeViodeRos2(ds, bag_path, options);
    return;
  }
  if (options.format != "ros1") throw InputError(bag_path, "unknown bag format '" + options.format + "' (ros1, mcap)");
  Ros1Sink sink(bag_path, options.compression);
  writeViode(ds, sink, options.rgb_ids, options.vehicle_ids);
}

}  // namespace idyvins::io
