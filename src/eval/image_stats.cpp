#include "eval/image_stats.h"

#include <algorithm>
#include <cmath>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

namespace idyvins::eval {
namespace {

double quantile(std::vector<float>& v, double q) {
  if (v.empty()) return 0;
  const auto k =
      static_cast<std::size_t>(std::min<double>(static_cast<double>(v.size()) - 1, q * static_cast<double>(v.size())));
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}

}  // namespace

ImageFigures imageFigures(const cv::Mat& gray, double min_dist_px) {
  CV_Assert(gray.type() == CV_8UC1 && !gray.empty());
  ImageFigures f;
  cv::Scalar m, s;
  cv::meanStdDev(gray, m, s);
  f.mean = m[0];
  f.stddev = s[0];
  // Sobel 3x3 responds 8x to a unit gradient: divide for gray levels per pixel.
  cv::Mat gx, gy, mag;
  cv::Sobel(gray, gx, CV_32F, 1, 0, 3, 1.0 / 8.0);
  cv::Sobel(gray, gy, CV_32F, 0, 1, 3, 1.0 / 8.0);
  cv::magnitude(gx, gy, mag);
  std::vector<float> g(mag.begin<float>(), mag.end<float>());
  f.flat_fraction = static_cast<double>(std::count_if(g.begin(), g.end(), [](float v) { return v < 2.0f; })) /
                    static_cast<double>(g.size());
  f.gradient_p90 = quantile(g, 0.9);
  f.gradient_median = quantile(g, 0.5);
  std::vector<cv::Point2f> corners;
  cv::goodFeaturesToTrack(gray, corners, 0, 0.01, min_dist_px);
  f.corners = corners.size();
  std::array<double, kVignettingRings> sum{};
  std::array<std::size_t, kVignettingRings> n{};
  const double cx = 0.5 * (gray.cols - 1), cy = 0.5 * (gray.rows - 1);
  const double half_diag = 0.5 * std::hypot(gray.cols, gray.rows);
  for (int y = 0; y < gray.rows; ++y) {
    const std::uint8_t* row = gray.ptr<std::uint8_t>(y);
    for (int x = 0; x < gray.cols; ++x) {
      const int ring =
          std::min(kVignettingRings - 1, static_cast<int>(std::hypot(x - cx, y - cy) / half_diag * kVignettingRings));
      sum[ring] += row[x];
      ++n[ring];
    }
  }
  for (int i = 0; i < kVignettingRings; ++i) f.ring_mean[i] = n[i] ? sum[i] / static_cast<double>(n[i]) : 0.0;
  return f;
}

void SequenceStatistics::add(const cv::Mat& left, const cv::Mat& right) {
  left_.push_back(imageFigures(left, min_dist_px_));
  if (!right.empty()) {
    right_sum_ += cv::mean(right)[0];
    left_sum_for_right_ += left_.back().mean;
  }
}

SequenceFigures SequenceStatistics::figures() const {
  SequenceFigures s;
  s.frames = left_.size();
  if (left_.empty()) return s;
  const double n = static_cast<double>(left_.size());
  double var = 0;
  for (const ImageFigures& f : left_) {
    s.mean.mean += f.mean / n;
    s.mean.stddev += f.stddev / n;
    s.mean.gradient_median += f.gradient_median / n;
    s.mean.gradient_p90 += f.gradient_p90 / n;
    s.mean.flat_fraction += f.flat_fraction / n;
    s.mean.corners += f.corners;
    for (int i = 0; i < kVignettingRings; ++i) {
      s.mean.ring_mean[i] += f.ring_mean[i] / n;
      s.vignetting[i] += (f.ring_mean[0] > 0 ? f.ring_mean[i] / f.ring_mean[0] : 0.0) / n;
    }
  }
  s.mean.corners = static_cast<std::size_t>(std::lround(static_cast<double>(s.mean.corners) / n));
  for (const ImageFigures& f : left_) var += (f.mean - s.mean.mean) * (f.mean - s.mean.mean) / n;
  s.frame_mean_variation = s.mean.mean > 0 ? std::sqrt(var) / s.mean.mean : 0.0;
  s.right_left_ratio = left_sum_for_right_ > 0 ? right_sum_ / left_sum_for_right_ : 0.0;
  return s;
}

}  // namespace idyvins::eval
