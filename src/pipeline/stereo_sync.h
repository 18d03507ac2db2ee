#pragma once
// Stereo pairs from two image streams that arrive separately (ROS topics, a live driver):
// images are paired by their stamps as VINS-Fusion's node pairs /cam0 and /cam1, and as
// the EuRoC and bag readers pair a dataset's rows, so a live run sees the pairs an offline
// run of the same data sees.

#include <cstddef>
#include <deque>
#include <optional>

#include "core/measurements.h"
#include "core/time.h"

namespace idyvins::pipeline {

/// Pairs left (camera 0) and right (camera 1) images by stamp. An image whose partner
/// cannot come any more (the other camera's next image is later than its stamp plus the
/// tolerance) is dropped and counted; so is an image not after its camera's previous one.
/// Not thread-safe: one caller (or a caller-held lock).
class StereoSync {
 public:
  /// `tolerance_ns`: the largest |t_left - t_right| of a pair (the readers' 1 ms by default).
  explicit StereoSync(TimeNs tolerance_ns = 1'000'000) : tolerance_ns_(tolerance_ns) {}

  /// Adds an 8-bit gray image of `camera` (0 left, 1 right). Returns false (and counts it)
  /// when its stamp is not after the previous image of that camera.
  bool add(int camera, TimeNs t_ns, const cv::Mat& image);
  /// The oldest complete pair (stamp of the left image, index counting pairs from 0), or
  /// nothing when no pair is complete yet.
  std::optional<StereoFrame> next();

  std::size_t unpaired(int camera) const { return unpaired_[camera]; }  ///< dropped without a partner
  std::size_t outOfOrder(int camera) const { return out_of_order_[camera]; }
  std::size_t waiting(int camera) const { return queue_[camera].size(); }  ///< images not yet paired

 private:
  struct Image {
    TimeNs t_ns;
    cv::Mat image;
  };
  TimeNs tolerance_ns_;
  std::deque<Image> queue_[2];
  TimeNs last_t_ns_[2] = {-1, -1};
  std::size_t unpaired_[2] = {0, 0}, out_of_order_[2] = {0, 0};
  std::size_t pairs_ = 0;
};

}  // namespace idyvins::pipeline
