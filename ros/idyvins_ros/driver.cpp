#include "driver.h"

#include <cv_bridge/cv_bridge.h>

#include <exception>

#include "map/map_io.h"

namespace idyvins::ros_node {

Driver::Driver(ros::NodeHandle& nh, ros::NodeHandle& pnh, const Config& config, const DriverOptions& options)
    : config_(config),
      options_(options),
      system_(config, options.run),
      publisher_(
          pnh, options.publish, [this](TimeNs t) { return arrival(t); },
          config.loop.enabled ? LoopCorrection([this](const imu::NavState& s, Eigen::Vector3d& p,
                                                      Eigen::Quaterniond& q) { return system_.loopCorrected(s, p, q); })
                              : LoopCorrection()) {
  if (!options.load_map.empty())
    system_.loadMap(map::loadMap(options.load_map), !options.localization_only, options.load_map);
  system_.addObserver(publisher_);
  worker_ = std::thread([this] { process(); });
  // Large queues: the callbacks only queue, so nothing is dropped by roscpp while the
  // system works; the queue_frames policy decides what a slow system skips.
  imu_sub_ = nh.subscribe(config.imu_topic, 4000, &Driver::onImu, this, ros::TransportHints().tcpNoDelay());
  image_sub_[0] = nh.subscribe<sensor_msgs::Image>(config.image0_topic, 200,
                                                   [this](const sensor_msgs::ImageConstPtr& m) { onImage(0, m); });
  image_sub_[1] = nh.subscribe<sensor_msgs::Image>(config.image1_topic, 200,
                                                   [this](const sensor_msgs::ImageConstPtr& m) { onImage(1, m); });
}

Driver::~Driver() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  if (worker_.joinable()) worker_.join();
}

void Driver::onImu(const sensor_msgs::ImuConstPtr& msg) {
  ImuSample s;
  s.t_ns = static_cast<TimeNs>(msg->header.stamp.toNSec());
  s.gyr_b = {msg->angular_velocity.x, msg->angular_velocity.y, msg->angular_velocity.z};
  s.acc_b = {msg->linear_acceleration.x, msg->linear_acceleration.y, msg->linear_acceleration.z};
  std::lock_guard<std::mutex> lock(mutex_);
  if (s.t_ns <= last_imu_ns_) {  // a clock that went back (bag looped, driver restarted): say so
    ++counts_.imu_backwards;
    ROS_WARN_THROTTLE(5,
                      "idyvins: IMU time went back %.3f s (%zu samples so far not after their predecessor; "
                      "they are dropped; restart the node after a clock reset)",
                      1e-9 * static_cast<double>(last_imu_ns_ - s.t_ns), counts_.imu_backwards);
  } else {
    last_imu_ns_ = s.t_ns;
  }
  push(s);
}

void Driver::onImage(int camera, const sensor_msgs::ImageConstPtr& msg) {
  cv::Mat gray;
  try {  // mono8 as it is; rgb8, bgr8, rgba8, bgra8 converted as the bag reader does (cv::cvtColor)
    gray = cv_bridge::toCvShare(msg, "mono8")->image.clone();
  } catch (const std::exception& e) {
    ROS_ERROR_THROTTLE(5, "idyvins: image on camera %d not usable (%s): dropped", camera, e.what());
    std::lock_guard<std::mutex> lock(mutex_);
    ++counts_.bad_images;
    return;
  }
  std::lock_guard<std::mutex> lock(mutex_);
  if (gray.cols != config_.image_width || gray.rows != config_.image_height) {
    ROS_ERROR_THROTTLE(5, "idyvins: image on camera %d is %dx%d, the config says %dx%d: dropped", camera, gray.cols,
                       gray.rows, config_.image_width, config_.image_height);
    ++counts_.bad_images;
    return;
  }
  const TimeNs t_ns = static_cast<TimeNs>(msg->header.stamp.toNSec());
  if (t_ns <= last_image_ns_[camera])
    ROS_WARN_THROTTLE(5,
                      "idyvins: camera %d time went back %.3f s (%zu images so far not after their predecessor; "
                      "they are dropped; restart the node after a clock reset)",
                      camera, 1e-9 * static_cast<double>(last_image_ns_[camera] - t_ns), sync_.outOfOrder(camera) + 1);
  else
    last_image_ns_[camera] = t_ns;
  sync_.add(camera, t_ns, gray);
  while (auto pair = sync_.next()) {
    arrival_[pair->t_ns] = std::chrono::steady_clock::now();
    ++counts_.frames_in;
    push(std::move(*pair));
  }
}

void Driver::push(io::Measurement m) {
  if (std::holds_alternative<StereoFrame>(m)) {
    ++queued_frames_;
    if (options_.queue_frames > 0 && queued_frames_ > static_cast<std::size_t>(options_.queue_frames)) {
      for (auto it = queue_.begin(); it != queue_.end(); ++it) {  // the oldest waiting pair goes
        if (const auto* f = std::get_if<StereoFrame>(&*it)) {
          arrival_.erase(f->t_ns);
          queue_.erase(it);
          --queued_frames_;
          ++counts_.frames_dropped;
          break;
        }
      }
    }
  }
  queue_.push_back(std::move(m));
  wake_.notify_one();
}

void Driver::process() {
  for (;;) {
    io::Measurement m;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      wake_.wait(lock, [this] { return !queue_.empty() || stopping_; });
      if (queue_.empty() || !error_.empty()) return;
      m = std::move(queue_.front());
      queue_.pop_front();
      if (std::holds_alternative<StereoFrame>(m)) --queued_frames_;
    }
    try {
      if (const auto* imu = std::get_if<ImuSample>(&m)) {
        const std::size_t spikes = system_.summary().imu_spikes;
        system_.addImu(*imu);
        if (system_.summary().imu_spikes > spikes)
          ROS_WARN_THROTTLE(5, "idyvins: IMU spike dropped (%zu so far, %zu samples; imu_spike_acc / imu_spike_gyr)",
                            system_.summary().imu_spikes, system_.summary().imu_spike_samples);
        system_.poll();
      } else {
        system_.addFrame(std::get<StereoFrame>(m));
      }
    } catch (const std::exception& e) {
      ROS_ERROR("idyvins: processing stopped: %s", e.what());
      std::lock_guard<std::mutex> lock(mutex_);
      error_ = e.what();
      return;
    }
  }
}

SteadyTime Driver::arrival(TimeNs t_ns) {
  std::lock_guard<std::mutex> lock(mutex_);
  const auto it = arrival_.find(t_ns);
  if (it == arrival_.end()) return std::chrono::steady_clock::now();
  const SteadyTime t = it->second;
  arrival_.erase(it);
  return t;
}

pipeline::Result Driver::finish() {
  imu_sub_.shutdown();
  image_sub_[0].shutdown();
  image_sub_[1].shutdown();
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
    counts_.unpaired[0] = sync_.unpaired(0);
    counts_.unpaired[1] = sync_.unpaired(1);
    counts_.out_of_order[0] = sync_.outOfOrder(0);
    counts_.out_of_order[1] = sync_.outOfOrder(1);
  }
  wake_.notify_all();
  worker_.join();  // the queue drains first
  pipeline::Result result = system_.finish();
  publisher_.publishFinalMaps(result);
  return result;
}

InputCounts Driver::counts() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return counts_;
}

std::string Driver::error() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return error_;
}

}  // namespace idyvins::ros_node
