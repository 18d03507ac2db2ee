// `idyvins info`: what a dataset holds (counts, rates, span, gaps, calibration), validated.

#include <cstdio>
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>

#include "commands.h"
#include "config/config.h"
#include "core/error.h"
#include "imu/spike_gate.h"
#include "io/bag_dataset.h"
#include "io/dataset_summary.h"
#include "io/euroc_dataset.h"
#include "pipeline/run.h"
#include "pipeline/system.h"
#include "progress.h"

namespace idyvins::app {
namespace {

struct InfoArgs {
  std::string dataset;
  std::string config;
  std::string groundtruth_topic;
  bool json = false;
  bool skip_images = false;
};

nlohmann::json toJson(const io::StreamStats& s) {
  return {{"count", s.count},     {"first_ns", s.first_ns},   {"last_ns", s.last_ns}, {"span_s", s.span_s},
          {"rate_hz", s.rate_hz}, {"max_gap_s", s.max_gap_s}, {"gaps", s.gaps}};
}

void printStream(const char* name, const io::StreamStats& s, const char* unit) {
  std::printf("  %-12s %6zu %-8s %7.2f Hz  span %8.3f s  [%s .. %s]  max gap %.3f s", name, s.count, unit, s.rate_hz,
              s.span_s, formatSeconds(s.first_ns).c_str(), formatSeconds(s.last_ns).c_str(), s.max_gap_s);
  if (s.gaps) std::printf("  (%zu gaps > 1.5x nominal)", s.gaps);
  std::printf("\n");
}

/// Reads every image of every stereo pair; returns the image size. Throws on the first bad one.
std::pair<int, int> validateImages(const io::EurocDataset& ds, int width, int height) {
  namespace fs = std::filesystem;
  const std::string csv0 = (fs::path(ds.root) / "cam0" / "data.csv").string();
  const std::string csv1 = (fs::path(ds.root) / "cam1" / "data.csv").string();
  ProgressBar bar("checking images", ds.pairs.size(), "pairs");
  for (std::size_t k = 0; k < ds.pairs.size(); ++k) {
    const auto& p = ds.pairs[k];
    const cv::Mat left = io::loadGrayImage(ds.cam0[p.i0], csv0, width, height);
    if (width == 0) {
      width = left.cols;
      height = left.rows;
    }
    if (ds.stereo()) io::loadGrayImage(ds.cam1[p.i1], csv1, width, height);
    bar.update(k + 1);
  }
  bar.finish();
  return {width, height};
}

/// Decodes every image of every stereo pair of a bag; returns the image size.
std::pair<int, int> validateBagImages(const io::BagIndex& index, int width, int height) {
  const std::size_t total = index.dataset.pairs.size();
  // The source needs the image stamps only: no copy of the IMU and the ground truth.
  io::BagIndex images{index.path,  index.topics, index.all_topics, {}, index.segmentation, index.segmentation_of_pair,
                      index.format};
  const io::EurocDataset& d = index.dataset;
  images.dataset.root = d.root;
  images.dataset.cam0 = d.cam0;
  images.dataset.cam1 = d.cam1;
  images.dataset.pairs = d.pairs;
  io::BagSource source(std::move(images), width, height);
  ProgressBar bar("checking images", total, "pairs");
  std::size_t k = 0;
  std::pair<int, int> size{width, height};
  while (auto m = source.next()) {
    if (const auto* f = std::get_if<StereoFrame>(&*m)) {
      size = {f->left.cols, f->left.rows};
      bar.update(++k);
    }
  }
  bar.finish();
  return size;
}

/// Default topics for a bag without a config: VIODE's and EuRoC's names.
io::BagTopics defaultBagTopics(const std::optional<Config>& config, const std::string& groundtruth_topic) {
  if (config) return pipeline::datasetRequest(*config, groundtruth_topic).topics;
  io::BagTopics t;
  t.groundtruth = groundtruth_topic;
  return t;
}

/// The short IMU spikes `run` would drop (imu/spike_gate.h, the config's keys or the defaults).
struct SpikeCount {
  std::size_t runs = 0, samples = 0;
};

SpikeCount imuSpikes(const std::vector<ImuSample>& imu, const imu::SpikeGateOptions& options) {
  imu::SpikeGate gate(options);
  std::vector<ImuSample> released;
  released.reserve(imu.size());
  for (const ImuSample& sample : imu) gate.push(sample, released);
  gate.flush(released);
  return {gate.spikes(), gate.droppedSamples()};
}

/// What info found, for printing.
struct InfoOutcome {
  const io::EurocDataset& ds;
  const io::DatasetSummary& s;
  const io::BagIndex* bag;            ///< null for a EuRoC folder
  const Config* config;               ///< null without --config
  std::pair<int, int> size;           ///< image size (0 x 0 with --skip-images)
  SpikeCount spikes;                  ///< IMU spikes the spike gate would drop
  std::vector<std::string> warnings;  ///< what run would warn about (config keys, plausibility)
};

void printJson(const InfoArgs& args, const InfoOutcome& o) {
  const io::DatasetSummary& s = o.s;
  nlohmann::json j = {{"dataset", o.ds.root},
                      {"stereo", s.stereo},
                      {"imu", toJson(s.imu)},
                      {"cam0", toJson(s.cam0)},
                      {"cam1", toJson(s.cam1)},
                      {"stereo_pairs", toJson(s.pairs)},
                      {"unmatched_cam0", s.unmatched0},
                      {"unmatched_cam1", s.unmatched1},
                      {"unmatched_without_image", s.unmatched_missing_image},
                      {"groundtruth", s.has_groundtruth ? toJson(s.groundtruth) : nullptr},
                      {"imu_spikes", {{"runs", o.spikes.runs}, {"samples", o.spikes.samples}}},
                      {"images_checked", !args.skip_images},
                      {"image_width", o.size.first},
                      {"image_height", o.size.second},
                      {"config", o.config ? o.config->path : ""}};
  if (o.bag) {
    j["format"] = o.bag->format.rfind("ROS1", 0) == 0 ? "rosbag" : "rosbag2";
    j["bag_format"] = o.bag->format;
    j["topics"] = nlohmann::json::array();
    for (const auto& t : o.bag->all_topics)
      j["topics"].push_back({{"topic", t.topic}, {"type", t.type}, {"count", t.count}});
  }
  j["warnings"] = o.warnings;
  std::cout << j.dump(2) << "\n";
}

void printText(const InfoArgs& args, const InfoOutcome& o) {
  const io::DatasetSummary& s = o.s;
  const io::BagIndex* bag = o.bag;
  std::printf("dataset: %s (%s, %s)\n", o.ds.root.c_str(), bag ? bag->format.c_str() : "EuRoC ASL",
              s.stereo ? "stereo" : "mono");
  if (bag) {
    for (const auto& t : bag->all_topics)
      std::printf("  topic        %-40s %-32s %7zu messages\n", t.topic.c_str(), t.type.c_str(), t.count);
    std::printf("  reading      imu %s, cam0 %s, cam1 %s, groundtruth %s\n", bag->topics.imu.c_str(),
                bag->topics.image0.c_str(), bag->topics.image1.empty() ? "-" : bag->topics.image1.c_str(),
                bag->topics.groundtruth.empty() ? "-" : bag->topics.groundtruth.c_str());
  }
  printStream("imu0", s.imu, "samples");
  printStream("cam0", s.cam0, "images");
  if (s.stereo) printStream("cam1", s.cam1, "images");
  printStream(s.stereo ? "stereo pairs" : "frames", s.pairs, "frames");
  if (s.stereo) {
    std::printf("  unmatched    cam0 %zu, cam1 %zu rows without a partner within 1 ms", s.unmatched0, s.unmatched1);
    if (s.unmatched_missing_image) std::printf(" (%zu of them have no image file)", s.unmatched_missing_image);
    std::printf("; not used\n");
  }
  if (s.has_groundtruth)
    printStream("groundtruth", s.groundtruth, "states");
  else if (bag)
    std::printf("  groundtruth  none (no --groundtruth-topic, no groundtruth_topic in the config)\n");
  else
    std::printf("  groundtruth  none (no state_groundtruth_estimate0/data.csv)\n");
  std::printf("  imu coverage %.3f s before the first frame, %.3f s after the last\n", s.imu_before_first_frame_s,
              s.imu_after_last_frame_s);
  if (s.imu_before_first_frame_s < 0 || s.imu_after_last_frame_s < 0)
    std::printf("  warning: IMU does not cover every frame\n");
  if (o.spikes.runs > 0)
    std::printf("  imu spikes   %zu short spikes (%zu samples) that run drops (imu_spike_acc / imu_spike_gyr)\n",
                o.spikes.runs, o.spikes.samples);
  else
    std::printf("  imu spikes   none that run would drop\n");
  if (!args.skip_images)
    std::printf("  images       %zu pairs read, all %dx%d 8-bit gray\n", o.ds.pairs.size(), o.size.first,
                o.size.second);
  if (o.config) std::printf("%s", describe(*o.config).c_str());
  if (o.warnings.empty())
    std::printf("valid: yes\n");
  else
    std::printf("valid: yes, with %zu warning(s) (on stderr; run prints them too)\n", o.warnings.size());
}

int runInfo(const InfoArgs& args) {
  std::optional<Config> config;
  if (!args.config.empty()) config = loadConfig(args.config);
  std::optional<io::BagIndex> bag;
  if (io::isBagFile(args.dataset))
    bag = io::indexBag(args.dataset, defaultBagTopics(config, args.groundtruth_topic), config ? config->image_width : 0,
                       config ? config->image_height : 0);
  io::EurocDataset folder;
  if (!bag) folder = io::readEurocDataset(args.dataset);
  const io::EurocDataset& ds = bag ? bag->dataset : folder;  // no copy of a long bag's index
  const io::DatasetSummary s = io::summarize(ds);
  std::pair<int, int> size{0, 0};
  if (!args.skip_images)
    size = bag ? validateBagImages(*bag, config ? config->image_width : 0, config ? config->image_height : 0)
               : validateImages(ds, config ? config->image_width : 0, config ? config->image_height : 0);
  // What run would refuse (thrown here) or warn about, in its words.
  std::vector<std::string> warnings;
  if (config) {
    pipeline::checkRunnable(*config);
    warnings = config->warnings;
    const auto more = io::checkPlausible(ds, s, pipeline::datasetRequest(*config).rig);
    warnings.insert(warnings.end(), more.begin(), more.end());
  }
  for (const std::string& w : warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());
  const SpikeCount spikes = imuSpikes(ds.imu, config ? config->imu.spike : imu::SpikeGateOptions{});
  const InfoOutcome outcome{ds, s, bag ? &*bag : nullptr, config ? &*config : nullptr, size, spikes, warnings};
  if (args.json)
    printJson(args, outcome);
  else
    printText(args, outcome);
  return kOk;
}

}  // namespace

void registerInfo(CLI::App& app, int& exit_code) {
  auto args = std::make_shared<InfoArgs>();
  CLI::App* cmd =
      app.add_subcommand("info",
                         "Print what a EuRoC ASL dataset or a ROS1 / ROS 2 bag holds (counts, rates, time span, gaps,\n"
                         "unmatched stereo rows, calibration; for a bag also every topic with its type and count)\n"
                         "and validate it: syntax, time order, every image readable and of the config's size.\n"
                         "Exits 1 with file:line: reason on bad input.");
  cmd->add_option("dataset", args->dataset,
                  "EuRoC folder (holding mav0/), the mav0 folder, a ROS1 .bag, or a ROS 2 bag (folder with\n"
                  "metadata.yaml, .mcap or .db3)")
      ->required();
  cmd->add_option("--groundtruth-topic", args->groundtruth_topic,
                  "bag only: ground-truth topic, e.g. /odometry (VIODE) or /vicon/firefly_sbx/firefly_sbx (EuRoC)");
  cmd->add_option("-c,--config", args->config, "VINS-Fusion config to validate against (image size, camera count)");
  cmd->add_flag("--json", args->json, "print the summary as JSON");
  cmd->add_flag("--skip-images", args->skip_images, "do not read the images (faster)");
  cmd->callback([args, &exit_code] { exit_code = runInfo(*args); });
}

}  // namespace idyvins::app
