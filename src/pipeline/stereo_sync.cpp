#include "pipeline/stereo_sync.h"

#include <stdexcept>

namespace idyvins::pipeline {

bool StereoSync::add(int camera, TimeNs t_ns, const cv::Mat& image) {
  if (camera != 0 && camera != 1) throw std::invalid_argument("StereoSync::add: camera must be 0 or 1");
  if (last_t_ns_[camera] >= 0 && t_ns <= last_t_ns_[camera]) {
    ++out_of_order_[camera];
    return false;
  }
  last_t_ns_[camera] = t_ns;
  queue_[camera].push_back({t_ns, image});
  return true;
}

std::optional<StereoFrame> StereoSync::next() {
  auto& left = queue_[0];
  auto& right = queue_[1];
  while (!left.empty() && !right.empty()) {
    const TimeNs dt = left.front().t_ns - right.front().t_ns;
    if (dt < -tolerance_ns_) {  // the right stream is past this left image's partner
      left.pop_front();
      ++unpaired_[0];
    } else if (dt > tolerance_ns_) {
      right.pop_front();
      ++unpaired_[1];
    } else {
      StereoFrame f;
      f.t_ns = left.front().t_ns;
      f.index = pairs_++;
      f.left = left.front().image;
      f.right = right.front().image;
      left.pop_front();
      right.pop_front();
      return f;
    }
  }
  return std::nullopt;
}

}  // namespace idyvins::pipeline
