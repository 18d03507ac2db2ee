#include "frontend/corner_detector.h"

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

namespace idyvins::frontend {

namespace {

/// A candidate corner: response and raster index (row * width + column).
struct Candidate {
  float response;
  std::int32_t index;
};

/// Tiles (row-major, tiles_x by tiles_y) that hold at least one allowed pixel.
std::vector<uchar> openTiles(const cv::Mat& mask, int width, int height, int tile, int tiles_x, int tiles_y) {
  std::vector<uchar> open(static_cast<std::size_t>(tiles_x) * tiles_y, mask.empty() ? 1 : 0);
  if (mask.empty()) return open;
  for (int y = 0; y < height; ++y) {
    const uchar* m = mask.ptr<uchar>(y);
    uchar* row_open = open.data() + static_cast<std::size_t>(y / tile) * tiles_x;
    for (int tx = 0; tx < tiles_x; ++tx) {
      if (row_open[tx]) continue;
      const int x_end = std::min(width, (tx + 1) * tile);
      uchar any = 0;
      for (int x = tx * tile; x < x_end; ++x) any |= m[x];
      row_open[tx] = any ? 1 : 0;
    }
  }
  return open;
}

/// Minimum eigenvalue of the structure tensor (3x3 Sobel gradients summed over a 3x3
/// block, as OpenCV's cornerMinEigenVal with blockSize 3 and ksize 3, same scale) at
/// the pixels of `region`, written into `eig`. `padded` is the image with a 2 px
/// BORDER_REFLECT_101 border. Integer gradients and sums (exact), then the eigenvalue
/// in double: rows of products are computed once and summed in a rolling window.
class ResponseRows {
 public:
  void compute(const cv::Mat& padded, const cv::Rect& region, cv::Mat& eig) {
    const int wc = region.width + 2;  // tensor columns: the region plus one on each side
    for (auto& r : rows_) r.resize(3 * static_cast<std::size_t>(wc));
    for (auto& r : sums_) r.resize(3 * static_cast<std::size_t>(region.width));
    for (auto* v : {&a_, &b_, &c_})
      if (v->size() < region.width) v->resize(region.width);
    // Scale of OpenCV's responses for 8-bit images: gradients / (4 * 3 * 255).
    constexpr double kScale2 = 1.0 / (3060.0 * 3060.0);
    for (int cy = region.y - 1; cy <= region.y + region.height; ++cy) {
      const int k = (cy - region.y + 1) % 3;
      tensorRow(padded, cy, region.x - 1, wc, rows_[k]);
      horizontalSums(rows_[k], region.width, sums_[k]);
      if (cy < region.y + 1) continue;
      // Rows cy-2, cy-1, cy are in the window: the output row is cy - 1.
      // Element-wise array expressions (Eigen vectorizes them, the square root too): the same
      // operations in the same order per pixel, so the same values as a scalar loop.
      const Eigen::Index w = region.width;
      using Row = Eigen::Map<const Eigen::ArrayXi>;
      const auto sum = [&](Eigen::Index part) {
        return (Row(sums_[0].data() + part * w, w) + Row(sums_[1].data() + part * w, w) +
                Row(sums_[2].data() + part * w, w))
            .cast<double>();
      };
      auto a = a_.head(w), b = b_.head(w), c = c_.head(w);
      a = 0.5 * sum(0);
      b = sum(1);
      c = 0.5 * sum(2);
      Eigen::Map<Eigen::ArrayXf>(eig.ptr<float>(cy - 1) + region.x, w) =
          (kScale2 * ((a + c) - ((a - c) * (a - c) + b * b).sqrt())).cast<float>();
    }
  }

