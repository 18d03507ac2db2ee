// `idyvins convert BAG OUT`: a ROS1 or ROS 2 bag as a EuRoC ASL folder (what `run` reads
// identically from either).

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <optional>

#include "commands.h"
#include "config/config.h"
#include "core/error.h"
#include "io/bag_dataset.h"
#include "io/trajectory_io.h"
#include "pipeline/run.h"
#include "progress.h"

namespace idyvins::app {
namespace {

namespace fs = std::filesystem;

struct ConvertArgs {
  std::string bag, out, config, groundtruth_topic;
};

std::ofstream openCsv(const fs::path& path, const char* header) {
  fs::create_directories(path.parent_path());
  std::ofstream f(path);
  if (!f) throw InputError(path.string(), "cannot write");
  f << header << "\n";
  return f;
}

void writeImage(const fs::path& path, const cv::Mat& image) {
  if (!cv::imwrite(path.string(), image)) throw InputError(path.string(), "cannot write image");
}

/// EuRoC's imu0/data.csv, every digit kept.
void writeImuCsv(const fs::path& path, const std::vector<ImuSample>& imu) {
  std::ofstream csv = openCsv(path,
                              "#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],"
                              "a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]");
  char buf[512];
  for (const auto& m : imu) {
    std::snprintf(buf, sizeof(buf), "%lld,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g\n", static_cast<long long>(m.t_ns),
                  m.gyr_b.x(), m.gyr_b.y(), m.gyr_b.z(), m.acc_b.x(), m.acc_b.y(), m.acc_b.z());
    csv << buf;
  }
}

int runConvert(const ConvertArgs& a) {
  if (!io::isBagFile(a.bag))
    throw InputError(a.bag, "not a bag (a ROS1 .bag, a ROS 2 bag folder with metadata.yaml, an .mcap or .db3 file)");
  std::optional<Config> config;
  if (!a.config.empty()) config = loadConfig(a.config);
  io::BagTopics topics;
  if (config)
    topics = pipeline::datasetRequest(*config, a.groundtruth_topic).topics;
  else
    topics.groundtruth = a.groundtruth_topic;
  const int w = config ? config->image_width : 0, h = config ? config->image_height : 0;
  io::BagIndex index = io::indexBag(a.bag, topics, w, h);
  const fs::path mav0 = fs::path(a.out) / "mav0";
  if (fs::exists(mav0)) throw InputError(mav0.string(), "already exists; convert writes a new folder");
  const bool stereo = index.dataset.stereo();
  const auto imu = index.dataset.imu;
  const auto groundtruth = index.dataset.groundtruth;
  const std::size_t pairs = index.dataset.pairs.size();
  // Masks when the config names a segmentation topic the bag has (VIODE): mav0/cam0/mask/.
  std::optional<io::SegmentationColors> colors;
  if (config && !index.segmentation.empty())
    colors = io::readSegmentationColors(config->segmentation_rgb_ids, config->segmentation_vehicle_ids);
  if (colors) fs::create_directories(mav0 / "cam0" / "mask");

  for (const char* cam : {"cam0", "cam1"})
    if (std::string(cam) == "cam0" || stereo) fs::create_directories(mav0 / cam / "data");
  std::ofstream csv0 = openCsv(mav0 / "cam0" / "data.csv", "#timestamp [ns],filename");
  std::ofstream csv1;
  if (stereo) csv1 = openCsv(mav0 / "cam1" / "data.csv", "#timestamp [ns],filename");
  writeImuCsv(mav0 / "imu0" / "data.csv", imu);
  if (!groundtruth.empty()) {
    fs::create_directories(mav0 / "state_groundtruth_estimate0");
    io::writeStateCsv((mav0 / "state_groundtruth_estimate0" / "data.csv").string(), groundtruth);
  }
  // Stereo pairs only, both images named by the left stamp (the folder pairs them exactly).
  io::BagSource source(std::move(index), w, h, colors);
  ProgressBar bar("convert", pairs, "frames");
  std::size_t k = 0;
  while (auto m = source.next()) {
    const auto* f = std::get_if<StereoFrame>(&*m);
    if (!f) continue;
    const std::string name = std::to_string(f->t_ns) + ".png";
    writeImage(mav0 / "cam0" / "data" / name, f->left);
    csv0 << f->t_ns << "," << name << "\n";
    if (colors) writeImage(mav0 / "cam0" / "mask" / name, f->left_mask);
    if (stereo) {
      writeImage(mav0 / "cam1" / "data" / name, f->right);
      csv1 << f->t_ns << "," << name << "\n";
    }
    bar.update(++k);
  }
  bar.finish();
  std::printf(
      "wrote %s: %zu %s frames%s, %zu IMU samples, %s\n", mav0.string().c_str(), k, stereo ? "stereo" : "mono",
      colors ? " with masks (cam0/mask)" : "", imu.size(),
      groundtruth.empty() ? "no ground truth" : (std::to_string(groundtruth.size()) + " ground-truth states").c_str());
  return kOk;
}

}  // namespace

void registerConvert(CLI::App& app, int& exit_code) {
  auto a = std::make_shared<ConvertArgs>();
  CLI::App* cmd = app.add_subcommand(
      "convert",
      "Write a ROS1 or ROS 2 bag as a EuRoC ASL folder: OUT/mav0/cam0 and cam1 (data.csv and PNGs of the\n"
      "stereo pairs, 8-bit gray, both named by the left stamp), imu0/data.csv, and\n"
      "state_groundtruth_estimate0/data.csv from the ground-truth topic (pose; velocity and\n"
      "biases zero), and cam0/mask/ (moving-object labels) when the config names a segmentation topic\n"
      "the bag has. `run` gives the same outputs on the bag and on the folder.");
  cmd->add_option("bag", a->bag, "ROS1 .bag, or ROS 2 bag (folder with metadata.yaml, .mcap or .db3)")->required();
  cmd->add_option("out", a->out, "output folder (OUT/mav0 must not exist)")->required();
  cmd->add_option("-c,--config", a->config,
                  "VINS-Fusion config: topics (imu_topic, image0_topic, image1_topic, groundtruth_topic)\n"
                  "and image size; without it /imu0, /cam0/image_raw, /cam1/image_raw");
  cmd->add_option("--groundtruth-topic", a->groundtruth_topic,
                  "ground-truth topic, e.g. /odometry (VIODE) or /vicon/firefly_sbx/firefly_sbx (EuRoC)");
  cmd->callback([a, &exit_code] { exit_code = runConvert(*a); });
}

}  // namespace idyvins::app
