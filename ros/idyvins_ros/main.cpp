// idyvins_ros: the ROS1 node. A thin driver of pipeline::System (Driver): reads the VINS-Fusion
// config named by ~config_file (or the first argument, as VINS-Fusion's node), subscribes to
// its imu_topic, image0_topic and image1_topic, publishes on ~odometry, ~path, TF, ~map_static,
// ~map_dynamic, ~feature_image and ~timing (docs/ros.md). On SIGINT / SIGTERM it stops
// listening, processes what it received, publishes the final maps and, with ~out, writes the
// files `idyvins run` writes (trajectory.tum, state.csv, PLY maps, stats.json) and latency.csv.

#include <ros/ros.h>

#include <algorithm>
#include <atomic>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>

#include "config/config.h"
#include "core/error.h"
#include "driver.h"
#include "pipeline/run.h"
#include "pipeline/run_outputs.h"

namespace {

std::atomic<bool> g_stop{false};
void onSignal(int) { g_stop = true; }

struct NodeArgs {
  std::string config_file, mode, out;
  bool force = false;  ///< ~force: write into an ~out holding files idyvins did not write (none removed)
  int threads = 1;     ///< ~threads: 1 (lowest latency) or 2 (pipelined, as `idyvins run`'s default)
  idyvins::ros_node::DriverOptions driver;
};

NodeArgs readParams(ros::NodeHandle& pnh, int argc, char** argv) {
  NodeArgs a;
  pnh.param<std::string>("config_file", a.config_file, argc > 1 ? argv[1] : "");
  pnh.param<std::string>("mode", a.mode, "");
  pnh.param<std::string>("out", a.out, "");
  pnh.param("force", a.force, false);
  pnh.param("threads", a.threads, 1);
  pnh.param("queue_frames", a.driver.queue_frames, 0);
  pnh.param<std::string>("world_frame", a.driver.publish.world_frame, "world");
  pnh.param<std::string>("body_frame", a.driver.publish.body_frame, "body");
  pnh.param("map_every_frames", a.driver.publish.map_every_frames, 10);
  idyvins::ros_node::PublisherOptions& pub = a.driver.publish;  // the odometry covariance model (publisher.h)
  pnh.param("position_sigma", pub.position_sigma_m, pub.position_sigma_m);
  pnh.param("position_drift", pub.drift_fraction, pub.drift_fraction);
  pnh.param("orientation_sigma", pub.orientation_sigma_rad, pub.orientation_sigma_rad);
  pnh.param("orientation_drift", pub.drift_rad_per_m, pub.drift_rad_per_m);
  pnh.param("velocity_sigma", pub.velocity_sigma_mps, pub.velocity_sigma_mps);
  pnh.param<std::string>("load_map", a.driver.load_map, "");
  pnh.param("localization_only", a.driver.localization_only, false);
  if (a.config_file.empty()) throw idyvins::InputError("idyvins_ros", "no config: set ~config_file or pass its path");
  if (a.driver.queue_frames < 0) throw idyvins::InputError("idyvins_ros", "~queue_frames must be >= 0");
  for (const double v : {pub.position_sigma_m, pub.drift_fraction, pub.orientation_sigma_rad, pub.drift_rad_per_m,
                         pub.velocity_sigma_mps})
    if (!(v >= 0))
      throw idyvins::InputError("idyvins_ros",
                                "~position_sigma, ~position_drift, ~orientation_sigma, "
                                "~orientation_drift and ~velocity_sigma must be >= 0");
  if (pub.position_sigma_m == 0 || pub.orientation_sigma_rad == 0 || pub.velocity_sigma_mps == 0)
    throw idyvins::InputError("idyvins_ros",
                              "~position_sigma, ~orientation_sigma and ~velocity_sigma must be > 0 "
                              "(a zero covariance claims an exact pose)");
  return a;
}

/// The config with the node's parameters applied by the run rules (pipeline/run.h), and the
/// system's run options in `a.driver.run`.
idyvins::Config nodeConfig(NodeArgs& a) {
  idyvins::Config config = idyvins::loadConfig(a.config_file);
  for (const std::string& w : config.warnings) ROS_WARN("idyvins: %s", w.c_str());
  idyvins::pipeline::RunRequest request;
  request.mode = a.mode;
  request.threads = a.threads;
  request.load_map = !a.driver.load_map.empty();
  request.localization_only = a.driver.localization_only;
  request.masks_available = false;  // live topics carry no ground-truth masks
  try {
    a.driver.run = idyvins::pipeline::applyRunRequest(request, config);
  } catch (const idyvins::pipeline::OptionError& e) {
    throw idyvins::InputError("idyvins_ros",
                              "~" + e.option() + " " + e.text([](const std::string& name) { return "~" + name; }));
  }
  return config;
}

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<std::size_t>(q * static_cast<double>(v.size())))];
}

