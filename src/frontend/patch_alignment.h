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

/// `image` with its brightness mapped to `reference`'s: I' = a I + b with a and b such that
/// the mean and standard deviation equal the reference's (8-bit, saturated). Returns
/// `image` itself (no copy) when the standard deviations and the means already agree
/// within `tolerance` (relative).
cv::Mat matchBrightness(const cv::Mat& image, const cv::Mat& reference, double tolerance = 0.01);

/// Affine warp from template offsets x (px, relative to the patch centre) to
/// image pixels: uv = A x + t.
struct AffineWarp {
  Eigen::Matrix2d A = Eigen::Matrix2d::Identity();
  Eigen::Vector2d t = Eigen::Vector2d::Zero();  ///< image position of the patch centre (px)
};

/// A square patch of (2 half + 1)² pixels with what inverse-compositional
/// alignment precomputes: zero-mean, unit-norm intensities, steepest-descent
/// images and the inverse Gauss-Newton Hessian. A patch cut at the image border
/// marks the pixels it holds in `inside`; its values, steepest-descent images and
/// Hessian are then those of the pixels inside (the others are 0).
struct PatchTemplate {
  int half = 0;
  std::vector<float> values;  ///< normalized intensities, row-major
  std::vector<float> sd;      ///< 6 steepest-descent values per pixel
  Eigen::Matrix<double, 6, 6> H_inv;
  Eigen::Matrix2d H_translation_inv;  ///< inverse of H's translation block (WarpModel::kTranslation)
  std::vector<unsigned char> inside;  ///< per pixel, 1 = in the image; empty: the whole square
  double min_inside = 1.0;            ///< the share asked when it was cut (alignAffine asks no more of it)
  bool valid = false;                 ///< false: too little of it in the image, or without texture
};

/// The warps alignAffine searches: the whole affine group, or translations only (the
/// other four parameters held at the initial guess's A).
enum class WarpModel { kAffine, kTranslation };

/// Options of alignAffine.
struct AlignOptions {
  WarpModel model = WarpModel::kAffine;
  int max_iterations = 10;
  double epsilon_px = 0.01;       ///< stops when the centre moves less than this
  double max_scale_change = 3.0;  ///< singular values of A outside [1/this, this]: diverged
  /// Share of the template's square that must lie in the image (and in the template) at
  /// every iteration; 1: the whole warped patch in the image, else failure. Below 1, an
  /// iteration whose warped patch is cut by the border uses the pixels inside both, its
  /// Hessian built from them.
  double min_inside = 1.0;
};

/// Result of alignAffine: whether it converged and how well the patch matches.
struct AlignResult {
  bool converged = false;
  double zncc = -1.0;  ///< zero-mean normalized cross-correlation at the solution, in [-1, 1]
  int iterations = 0;
};

/// Cuts the template around `uv_center` (px, may be subpixel; bilinear) from a
/// CV_8UC1 image. Invalid when the patch (plus a 1 px margin) leaves the image, unless
/// `min_inside` < 1: then the pixels whose value and gradient lie in the image are kept
/// (`inside`) when they are at least that share of the square. Invalid as well when the
/// patch has (almost) no texture (in both directions).
PatchTemplate makePatchTemplate(const cv::Mat& image, const Eigen::Vector2d& uv_center, int half,
                                double min_inside = 1.0);

/// Refines `warp` so that the image under it matches the template (gain and
/// bias invariant). `warp` holds the initial guess and, on return, the last
/// iterate. A template cut at the border, or a warp leaving the image with
/// `options.min_inside` < 1, is aligned on the pixels inside both (AlignOptions).
/// Never throws; non-convergence or leaving the image is reported.
AlignResult alignAffine(const PatchTemplate& tmpl, const cv::Mat& image, AffineWarp& warp,
                        const AlignOptions& options = {});

/// Zero-mean normalized cross-correlation of the (2 half + 1)² patches (bilinear) around
/// `uv_a` in `a` and `uv_b` in `b` (CV_8UC1); -1 when a patch leaves its image or is flat.
/// With `min_inside` < 1, a patch cut by the border is correlated over the offsets at
/// which both points lie in their images, when they are at least that share of the square.
/// Gain and bias invariant, no warp: for two views of the same surface seen alike
/// (a stereo match).
double patchZncc(const cv::Mat& a, const Eigen::Vector2d& uv_a, const cv::Mat& b, const Eigen::Vector2d& uv_b, int half,
                 double min_inside = 1.0);

/// Shape of a point match's noise at `uv` (px) in a CV_8UC1 image: λ_max H⁻¹ with H the
/// structure tensor (summed outer products of the central-difference gradients) over the
/// (2 half + 1)² pixels around the rounded pixel, its eigenvalues clamped to [1, max_ratio].
/// A corner textured alike in every direction gives the identity; an edge-like one is
/// stretched along its edge by λ_max / λ_min, the direction its position is not measured
/// in (the Cramér-Rao bound of a translation's estimate, Shi & Tomasi 1994, up to the
/// intensity noise). Identity when the window leaves the image or has no texture.
Eigen::Matrix2d matchShape(const cv::Mat& image, const Eigen::Vector2d& uv, int half, double max_ratio);

}  // namespace idyvins::frontend
