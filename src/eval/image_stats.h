#pragma once
// Image statistics of a camera sequence, to put simulated images beside real ones
// (`idyvins imstats`): brightness and its spread, how much the exposure moves between
// frames, gradient magnitudes, Shi-Tomasi corners, the vignetting profile and the
// left/right brightness ratio. Pure functions on 8-bit images.

#include <array>
#include <cstddef>
#include <opencv2/core/mat.hpp>
#include <vector>

namespace idyvins::eval {

/// Radial rings of the vignetting profile: r = distance to the image centre over the half
/// diagonal, rings [0, 0.2), [0.2, 0.4), ... [0.8, 1.0].
constexpr int kVignettingRings = 5;

/// One image's figures.
struct ImageFigures {
  double mean = 0, stddev = 0;                       ///< gray levels
  double gradient_median = 0, gradient_p90 = 0;      ///< Sobel 3x3 magnitude / 8 (gray levels per px)
  double flat_fraction = 0;                          ///< pixels with gradient magnitude < 2 gray levels per px
  std::size_t corners = 0;                           ///< Shi-Tomasi corners (quality 0.01, min_dist apart)
  std::array<double, kVignettingRings> ring_mean{};  ///< mean brightness per radial ring
};

ImageFigures imageFigures(const cv::Mat& gray, double min_dist_px);

/// A sequence's figures: means over the frames, plus what only a sequence has.
struct SequenceFigures {
  std::size_t frames = 0;
  ImageFigures mean;                                  ///< each field averaged over the left images
  double frame_mean_variation = 0;                    ///< std over frames of the left mean / its average
  std::array<double, kVignettingRings> vignetting{};  ///< ring means / centre ring's, averaged over frames
  double right_left_ratio = 0;                        ///< mean right brightness / mean left brightness
};

class SequenceStatistics {
 public:
  explicit SequenceStatistics(double min_dist_px) : min_dist_px_(min_dist_px) {}
  /// Adds a stereo frame (right may be empty).
  void add(const cv::Mat& left, const cv::Mat& right);
  SequenceFigures figures() const;

 private:
  double min_dist_px_;
  std::vector<ImageFigures> left_;
  double right_sum_ = 0, left_sum_for_right_ = 0;
};

}  // namespace idyvins::eval
