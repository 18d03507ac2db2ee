// simulate --format mcap: a rosbag2 folder (metadata.yaml, one MCAP file) with VIODE's topics.

#include <filesystem>
#include <fstream>
#include <map>

#include "core/error.h"
#include "io/bag_writer.h"
#include "io/mcap_writer.h"
#include "io/ros2_messages.h"

namespace idyvins::io {
namespace {

namespace fs = std::filesystem;

class McapSink : public ViodeSink {
 public:
  McapSink(const std::string& folder, const std::string& compression)
      : folder_(folder),
        file_(fs::path(folder).filename().string() + "_0.mcap"),
        writer_((fs::path(folder) / file_).string(), compression) {}
  void imu(const ImuSample& s) override { put("/imu0", "sensor_msgs/msg/Imu", s.t_ns, encodeRos2Imu(s, "imu")); }
  void odometry(const GroundTruthState& g) override {
    put("/odometry", "nav_msgs/msg/Odometry", g.t_ns, encodeRos2Odometry(g.t_ns, "world", "body", g.p_w_b, g.q_w_b));
  }
  void image(const std::string& topic, const cv::Mat& image, TimeNs t, const std::string& frame_id) override {
    const cv::Mat c = image.isContinuous() ? image : image.clone();
    const auto step = static_cast<std::uint32_t>(c.cols * c.channels());
    put(topic, "sensor_msgs/msg/Image", t,
        encodeRos2Image(t, frame_id, static_cast<std::uint32_t>(c.cols), static_cast<std::uint32_t>(c.rows),
                        c.channels() == 1 ? "mono8" : "rgb8", step, c.ptr<std::uint8_t>(0)));
  }
  void close() override {
    writer_.close();
    writeMetadata();
  }

 private:
  struct Topic {
    std::string type;
    std::uint16_t channel = 0;
    std::size_t count = 0;
  };
  void put(const std::string& topic, const std::string& type, TimeNs t, const std::vector<std::uint8_t>& cdr) {
    auto it = topics_.find(topic);
    if (it == topics_.end())
      it = topics_.emplace(topic, Topic{type, writer_.addChannel(topic, type, ros2MessageDefinition(type)), 0}).first;
    writer_.write(it->second.channel, static_cast<std::uint64_t>(t), cdr);
    ++it->second.count;
    first_ = std::min(first_, t);
    last_ = std::max(last_, t);
    ++messages_;
  }
  void writeMetadata() const {
    const std::string path = (fs::path(folder_) / "metadata.yaml").string();
    std::ofstream m(path);
    m << "rosbag2_bagfile_information:\n  version: 5\n  storage_identifier: mcap\n  duration:\n    nanoseconds: "
      << (messages_ ? last_ - first_ : 0)
      << "\n  starting_time:\n    nanoseconds_since_epoch: " << (messages_ ? first_ : 0)
      << "\n  message_count: " << messages_ << "\n  topics_with_message_count:\n";
    for (const auto& [name, t] : topics_)
      m << "    - topic_metadata:\n        name: " << name << "\n        type: " << t.type
        << "\n        serialization_format: cdr\n        offered_qos_profiles: \"\"\n      message_count: " << t.count
        << "\n";
    m << "  compression_format: \"\"\n  compression_mode: \"\"\n  relative_file_paths:\n    - " << file_ << "\n";
    if (!m) throw InputError(path, "cannot write");
  }
  std::string folder_, file_;
  McapWriter writer_;
  std::map<std::string, Topic> topics_;
  TimeNs first_ = std::numeric_limits<TimeNs>::max(), last_ = 0;
  std::size_t messages_ = 0;
};

}  // namespace

void writeViodeRos2(const EurocDataset& ds, const std::string& folder, const BagWriteOptions& options) {
  if (fs::exists(folder)) throw InputError(folder, "already exists; a ROS 2 bag is written as a new folder");
  fs::create_directories(folder);
  McapSink sink(folder, options.compression);
  writeViode(ds, sink, options.rgb_ids, options.vehicle_ids);
}

}  // namespace idyvins::io