nlohmann::json nodeSummary(const idyvins::ros_node::Driver& driver) {
  const auto c = driver.counts();
  std::vector<double> ms;
  for (const auto& l : driver.publisher().latencies()) ms.push_back(l.latency_ms);
  return {{"frames_in", c.frames_in},
          {"frames_dropped_queue_full", c.frames_dropped},
          {"images_unpaired", {c.unpaired[0], c.unpaired[1]}},
          {"images_out_of_order", {c.out_of_order[0], c.out_of_order[1]}},
          {"imu_backwards", c.imu_backwards},
          {"images_bad", c.bad_images},
          {"latency_median_ms", percentile(ms, 0.5)},
          {"latency_p95_ms", percentile(ms, 0.95)},
          {"latency_max_ms", percentile(ms, 1.0)}};
}

/// ~out as `idyvins run` treats --out (pipeline::RunOutputs): staged, published whole, never
/// replacing a folder it did not write; latency.csv beside the run's files.
std::unique_ptr<idyvins::pipeline::RunOutputs> nodeOutputs(const NodeArgs& a) {
  if (a.out.empty()) return nullptr;
  idyvins::pipeline::RunOutputsOptions o;
  o.inputs = {a.config_file, a.driver.load_map};
  o.force = a.force;
  o.extra_names = {"latency.csv", "latency.csv.part"};
  return std::make_unique<idyvins::pipeline::RunOutputs>(a.out, o);
}

void writeOutputs(idyvins::pipeline::RunOutputs& outputs, const idyvins::pipeline::Result& result,
                  const idyvins::ros_node::Driver& driver) {
  idyvins::pipeline::RunEnd end;
  end.extras["ros"] = nodeSummary(driver);
  outputs.write(driver.system(), result, end);
  const std::string lat_path = outputs.path() + "/latency.csv";
  std::ofstream lat(lat_path + ".part");
  lat << "#stamp_ns,latency_ms\n";
  for (const auto& l : driver.publisher().latencies()) lat << l.t_ns << ',' << l.latency_ms << '\n';
  lat.close();
  if (!lat) throw idyvins::InputError(lat_path + ".part", "write failed");
  std::filesystem::rename(lat_path + ".part", lat_path);
}

int runNode(int argc, char** argv) {
  ros::NodeHandle nh, pnh("~");
  NodeArgs args = readParams(pnh, argc, argv);
  const idyvins::Config config = nodeConfig(args);
  const std::unique_ptr<idyvins::pipeline::RunOutputs> outputs = nodeOutputs(args);  // refused now, not at the end
  idyvins::ros_node::Driver driver(nh, pnh, config, args.driver);
  if (outputs)
    for (idyvins::pipeline::FrameObserver* o : outputs->observers()) driver.addObserver(*o);
  ROS_INFO("idyvins: mode %s, %d thread(s); listening to %s, %s, %s", idyvins::toString(config.mode),
           driver.system().threads(), config.imu_topic.c_str(), config.image0_topic.c_str(),
           config.image1_topic.c_str());
  ros::AsyncSpinner spinner(1);
  spinner.start();
  while (!g_stop && ros::ok()) ros::WallDuration(0.02).sleep();
  spinner.stop();
  const idyvins::pipeline::Result result = driver.finish();
  if (outputs) {
    writeOutputs(*outputs, result, driver);
    for (const std::string& w : outputs->publish()) ROS_WARN("idyvins: %s", w.c_str());
  }
  const nlohmann::json s = nodeSummary(driver);
  ROS_INFO("idyvins: %zu frames processed, %zu poses, %zu dropped (queue full); latency median %.1f ms, p95 %.1f ms",
           result.summary.frames, result.trajectory.size(), s["frames_dropped_queue_full"].get<std::size_t>(),
           s["latency_median_ms"].get<double>(), s["latency_p95_ms"].get<double>());
  // Messages published while draining sit in the publishers' outgoing queues; ros::shutdown()
  // drops what is still there, so the transport gets a moment to deliver them.
  ros::WallDuration(0.5).sleep();
  return driver.error().empty() ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "idyvins", ros::init_options::NoSigintHandler);
  std::signal(SIGINT, onSignal);
  std::signal(SIGTERM, onSignal);
  int code = 1;
  try {
    code = runNode(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s\n", e.what());
    code = 1;
  }
  ros::shutdown();
  return code;
}
