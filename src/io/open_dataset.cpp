#include "io/open_dataset.h"

#include <filesystem>
#include <optional>

#include "core/error.h"
#include "io/dataset_summary.h"
#include "io/euroc_dataset.h"
#include "io/trajectory_io.h"

namespace idyvins::io {
namespace {

void copyGroundTruth(const EurocDataset& ds, OpenedDataset& out) {
  for (const auto& g : ds.groundtruth) out.groundtruth.push_back({g.t_ns, g.p_w_b, g.q_w_b});
  out.unpaired_cam0 = ds.unmatched0.size();
  out.unpaired_cam1 = ds.unmatched1.size();
}

#if IDYVINS_HAVE_BAG
OpenedDataset openBag(const std::string& path, const DatasetRequest& r) {
  BagIndex index = indexBag(path, r.topics, r.image_width, r.image_height);
  OpenedDataset out;
  out.is_bag = true;
  out.root = path;
  out.warnings = checkPlausible(index.dataset, summarize(index.dataset), r.rig);
  out.has_masks = r.masks && !index.segmentation.empty();
  std::optional<SegmentationColors> colors;
  if (out.has_masks) colors = readSegmentationColors(r.segmentation_rgb_ids, r.segmentation_vehicle_ids);
  copyGroundTruth(index.dataset, out);
  out.source = std::make_unique<BagSource>(std::move(index), r.image_width, r.image_height, std::move(colors));
  return out;
}
#endif

}  // namespace

OpenedDataset openDataset(const std::string& path, const DatasetRequest& r) {
#if IDYVINS_HAVE_BAG
  if (isBagFile(path)) return openBag(path, r);
#endif
  EurocOptions options;
  options.left_only = r.rig.num_cam == 1;  // a mono run takes every cam0 image, paired or not
  EurocDataset ds = readEurocDataset(path, options);
  OpenedDataset out;
  out.root = ds.root;
  out.warnings = checkPlausible(ds, summarize(ds), r.rig);
  copyGroundTruth(ds, out);
  out.has_masks =
      r.masks && !ds.cam0.empty() && std::filesystem::is_directory(std::filesystem::path(ds.root) / "cam0" / "mask");
  out.source = std::make_unique<EurocSource>(std::move(ds), r.image_width, r.image_height, out.has_masks);
  return out;
}

std::vector<StampedPose> readReference(const std::string& path) {
  namespace fs = std::filesystem;
  if (fs::is_directory(path)) {
    for (const fs::path& p : {fs::path(path) / "mav0/state_groundtruth_estimate0/data.csv",
                              fs::path(path) / "state_groundtruth_estimate0/data.csv"})
      if (fs::is_regular_file(p)) return readEurocCsv(p.string());
    throw InputError(path, "folder holds no mav0/state_groundtruth_estimate0/data.csv");
  }
  return readTrajectory(path);
}

}  // namespace idyvins::io
