// detectCorners against OpenCV's goodFeaturesToTrack (the selection rule it
// reproduces), on a real EuRoC image and a rendered one, with tracker-like masks.

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <random>

#include "frontend/corner_detector.h"
#include "sim/simulator.h"

namespace {

using idyvins::frontend::CornerOptions;
using idyvins::frontend::detectCorners;

/// A mask closed around `n` random points (radius r), as the tracker closes it
/// around its existing features.
cv::Mat circleMask(cv::Size size, int n, int r, unsigned seed) {
  cv::Mat mask(size, CV_8UC1, cv::Scalar(255));
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> ux(0, size.width - 1), uy(0, size.height - 1);
  for (int i = 0; i < n; ++i) cv::circle(mask, cv::Point(ux(rng), uy(rng)), r, cv::Scalar(0), cv::FILLED);
  return mask;
}

cv::Mat realImage() {
  const std::string path =
      std::string(IDYVINS_SHARED_DATA) + "/euroc_v101_micro/mav0/cam0/data/1403715273262142976.png";
  return cv::imread(path, cv::IMREAD_GRAYSCALE);
}

cv::Mat renderedImage() {
  idyvins::sim::SimOptions o;
  o.scene.scene = "city";
  o.scene.level = idyvins::sim::Level::kHigh;
  o.duration_s = 1.0;
  const idyvins::sim::Scene scene(o);
  return scene.renderFrame(5).cam[0].image;
}

/// Share of OpenCV's corners that detectCorners returns at the same pixel.
double agreement(const std::vector<cv::Point2f>& ours, const std::vector<cv::Point2f>& reference) {
  std::size_t same = 0;
  for (const auto& c : reference)
    if (std::find(ours.begin(), ours.end(), c) != ours.end()) ++same;
  return reference.empty() ? 1.0 : static_cast<double>(same) / reference.size();
}

void expectLikeOpenCv(const cv::Mat& image, const cv::Mat& mask, int max_corners, double min_distance) {
  std::vector<cv::Point2f> reference;
  cv::goodFeaturesToTrack(image, reference, max_corners, 0.01, min_distance, mask);
  CornerOptions o;
  o.max_corners = max_corners;
  o.min_distance = min_distance;
  const std::vector<cv::Point2f> ours = detectCorners(image, mask, o);
  ASSERT_FALSE(reference.empty());
  // Exact integer tensor sums instead of OpenCV's float ones: the responses agree to
  // float rounding, so the selection differs only where two candidates nearly tie.
  EXPECT_LE(std::abs(static_cast<int>(ours.size()) - static_cast<int>(reference.size())), 1);
  const double same = agreement(ours, reference);
  std::printf("same corners as goodFeaturesToTrack: %.1f %% of %zu\n", 100.0 * same, reference.size());
  EXPECT_GE(same, 0.95);
  // Every corner is allowed by the mask and at least min_distance from the others.
  for (std::size_t i = 0; i < ours.size(); ++i) {
    if (!mask.empty()) {
      EXPECT_NE(mask.at<uchar>(cvRound(ours[i].y), cvRound(ours[i].x)), 0);
    }
    for (std::size_t j = 0; j < i; ++j) EXPECT_GE(cv::norm(ours[i] - ours[j]), min_distance);
  }
}

TEST(CornerDetector, SelectsAsGoodFeaturesToTrackOnARealImage) {
  const cv::Mat image = realImage();
  ASSERT_FALSE(image.empty());
  expectLikeOpenCv(image, cv::Mat(), 150, 30.0);
  for (unsigned seed = 1; seed <= 4; ++seed) expectLikeOpenCv(image, circleMask(image.size(), 120, 30, seed), 40, 30.0);
  expectLikeOpenCv(image, circleMask(image.size(), 60, 20, 9), 300, 5.0);
}

TEST(CornerDetector, SelectsAsGoodFeaturesToTrackOnARenderedImage) {
  const cv::Mat image = renderedImage();
  ASSERT_FALSE(image.empty());
  expectLikeOpenCv(image, cv::Mat(), 150, 30.0);
  for (unsigned seed = 1; seed <= 4; ++seed) expectLikeOpenCv(image, circleMask(image.size(), 120, 30, seed), 40, 30.0);
}

TEST(CornerDetector, FindsTheCornersOfASquareAndHonoursTheMask) {
  cv::Mat image(120, 160, CV_8UC1, cv::Scalar(40));
  cv::rectangle(image, cv::Rect(40, 30, 60, 50), cv::Scalar(220), cv::FILLED);
  CornerOptions o;
  o.max_corners = 10;
  o.min_distance = 10.0;
  o.tile = 16;
  const std::vector<cv::Point2f> all = detectCorners(image, cv::Mat(), o);
  ASSERT_EQ(all.size(), 4u);
  for (const cv::Point2f c : {cv::Point2f(40, 30), cv::Point2f(99, 30), cv::Point2f(40, 79), cv::Point2f(99, 79)}) {
    const bool near = std::any_of(all.begin(), all.end(), [&](const cv::Point2f& p) { return cv::norm(p - c) <= 1.5; });
    EXPECT_TRUE(near) << c;
  }
  cv::Mat mask(image.size(), CV_8UC1, cv::Scalar(0));
  mask(cv::Rect(0, 0, 70, 120)).setTo(255);  // left half only
  const std::vector<cv::Point2f> left = detectCorners(image, mask, o);
  ASSERT_EQ(left.size(), 2u);
  for (const auto& p : left) EXPECT_LT(p.x, 70.f);
  EXPECT_TRUE(detectCorners(image, cv::Mat(image.size(), CV_8UC1, cv::Scalar(0)), o).empty());
}

TEST(CornerDetector, RejectsWrongInputTypes) {
  CornerOptions o;
  EXPECT_THROW(detectCorners(cv::Mat(10, 10, CV_32FC1), cv::Mat(), o), std::invalid_argument);
  EXPECT_THROW(detectCorners(cv::Mat(10, 10, CV_8UC1), cv::Mat(5, 5, CV_8UC1), o), std::invalid_argument);
}

}  // namespace
