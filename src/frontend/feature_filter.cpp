#include "frontend/feature_filter.h"

#include <opencv2/calib3d.hpp>

namespace idyvins::frontend {

void RansacFilter::apply(const FilterContext& ctx, std::vector<FilterItem>& items) {
  std::vector<cv::Point2f> a, b;
  std::vector<std::size_t> index;
  const auto& p = ctx.camera->params();
  const double f = ctx.camera->focal();
  for (std::size_t i = 0; i < items.size(); ++i) {
    if (!items[i].tracked) continue;
    // Undistorted pixels with the mean focal length (VINS-Fusion uses a fixed 460).
    a.emplace_back(static_cast<float>(f * items[i].prev_xy.x() + p.cx),
                   static_cast<float>(f * items[i].prev_xy.y() + p.cy));
    const Eigen::Vector2d& xy = items[i].feature->xy;
    b.emplace_back(static_cast<float>(f * xy.x() + p.cx), static_cast<float>(f * xy.y() + p.cy));
    index.push_back(i);
  }
  if (a.size() < 8) return;
  std::vector<uchar> inlier;
  cv::findFundamentalMat(a, b, cv::FM_RANSAC, threshold_px_, 0.99, inlier);
  if (inlier.size() != a.size()) return;
  for (std::size_t k = 0; k < index.size(); ++k)
    if (!inlier[k]) items[index[k]].remove = true;
}

void SegFilter::apply(const FilterContext& ctx, std::vector<FilterItem>& items) {
  if (!ctx.mask || ctx.mask->empty()) return;
  const cv::Mat& m = *ctx.mask;
  for (auto& it : items) {
    const int u = static_cast<int>(std::lround(it.feature->uv.x()));
    const int v = static_cast<int>(std::lround(it.feature->uv.y()));
    if (u < 0 || v < 0 || u >= m.cols || v >= m.rows) continue;
    if (m.at<std::uint8_t>(v, u) != 0) it.remove = true;
  }
}

}  // namespace idyvins::frontend
