#include "io/data_source.h"

#include <filesystem>

namespace idyvins::io {

EurocSource::EurocSource(EurocDataset dataset, int expected_width, int expected_height, bool load_masks)
    : dataset_(std::move(dataset)), width_(expected_width), height_(expected_height), load_masks_(load_masks) {}

std::optional<Measurement> EurocSource::next() {
  const bool imu_left = next_imu_ < dataset_.imu.size();
  const bool frames_left = next_pair_ < dataset_.pairs.size();
  if (!imu_left && !frames_left) return std::nullopt;
  if (imu_left && (!frames_left || dataset_.imu[next_imu_].t_ns <= dataset_.pairs[next_pair_].t_ns)) {
    return Measurement{dataset_.imu[next_imu_++]};
  }
  const StereoPair& pair = dataset_.pairs[next_pair_];
  const auto csv = [&](const char* cam) { return (std::filesystem::path(dataset_.root) / cam / "data.csv").string(); };
  StereoFrame frame;
  frame.t_ns = pair.t_ns;
  frame.index = next_pair_;
  frame.left = loadGrayImage(dataset_.cam0[pair.i0], csv("cam0"), width_, height_);
  if (dataset_.stereo()) frame.right = loadGrayImage(dataset_.cam1[pair.i1], csv("cam1"), width_, height_);
  if (load_masks_) {
    const std::filesystem::path image(dataset_.cam0[pair.i0].path);
    ImageRecord mask = dataset_.cam0[pair.i0];
    mask.path = (image.parent_path().parent_path() / "mask" / image.filename()).string();
    frame.left_mask = loadGrayImage(mask, csv("cam0"), width_, height_);
  }
  ++next_pair_;
  return Measurement{std::move(frame)};
}

}  // namespace idyvins::io