 private:
  /// gx², gx gy, gy² (three blocks of n) at columns x0 .. x0+n-1 of image row y.
  static void tensorRow(const cv::Mat& padded, int y, int x0, int n, std::vector<std::int32_t>& row) {
    const uchar* up = padded.ptr<uchar>(y + 1) + x0 + 2;
    const uchar* mid = padded.ptr<uchar>(y + 2) + x0 + 2;
    const uchar* down = padded.ptr<uchar>(y + 3) + x0 + 2;
    std::int32_t* xx = row.data();
    std::int32_t* xy = xx + n;
    std::int32_t* yy = xy + n;
    for (int i = 0; i < n; ++i) {
      const std::int32_t gx = (up[i + 1] - up[i - 1]) + 2 * (mid[i + 1] - mid[i - 1]) + (down[i + 1] - down[i - 1]);
      const std::int32_t gy = (down[i - 1] + 2 * down[i] + down[i + 1]) - (up[i - 1] + 2 * up[i] + up[i + 1]);
      xx[i] = gx * gx;
      xy[i] = gx * gy;
      yy[i] = gy * gy;
    }
  }
  /// Sums of three neighbouring columns: output i covers tensor columns i .. i+2.
  static void horizontalSums(const std::vector<std::int32_t>& row, int w, std::vector<std::int32_t>& sums) {
    const std::size_t n = static_cast<std::size_t>(w) + 2;
    for (int c = 0; c < 3; ++c) {
      const std::int32_t* in = row.data() + c * n;
      std::int32_t* out = sums.data() + static_cast<std::size_t>(c) * w;
      for (int i = 0; i < w; ++i) out[i] = in[i] + in[i + 1] + in[i + 2];
    }
  }
  std::vector<std::int32_t> rows_[3], sums_[3];
  Eigen::ArrayXd a_, b_, c_;  ///< the tensor's halved diagonal sums and its off-diagonal sum, one row
};

/// Responses on every run of open tiles, plus the one-pixel ring the 3x3 suppression reads.
void responsesOnOpenTiles(const cv::Mat& image, const std::vector<uchar>& open, int tile, int tiles_x, int tiles_y,
                          cv::Mat& eig) {
  const cv::Rect whole(0, 0, image.cols, image.rows);
  cv::Mat padded;
  cv::copyMakeBorder(image, padded, 2, 2, 2, 2, cv::BORDER_REFLECT_101);
  ResponseRows rows;
  for (int ty = 0; ty < tiles_y; ++ty) {
    int tx = 0;
    while (tx < tiles_x) {
      if (!open[static_cast<std::size_t>(ty) * tiles_x + tx]) {
        ++tx;
        continue;
      }
      const int first = tx;
      while (tx < tiles_x && open[static_cast<std::size_t>(ty) * tiles_x + tx]) ++tx;
      const cv::Rect run(first * tile - 1, ty * tile - 1, (tx - first) * tile + 2, tile + 2);
      rows.compute(padded, run & whole, eig);
    }
  }
}

/// The tiles of a detection: which are open, and the allowed pixels of a row.
struct TileGrid {
  int width, height, tile, tiles_x, tiles_y;
  std::vector<uchar> open;
  const cv::Mat& mask;
  std::vector<uchar> all_allowed;  ///< one row of 255 when there is no mask
  bool isOpen(int tx, int ty) const { return open[static_cast<std::size_t>(ty) * tiles_x + tx] != 0; }
  const uchar* maskRow(int y) const { return mask.empty() ? all_allowed.data() : mask.ptr<uchar>(y); }
};

/// The strongest response at an allowed pixel of an open tile (0 when there is none).
float strongestResponse(const TileGrid& g, const cv::Mat& eig) {
  float strongest = 0.f;
  bool any = false;
  for (int ty = 0; ty < g.tiles_y; ++ty)
    for (int tx = 0; tx < g.tiles_x; ++tx) {
      if (!g.isOpen(tx, ty)) continue;
      const int x0 = tx * g.tile, x1 = std::min(g.width, x0 + g.tile);
      for (int y = ty * g.tile; y < std::min(g.height, (ty + 1) * g.tile); ++y) {
        const float* e = eig.ptr<float>(y);
        const uchar* m = g.maskRow(y);
        for (int x = x0; x < x1; ++x)
          if (m[x] && (!any || e[x] > strongest)) {
            strongest = e[x];
            any = true;
          }
      }
    }
  return strongest;
}

/// Local maxima of the 3x3 neighbourhood above `threshold`, at allowed pixels away from
/// the image border, strongest first (ties: the later pixel first).
std::vector<Candidate> localMaxima(const TileGrid& g, const cv::Mat& eig, float threshold) {
  std::vector<Candidate> candidates;
  for (int ty = 0; ty < g.tiles_y; ++ty)
    for (int tx = 0; tx < g.tiles_x; ++tx) {
      if (!g.isOpen(tx, ty)) continue;
      const int y_end = std::min(g.height - 1, (ty + 1) * g.tile), x_end = std::min(g.width - 1, (tx + 1) * g.tile);
      for (int y = std::max(1, ty * g.tile); y < y_end; ++y) {
        const float* up = eig.ptr<float>(y - 1);
        const float* row = eig.ptr<float>(y);
        const float* down = eig.ptr<float>(y + 1);
        const uchar* m = g.maskRow(y);
        for (int x = std::max(1, tx * g.tile); x < x_end; ++x) {
          const float v = row[x];
          if (!(v > threshold) || !m[x]) continue;
          if (up[x - 1] > v || up[x] > v || up[x + 1] > v || row[x - 1] > v || row[x + 1] > v || down[x - 1] > v ||
              down[x] > v || down[x + 1] > v)
            continue;
          candidates.push_back({v, y * g.width + x});
        }
      }
    }
  std::sort(candidates.begin(), candidates.end(), [](const Candidate& a, const Candidate& b) {
    return a.response != b.response ? a.response > b.response : a.index > b.index;
  });
  return candidates;
}

/// Strongest first, none closer than min_distance to one already taken (grid of
/// min_distance cells: only the 3x3 cells around a candidate can hold a conflict).
std::vector<cv::Point2f> spreadOut(const std::vector<Candidate>& candidates, int width, int height,
                                   const CornerOptions& options) {
  std::vector<cv::Point2f> corners;
  const std::size_t n_max = static_cast<std::size_t>(options.max_corners);
  if (options.min_distance < 1.0) {
    for (std::size_t i = 0; i < candidates.size() && corners.size() < n_max; ++i)
      corners.emplace_back(static_cast<float>(candidates[i].index % width),
                           static_cast<float>(candidates[i].index / width));
    return corners;
  }
  const int cell = cvRound(options.min_distance);
  const int cells_x = (width + cell - 1) / cell, cells_y = (height + cell - 1) / cell;
  const double min_d2 = options.min_distance * options.min_distance;
  std::vector<std::vector<cv::Point>> grid(static_cast<std::size_t>(cells_x) * cells_y);
  for (const Candidate& c : candidates) {
    const int x = c.index % width, y = c.index / width;
    const int cx = x / cell, cy = y / cell;
    bool free = true;
    for (int gy = std::max(0, cy - 1); free && gy <= std::min(cells_y - 1, cy + 1); ++gy)
      for (int gx = std::max(0, cx - 1); free && gx <= std::min(cells_x - 1, cx + 1); ++gx)
        for (const cv::Point& p : grid[static_cast<std::size_t>(gy) * cells_x + gx]) {
          const double dx = x - p.x, dy = y - p.y;
          if (dx * dx + dy * dy < min_d2) {
            free = false;
            break;
          }
        }
    if (!free) continue;
    grid[static_cast<std::size_t>(cy) * cells_x + cx].emplace_back(x, y);
    corners.emplace_back(static_cast<float>(x), static_cast<float>(y));
    if (corners.size() == n_max) break;
  }
  return corners;
}

}  // namespace

std::vector<cv::Point2f> detectCorners(const cv::Mat& image, const cv::Mat& mask, const CornerOptions& options) {
  if (image.type() != CV_8UC1) throw std::invalid_argument("detectCorners: the image must be CV_8UC1");
  if (!mask.empty() && (mask.type() != CV_8UC1 || mask.size() != image.size()))
    throw std::invalid_argument("detectCorners: the mask must be CV_8UC1 and of the image's size");
  if (options.tile < 4) throw std::invalid_argument("detectCorners: tile must be at least 4 px");
  const int width = image.cols, height = image.rows, tile = options.tile;
  if (options.max_corners <= 0 || width < 3 || height < 3) return {};
  const int tiles_x = (width + tile - 1) / tile, tiles_y = (height + tile - 1) / tile;
  const TileGrid grid{width,   height,
                      tile,    tiles_x,
                      tiles_y, openTiles(mask, width, height, tile, tiles_x, tiles_y),
                      mask,    std::vector<uchar>(mask.empty() ? static_cast<std::size_t>(width) : 0, 255)};
  cv::Mat eig(image.size(), CV_32FC1);
  responsesOnOpenTiles(image, grid.open, tile, tiles_x, tiles_y, eig);
  // Threshold relative to the strongest response at an allowed pixel.
  const float threshold = static_cast<float>(static_cast<double>(strongestResponse(grid, eig)) * options.quality_level);
  return spreadOut(localMaxima(grid, eig, threshold), width, height, options);
}

cv::Mat lensMask(const camera::CameraModel& camera, int width, int height, int margin_px, double max_angle_deg) {
  if (camera.params().type == camera::ModelType::kPinhole) return cv::Mat();  // no lens circle
  cv::Mat mask(height, width, CV_8UC1);
  const double max_tan = max_angle_deg < 90.0 ? std::tan(max_angle_deg * M_PI / 180.0) : HUGE_VAL;
  bool every = true;
  for (int v = 0; v < height; ++v)
    for (int u = 0; u < width; ++u) {
      Eigen::Vector2d xy;
      const bool in = camera.liftToNormalized(Eigen::Vector2d(u, v), xy) && xy.norm() <= max_tan;
      mask.at<std::uint8_t>(v, u) = in ? 255 : 0;
      every = every && in;
    }
  if (every) return cv::Mat();
  if (margin_px > 0)
    cv::erode(mask, mask, cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * margin_px + 1, 2 * margin_px + 1)));
  return mask;
}

}  // namespace idyvins::frontend
