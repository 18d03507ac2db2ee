// `idyvins info`: what a dataset holds (counts, rates, span, gaps, calibration), validated.

#include <cstdio>
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>

#include "commands.h"
#include "core/error.h"
#include "io/config.h"
#include "io/dataset_summary.h"
#include "io/euroc_dataset.h"
#include "progress.h"

namespace idyvins::app {
namespace {

struct InfoArgs {
  std::string dataset;
  std::string config;
  bool json = false;
  bool skip_images = false;
};

nlohmann::json toJson(const io::StreamStats& s) {
  return {{"count", s.count},       {"first_ns", s.first_ns}, {"last_ns", s.last_ns},
          {"span_s", s.span_s},     {"rate_hz", s.rate_hz},   {"max_gap_s", s.max_gap_s},
          {"gaps", s.gaps}};
}

void printStream(const char* name, const io::StreamStats& s, const char* unit) {
  std::printf("  %-12s %6zu %-8s %7.2f Hz  span %8.3f s  [%s .. %s]  max gap %.3f s", name,
              s.count, unit, s.rate_hz, s.span_s, formatSeconds(s.first_ns).c_str(),
              formatSeconds(s.last_ns).c_str(), s.max_gap_s);
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

int runInfo(const InfoArgs& args) {
  std::optional<Config> config;
  if (!args.config.empty()) config = loadConfig(args.config);
  const io::EurocDataset ds = io::readEurocDataset(args.dataset);
  const io::DatasetSummary s = io::summarize(ds);
  if (config && config->num_cam == 2 && !ds.stereo())
    throw InputError(ds.root, "config asks for 2 cameras but the dataset has no cam1/");
  std::pair<int, int> size{0, 0};
  if (!args.skip_images)
    size = validateImages(ds, config ? config->image_width : 0, config ? config->image_height : 0);

  if (args.json) {
    nlohmann::json j = {{"dataset", ds.root},
                        {"stereo", s.stereo},
                        {"imu", toJson(s.imu)},
                        {"cam0", toJson(s.cam0)},
                        {"cam1", toJson(s.cam1)},
                        {"stereo_pairs", toJson(s.pairs)},
                        {"unmatched_cam0", s.unmatched0},
                        {"unmatched_cam1", s.unmatched1},
                        {"unmatched_without_image", s.unmatched_missing_image},
                        {"groundtruth", s.has_groundtruth ? toJson(s.groundtruth) : nullptr},
                        {"images_checked", !args.skip_images},
                        {"image_width", size.first},
                        {"image_height", size.second},
                        {"config", config ? config->path : ""}};
    std::cout << j.dump(2) << "\n";
    return kOk;
  }
  std::printf("dataset: %s (EuRoC ASL, %s)\n", ds.root.c_str(), s.stereo ? "stereo" : "mono");
  printStream("imu0", s.imu, "samples");
  printStream("cam0", s.cam0, "images");
  if (s.stereo) printStream("cam1", s.cam1, "images");
  printStream(s.stereo ? "stereo pairs" : "frames", s.pairs, "frames");
  if (s.stereo) {
    std::printf("  unmatched    cam0 %zu, cam1 %zu rows without a partner within 1 ms", s.unmatched0,
                s.unmatched1);
    if (s.unmatched_missing_image)
      std::printf(" (%zu of them have no image file)", s.unmatched_missing_image);
    std::printf("; not used\n");
  }
  if (s.has_groundtruth) printStream("groundtruth", s.groundtruth, "states");
  else std::printf("  groundtruth  none (no state_groundtruth_estimate0/data.csv)\n");
  std::printf("  imu coverage %.3f s before the first frame, %.3f s after the last\n",
              s.imu_before_first_frame_s, s.imu_after_last_frame_s);
  if (s.imu_before_first_frame_s < 0 || s.imu_after_last_frame_s < 0)
    std::printf("  warning: IMU does not cover every frame\n");
  if (!args.skip_images)
    std::printf("  images       %zu pairs read, all %dx%d 8-bit gray\n", ds.pairs.size(),
                size.first, size.second);
  if (config) std::printf("%s", describe(*config).c_str());
  std::printf("valid: yes\n");
  return kOk;
}

}  // namespace

void registerInfo(CLI::App& app, int& exit_code) {
  auto args = std::make_shared<InfoArgs>();
  CLI::App* cmd = app.add_subcommand(
      "info",
      "Print what a EuRoC ASL dataset holds (counts, rates, time span, gaps, unmatched\n"
      "stereo rows, calibration) and validate it: CSV syntax, time order, every image\n"
      "readable and of the config's size. Exits 1 with file:line: reason on bad input.");
  cmd->add_option("dataset", args->dataset, "EuRoC folder (holding mav0/) or the mav0 folder")
      ->required();
  cmd->add_option("-c,--config", args->config,
                  "VINS-Fusion config to validate against (image size, camera count)");
  cmd->add_flag("--json", args->json, "print the summary as JSON");
  cmd->add_flag("--skip-images", args->skip_images, "do not read the images (faster)");
  cmd->callback([args, &exit_code] { exit_code = runInfo(*args); });
}

}  // namespace idyvins::app
