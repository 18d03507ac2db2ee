// Affine alignment of a first-appearance patch (pure image math, no files).

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include "frontend/patch_alignment.h"

namespace idyvins::frontend {
namespace {

/// Smooth random texture (blurred noise), CV_8UC1.
cv::Mat texture(int seed, int size = 200) {
  cv::Mat noise(size, size, CV_32F);
  cv::RNG rng(seed);
  rng.fill(noise, cv::RNG::UNIFORM, 0.0, 255.0);
  cv::GaussianBlur(noise, noise, cv::Size(0, 0), 2.0);
  cv::normalize(noise, noise, 20, 235, cv::NORM_MINMAX);
  cv::Mat out;
  noise.convertTo(out, CV_8U);
  return out;
}

/// The image seen after mapping every point p of `src` to A (p - c) + c + shift.
cv::Mat warped(const cv::Mat& src, const Eigen::Matrix2d& A, const Eigen::Vector2d& c, const Eigen::Vector2d& shift) {
  const Eigen::Vector2d b = c + shift - A * c;
  cv::Mat M = (cv::Mat_<double>(2, 3) << A(0, 0), A(0, 1), b.x(), A(1, 0), A(1, 1), b.y());
  cv::Mat out;
  cv::warpAffine(src, out, M, src.size(), cv::INTER_LINEAR, cv::BORDER_REFLECT);
  return out;
}

TEST(PatchAlignment, RecoversAKnownAffineWarp) {
  const cv::Mat image0 = texture(1);
  const Eigen::Vector2d c(100, 100);
  const PatchTemplate tmpl = makePatchTemplate(image0, c, 7);
  ASSERT_TRUE(tmpl.valid);
  Eigen::Matrix2d A;
  A << 1.15, 0.08, -0.05, 0.95;  // scale, shear and a little rotation
  const Eigen::Vector2d shift(3.3, -2.7);
  const cv::Mat image1 = warped(image0, A, c, shift);
  AffineWarp warp;
  warp.t = c + shift + Eigen::Vector2d(1.2, -0.9);  // a drifted KLT position
  const AlignResult r = alignAffine(tmpl, image1, warp);
  ASSERT_TRUE(r.converged);
  EXPECT_LT((warp.t - (c + shift)).norm(), 0.05);
  EXPECT_LT((warp.A - A).cwiseAbs().maxCoeff(), 0.03);
  EXPECT_GT(r.zncc, 0.98);
}

TEST(PatchAlignment, IsInvariantToGainAndBias) {
  const cv::Mat image0 = texture(2);
  const Eigen::Vector2d c(90.5, 110.25);  // subpixel centre
  const PatchTemplate tmpl = makePatchTemplate(image0, c, 7);
  cv::Mat brighter;
  image0.convertTo(brighter, CV_8U, 0.7, 40.0);
  AffineWarp warp;
  warp.t = c + Eigen::Vector2d(-0.8, 0.6);
  const AlignResult r = alignAffine(tmpl, brighter, warp);
  ASSERT_TRUE(r.converged);
  EXPECT_LT((warp.t - c).norm(), 0.05);
  EXPECT_GT(r.zncc, 0.98);
}

TEST(PatchAlignment, TranslationModelFindsTheShiftUnderAGainAndOffsetAndKeepsA) {
  // A right view: the same texture shifted by a disparity, darker and offset (the
  // left/right gain difference a global compensation leaves). The translation model moves
  // only t; A stays the initial guess's. Once with the whole patch, once with a patch cut by
  // the image border (the masked step solves the same model).
  const cv::Mat image0 = texture(6);
  AlignOptions o;
  o.model = WarpModel::kTranslation;
  o.epsilon_px = 1e-3;
  o.max_iterations = 30;
  o.min_inside = 0.5;
  for (const bool cut : {false, true}) {
    const Eigen::Vector2d c = cut ? Eigen::Vector2d(4.3, 98.6) : Eigen::Vector2d(101.3, 98.6);
    const Eigen::Vector2d shift(cut ? 7.0 : -7.0, 0.0);  // whole pixels: the view is not resampled
    const PatchTemplate tmpl = makePatchTemplate(image0, c, 7, 0.5);
    ASSERT_TRUE(tmpl.valid);
    ASSERT_EQ(tmpl.inside.empty(), !cut);
    cv::Mat right;
    warped(image0, Eigen::Matrix2d::Identity(), c, shift).convertTo(right, CV_8U, 0.85, 12.0);
    AffineWarp warp;
    warp.t = c + shift + Eigen::Vector2d(0.6, -0.4);  // KLT's match, off by a fraction of a pixel
    const AlignResult r = alignAffine(tmpl, right, warp, o);
    ASSERT_TRUE(r.converged) << (cut ? "cut" : "whole");
    EXPECT_LT((warp.t - (c + shift)).norm(), 0.01) << (cut ? "cut" : "whole");
    EXPECT_TRUE(warp.A.isApprox(Eigen::Matrix2d::Identity())) << (cut ? "cut" : "whole");
    EXPECT_GT(r.zncc, 0.99);
  }
}

TEST(PatchAlignment, ReportsAPatchThatNoLongerMatches) {
  const cv::Mat image0 = texture(3), other = texture(4);
  const Eigen::Vector2d c(100, 100);
  const PatchTemplate tmpl = makePatchTemplate(image0, c, 7);
  AffineWarp warp;
  warp.t = c;
  const AlignResult r = alignAffine(tmpl, other, warp);
  EXPECT_FALSE(r.converged && r.zncc > 0.8);
}

TEST(PatchAlignment, RejectsFlatPatchesAndPatchesOffTheImage) {
  const cv::Mat flat(100, 100, CV_8U, cv::Scalar(128));
  EXPECT_FALSE(makePatchTemplate(flat, {50, 50}, 7).valid);
  const cv::Mat image = texture(5, 100);
  EXPECT_FALSE(makePatchTemplate(image, {5, 50}, 7).valid);  // the whole patch is asked by default
  // Cut at the border: 7 of the 15 columns have a value and a gradient in the image, less than half.
  EXPECT_FALSE(makePatchTemplate(image, {0.5, 50}, 7, 0.5).valid);
  EXPECT_TRUE(makePatchTemplate(image, {5, 50}, 7, 0.5).valid);
  const PatchTemplate tmpl = makePatchTemplate(image, {50, 50}, 7, 0.5);
  ASSERT_TRUE(tmpl.valid);
  EXPECT_TRUE(tmpl.inside.empty());
  AffineWarp warp;
  warp.t = {97, 50};  // the warped patch leaves the image: a failure unless a cut patch is allowed
  EXPECT_FALSE(alignAffine(tmpl, image, warp).converged);
  AlignOptions cut;
  cut.min_inside = 0.5;
  warp.t = {99.5, 50};  // less than half of the warped patch is in the image
  EXPECT_FALSE(alignAffine(tmpl, image, warp, cut).converged);
}

TEST(PatchAlignment, APatchCutAtTheBorderKeepsThePixelsInTheImage) {
  const cv::Mat image0 = texture(11);
  const Eigen::Vector2d c(3.0, 100.0);  // columns -4 .. 10: 1 .. 10 have a value and a gradient
  const PatchTemplate tmpl = makePatchTemplate(image0, c, 7, 0.5);
  ASSERT_TRUE(tmpl.valid);
  ASSERT_EQ(tmpl.inside.size(), 225u);
  int inside = 0;
  for (unsigned char k : tmpl.inside) inside += k;
  EXPECT_EQ(inside, 10 * 15);
  // The surface moves 4.3 px inwards (the view turns): the cut patch finds it.
  const Eigen::Vector2d shift(4.3, -1.2);
  const cv::Mat image1 = warped(image0, Eigen::Matrix2d::Identity(), c, shift);
  AffineWarp warp;
  warp.t = c + shift + Eigen::Vector2d(0.8, 0.5);
  const AlignResult r = alignAffine(tmpl, image1, warp);
  ASSERT_TRUE(r.converged);
  EXPECT_LT((warp.t - (c + shift)).norm(), 0.05);
  EXPECT_GT(r.zncc, 0.98);
}

TEST(PatchAlignment, AWholePatchFollowsItsSurfaceToTheBorder) {
  const cv::Mat image0 = texture(12);
  const Eigen::Vector2d c(30.0, 120.0);
  const PatchTemplate tmpl = makePatchTemplate(image0, c, 7);
  ASSERT_TRUE(tmpl.valid);
  // The surface moves to 4.4 px from the left border with a little scale: only the
  // part of the warped patch in the image is used.
  Eigen::Matrix2d A;
  A << 1.05, 0.0, 0.0, 1.05;
  const Eigen::Vector2d shift(-25.6, 2.1);
  const cv::Mat image1 = warped(image0, A, c, shift);
  AffineWarp warp;
  warp.t = c + shift + Eigen::Vector2d(-0.7, 0.6);
  AffineWarp whole_only = warp;
  EXPECT_FALSE(alignAffine(tmpl, image1, whole_only).converged);  // by default the whole patch is asked
  AlignOptions cut;
  cut.min_inside = 0.5;
  const AlignResult r = alignAffine(tmpl, image1, warp, cut);
  ASSERT_TRUE(r.converged);
  EXPECT_LT((warp.t - (c + shift)).norm(), 0.05);
  EXPECT_GT(r.zncc, 0.98);
  // Another surface there does not match.
  AffineWarp other;
  other.t = c + shift;
  const AlignResult bad = alignAffine(tmpl, texture(13), other, cut);
  EXPECT_FALSE(bad.converged && bad.zncc > 0.8);
}

TEST(PatchZncc, OneForTheSameSurfaceUnderGainAndShiftLowForAnotherAndMinusOneOffTheImage) {
  const cv::Mat image = texture(7);
  // The same surface 12.25 px to the right, with another gain and bias (a stereo pair).
  cv::Mat shifted = warped(image, Eigen::Matrix2d::Identity(), {100, 100}, {12.25, 0});
  shifted.convertTo(shifted, CV_8U, 0.7, 30);
  EXPECT_GT(patchZncc(image, {100, 100}, shifted, {112.25, 100}, 7), 0.98);
  // Off by 4 px (a neighbouring surface), another texture (an occluder), off the image.
  EXPECT_LT(patchZncc(image, {100, 100}, shifted, {116.25, 100}, 7), 0.8);
  EXPECT_LT(patchZncc(image, {100, 100}, texture(8), {100, 100}, 7), 0.5);
  EXPECT_EQ(patchZncc(image, {100, 100}, shifted, {195, 100}, 7), -1.0);
  // Cut by the border: the offsets inside both images (11 of 15 columns here), when asked.
  EXPECT_EQ(patchZncc(image, {3, 100}, shifted, {15.25, 100}, 7), -1.0);
  EXPECT_GT(patchZncc(image, {3, 100}, shifted, {15.25, 100}, 7, 0.5), 0.98);
  EXPECT_LT(patchZncc(image, {3, 100}, shifted, {19.25, 100}, 7, 0.5), 0.8);
  EXPECT_EQ(patchZncc(image, {100, 100}, shifted, {199.5, 100}, 7, 0.5), -1.0);  // 7 of 15 columns inside
  const cv::Mat flat(200, 200, CV_8U, cv::Scalar(128));
  EXPECT_EQ(patchZncc(image, {100, 100}, flat, {100, 100}, 7), -1.0);
}

TEST(MatchShape, IdentityOnACornerStretchedAlongAnEdgeAndIdentityOffTheImage) {
  // A checkerboard corner: textured alike in u and v.
  cv::Mat checker(60, 60, CV_8UC1, cv::Scalar(40));
  checker(cv::Rect(30, 0, 30, 30)).setTo(200);
  checker(cv::Rect(0, 30, 30, 30)).setTo(200);
  cv::GaussianBlur(checker, checker, cv::Size(0, 0), 1.0);
  const Eigen::Matrix2d corner = matchShape(checker, {29.5, 29.5}, 7, 100.0);
  EXPECT_NEAR(corner(0, 0), 1.0, 0.05);
  EXPECT_NEAR(corner(1, 1), 1.0, 0.05);
  EXPECT_NEAR(corner(0, 1), 0.0, 0.05);
  // A horizontal edge (a roofline against the sky): no gradient along u, so the stretch
  // reaches the cap along u and stays 1 across the edge.
  cv::Mat edge(60, 60, CV_8UC1, cv::Scalar(40));
  edge(cv::Rect(0, 30, 60, 30)).setTo(200);
  cv::GaussianBlur(edge, edge, cv::Size(0, 0), 1.0);
  const Eigen::Matrix2d horizontal = matchShape(edge, {30, 30}, 7, 100.0);
  EXPECT_NEAR(horizontal(0, 0), 100.0, 1e-6);
  EXPECT_NEAR(horizontal(1, 1), 1.0, 1e-6);
  // The same edge turned by 45°: stretched along the diagonal (1, 1).
  cv::Mat diagonal(60, 60, CV_8UC1);
  for (int v = 0; v < 60; ++v)
    for (int u = 0; u < 60; ++u) diagonal.at<uchar>(v, u) = u - v > 0 ? 200 : 40;
  cv::GaussianBlur(diagonal, diagonal, cv::Size(0, 0), 1.0);
  const Eigen::Matrix2d d = matchShape(diagonal, {30, 30}, 7, 100.0);
  const Eigen::Vector2d along = Eigen::Vector2d(1, 1).normalized(), across = Eigen::Vector2d(1, -1).normalized();
  EXPECT_GT(along.dot(d * along), 50.0);
  EXPECT_NEAR(across.dot(d * across), 1.0, 0.05);
  // A cap of 10 holds; the window off the image, a flat patch or a wrong type: identity.
  EXPECT_NEAR(matchShape(edge, {30, 30}, 7, 10.0)(0, 0), 10.0, 1e-6);
  EXPECT_TRUE(matchShape(edge, {5, 30}, 7, 100.0).isApprox(Eigen::Matrix2d::Identity()));
  EXPECT_TRUE(
      matchShape(cv::Mat(60, 60, CV_8UC1, cv::Scalar(90)), {30, 30}, 7, 100.0).isApprox(Eigen::Matrix2d::Identity()));
  cv::Mat as_float;
  edge.convertTo(as_float, CV_32F);
  EXPECT_TRUE(matchShape(as_float, {30, 30}, 7, 100.0).isApprox(Eigen::Matrix2d::Identity()));
}

}  // namespace
}  // namespace idyvins::frontend
