#pragma once
// idyvins_ros' core: ROS messages in, pipeline::System on its own thread, Publisher out.
// Callbacks only convert and queue (stereo pairs formed by stamp, as VINS-Fusion's node
// does), so a slow frame never blocks the subscribers; the processing thread gives the
// system every IMU sample and pair in arrival order and polls it after each IMU sample,
// so a frame is processed as soon as the IMU reaches its time. With every frame received
// in order, the outputs are those of `idyvins run` on the same data (docs/ros.md).

#include <ros/ros.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/Imu.h>

#include <condition_variable>
#include <deque>
#include <map>
#include <mutex>
#include <thread>

#include "config/config.h"
#include "io/data_source.h"
#include "pipeline/stereo_sync.h"
#include "pipeline/system.h"
#include "publisher.h"

namespace idyvins::ros_node {

struct DriverOptions {
  pipeline::RunOptions run;  ///< sequential (lowest latency) or pipelined (pipeline::applyRunRequest)
  int queue_frames = 0;      ///< frames waiting for the system beyond which the oldest is dropped (0: never drop)
  PublisherOptions publish;
  std::string load_map;            ///< a map saved by `idyvins run --save-map` to relocalize in (loop closure on)
  bool localization_only = false;  ///< with load_map: do not extend the map
};

/// Counters of what did not reach the system.
struct InputCounts {
  std::size_t frames_in = 0;             ///< pairs formed
  std::size_t frames_dropped = 0;        ///< pairs dropped because the queue was full
  std::size_t unpaired[2] = {0, 0};      ///< images without a partner (left, right)
  std::size_t out_of_order[2] = {0, 0};  ///< images not after their camera's previous one
  std::size_t bad_images = 0;            ///< wrong size or encoding
  std::size_t imu_backwards = 0;         ///< IMU messages not after the previous one (dropped by the system)
};

class Driver {
 public:
  /// Subscribes to the config's imu_topic, image0_topic, image1_topic on `nh`; publishes on `pnh`.
  Driver(ros::NodeHandle& nh, ros::NodeHandle& pnh, const Config& config, const DriverOptions& options);
  ~Driver();
  /// Attaches another observer (e.g. a stats.json writer) before the first message.
  void addObserver(pipeline::FrameObserver& observer) { system_.addObserver(observer); }
  /// Unsubscribes, processes everything received, finishes the system, publishes the final maps.
  pipeline::Result finish();
  InputCounts counts() const;
  const Publisher& publisher() const { return publisher_; }
  const pipeline::System& system() const { return system_; }
  /// The error that stopped processing, empty when none.
  std::string error() const;

 private:
  void onImu(const sensor_msgs::ImuConstPtr& msg);
  void onImage(int camera, const sensor_msgs::ImageConstPtr& msg);
  void push(io::Measurement m);  ///< under the lock
  void process();                ///< the processing thread
  SteadyTime arrival(TimeNs t_ns);

  Config config_;
  DriverOptions options_;
  pipeline::System system_;
  Publisher publisher_;
  ros::Subscriber imu_sub_, image_sub_[2];

  mutable std::mutex mutex_;
  std::condition_variable wake_;
  pipeline::StereoSync sync_;
  std::deque<io::Measurement> queue_;  ///< IMU samples and pairs in arrival order
  std::size_t queued_frames_ = 0;
  std::map<TimeNs, SteadyTime> arrival_;  ///< when each queued pair was formed
  InputCounts counts_;
  TimeNs last_imu_ns_ = -1, last_image_ns_[2] = {-1, -1};  ///< for the backward-time warnings
  bool stopping_ = false;
  std::string error_;
  std::thread worker_;
};

}  // namespace idyvins::ros_node
