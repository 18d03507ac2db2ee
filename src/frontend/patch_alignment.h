#pragma once
// Affine alignment of a feature's first-appearance patch to a later image
// (inverse-compositional Lucas-Kanade, Baker & Matthews 2004; the affine
// consistency check of Shi & Tomasi 1994). Frame-to-frame KLT accumulates a
// random-walk drift and slides along edges; aligning the original patch
// removes the drift and exposes the tracks whose appearance no longer matches.
//
// Pixel convention: (u, v) = (column, row), pixel centres at integers.

#include <Eigen/Core>
#include <opencv2/core/mat.hpp>
#include <vector>

namespace idyvins::frontend {

/// Affine warp from template offsets x (px, relative to the patch centre) to
/// image pixels: uv = A x + t.
struct AffineWarp {
  Eigen::Matrix2d A = Eigen::Matrix2d::Identity();
  Eigen::Vector2d t = Eigen::Vector2d::Zero();  ///< image position of the patch centre (px)
};

/// A square patch of (2 half + 1)² pixels with what inverse-compositional
/// alignment precomputes: zero-mean, unit-norm intensities, steepest-descent
/// images and the inverse Gauss-Newton Hessian.
struct PatchTemplate {
  int half = 0;
  std::vector<float> values;     ///< normalized intensities, row-major
  std::vector<float> sd;         ///< 6 steepest-descent values per pixel
  Eigen::Matrix<double, 6, 6> H_inv;
  bool valid = false;            ///< false: off the image or without texture
};

/// Options of alignAffine.
struct AlignOptions {
  int max_iterations = 10;
  double epsilon_px = 0.01;          ///< stops when the centre moves less than this
  double max_scale_change = 3.0;     ///< singular values of A outside [1/this, this]: diverged
};

/// Result of alignAffine: whether it converged and how well the patch matches.
struct AlignResult {
  bool converged = false;
  double zncc = -1.0;   ///< zero-mean normalized cross-correlation at the solution, in [-1, 1]
  int iterations = 0;
};

/// Cuts the template around `uv_center` (px, may be subpixel; bilinear) from a
/// CV_8UC1 image. Invalid when the patch (plus a 1 px margin) leaves the image
/// or has (almost) no texture.
PatchTemplate makePatchTemplate(const cv::Mat& image, const Eigen::Vector2d& uv_center, int half);

/// Refines `warp` so that the image under it matches the template (gain and
/// bias invariant). `warp` holds the initial guess and, on return, the last
/// iterate. Never throws; non-convergence or leaving the image is reported.
AlignResult alignAffine(const PatchTemplate& tmpl, const cv::Mat& image, AffineWarp& warp,
                        const AlignOptions& options = {});

/// Zero-mean normalized cross-correlation of the (2 half + 1)² patches (bilinear) around
/// `uv_a` in `a` and `uv_b` in `b` (CV_8UC1); -1 when a patch leaves its image or is flat.
/// Gain and bias invariant, no warp: for two views of the same surface seen alike
/// (a stereo match).
double patchZncc(const cv::Mat& a, const Eigen::Vector2d& uv_a, const cv::Mat& b, const Eigen::Vector2d& uv_b,
                 int half);

}  // namespace idyvins::frontend
