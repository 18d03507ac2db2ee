#include "input.h"

#include <filesystem>
#include <optional>

#include "core/error.h"
#include "io/bag_dataset.h"
#include "io/dataset_summary.h"
#include "io/euroc_dataset.h"
#include "io/trajectory_io.h"
#include "pipeline/modes.h"

namespace idyvins::app {

Input openInput(const std::string& dataset, const Config& config, const std::string& groundtruth_topic, bool masks) {
  if (io::isBagFile(dataset)) {
    io::BagIndex index = io::indexBag(dataset, io::bagTopics(config, groundtruth_topic), config.image_width,
                                      config.image_height);
    Input in;
    in.warnings = io::checkPlausible(index.dataset, io::summarize(index.dataset), config);
    in.has_masks = masks && !index.segmentation.empty();
    if (pipeline::traitsOf(config.mode).needs_masks && !in.has_masks)
      throw InputError(dataset, "mode seg needs ground-truth masks: a segmentation_topic in the config (VIODE: "
                                "/cam0/segmentation)");
    std::optional<io::SegmentationColors> colors;
    if (in.has_masks)
      colors = io::readSegmentationColors(config.segmentation_rgb_ids, config.segmentation_vehicle_ids);
    for (const auto& g : index.dataset.groundtruth) in.groundtruth.push_back({g.t_ns, g.p_w_b, g.q_w_b});
    in.unpaired_cam0 = index.dataset.unmatched0.size();
    in.unpaired_cam1 = index.dataset.unmatched1.size();
    in.source =
        std::make_unique<io::BagSource>(std::move(index), config.image_width, config.image_height, std::move(colors));
    return in;
  }
  io::EurocDataset ds = io::readEurocDataset(dataset);
  Input in;
  in.warnings = io::checkPlausible(ds, io::summarize(ds), config);
  for (const auto& g : ds.groundtruth) in.groundtruth.push_back({g.t_ns, g.p_w_b, g.q_w_b});
  in.unpaired_cam0 = ds.unmatched0.size();
  in.unpaired_cam1 = ds.unmatched1.size();
  in.has_masks =
      masks && !ds.cam0.empty() && std::filesystem::is_directory(std::filesystem::path(ds.root) / "cam0" / "mask");
  if (pipeline::traitsOf(config.mode).needs_masks && !in.has_masks)
    throw InputError(ds.root, "mode seg needs mav0/cam0/mask/ (ground-truth masks)");
  in.source = std::make_unique<io::EurocSource>(std::move(ds), config.image_width, config.image_height, in.has_masks);
  return in;
}

/// A trajectory file, or a EuRoC folder's ground truth.
std::vector<StampedPose> readReference(const std::string& path) {
  namespace fs = std::filesystem;
  if (fs::is_directory(path)) {
    for (const fs::path& p : {fs::path(path) / "mav0/state_groundtruth_estimate0/data.csv",
                             fs::path(path) / "state_groundtruth_estimate0/data.csv"})
      if (fs::is_regular_file(p)) return io::readEurocCsv(p.string());
    throw InputError(path, "folder holds no mav0/state_groundtruth_estimate0/data.csv");
  }
  return io::readTrajectory(path);
}

}  // namespace idyvins::app
