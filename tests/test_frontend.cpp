// The front end on rendered sequences with known geometry (the simulator in memory).

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <functional>
#include <map>
#include <memory>
#include <numeric>
#include <opencv2/core.hpp>
#include <set>

#include "frontend/corner_detector.h"
#include "frontend/feature_tracker.h"
#include "frontend/patch_alignment.h"
#include "frontend/track_quality.h"
#include "io/data_source.h"
#include "io/euroc_dataset.h"
#include "sim/camera_effects.h"
#include "sim/simulator.h"
#include "sim_scenes.h"

namespace idyvins::frontend {
namespace {

using Eigen::Vector2d;
using Eigen::Vector3d;

using test::crossingVehicleScene;
using test::options;
using test::stereo;
using test::truePrior;

/// Depth at a subpixel position when the 3x3 neighbourhood lies on one smooth surface.
bool smoothDepth(const cv::Mat& depth, const Vector2d& uv, double& z, int r = 2) {
  const int u = static_cast<int>(std::lround(uv.x())), v = static_cast<int>(std::lround(uv.y()));
  if (u < r || v < r || u >= depth.cols - r || v >= depth.rows - r) return false;
  float lo = 1e30f, hi = 0;
  for (int dv = -r; dv <= r; ++dv)
    for (int du = -r; du <= r; ++du) {
      const float d = depth.at<float>(v + dv, u + du);
      lo = std::min(lo, d);
      hi = std::max(hi, d);
    }
  if (lo <= 0 || hi - lo > 0.03f * lo) return false;  // an occlusion edge or the sky
  // Bilinear interpolation.
  const double x = uv.x(), y = uv.y();
  const int x0 = static_cast<int>(std::floor(x)), y0 = static_cast<int>(std::floor(y));
  const double ax = x - x0, ay = y - y0;
  z = (1 - ay) * ((1 - ax) * depth.at<float>(y0, x0) + ax * depth.at<float>(y0, x0 + 1)) +
      ay * ((1 - ax) * depth.at<float>(y0 + 1, x0) + ax * depth.at<float>(y0 + 1, x0 + 1));
  return true;
}

/// Tracking accuracy over the first 100 frames of a static city sequence, against
/// the true projections of each track's first-frame 3D point.
struct TrackAccuracy {
  double median = 0, p99 = 0, switch_rate = 0, v99 = 0;
  std::size_t steps = 0;
};

/// `change` edits the tracker keys of the rendered rig's config.
TrackAccuracy measureTrackAccuracy(const std::function<void(TrackerParams&)>& change = {},
                                   const std::string& realism = "none") {
  sim::SimOptions o = options("city", sim::Level::kNone, 5.0);
  o.realism = sim::realismPreset(realism);
  const sim::Scene scene(o);
  const Config& rig = scene.rig();
  TrackerParams params = rig.tracker;
  if (change) change(params);
  FeatureTracker tracker(rig.rig(), params);
  const auto cam = camera::makeCamera(rig.cams[0]);
  std::map<std::uint64_t, Vector3d> point_w;  // 3D point of each track, from its first frame
  std::map<std::uint64_t, bool> switched;
  std::vector<double> errors, vertical;
  std::vector<double> by_len[10];
  std::size_t steps = 0, switches = 0, stereo_total = 0;
  for (std::size_t k = 0; k < 101; ++k) {
    const sim::SceneFrame f = scene.renderFrame(k);
    const FeatureFrame out = tracker.track(stereo(f), MotionPrior{}, nullptr);
    const Eigen::Isometry3d T_w_c = f.T_w_b * rig.T_b_c[0];
    for (const Feature& ft : out.features) {
      if (ft.has_right) {
        ++stereo_total;
        vertical.push_back(std::abs(rig.cams[0].fy * (ft.xy.y() - ft.xy_right.y())));
      }
      if (ft.track_length == 1) {
        double z;
        if (smoothDepth(f.cam[0].depth, ft.uv, z)) point_w[ft.id] = T_w_c * (Vector3d(ft.xy.x(), ft.xy.y(), 1.0) * z);
        continue;
      }
      const auto it = point_w.find(ft.id);
      if (it == point_w.end() || switched[ft.id]) continue;
      Vector2d uv;
      if (!cam->project(T_w_c.inverse() * it->second, uv)) continue;
      const double e = (uv - ft.uv).norm();
      ++steps;
      if (e > 3.0) {  // the track left its world point
        ++switches;
        switched[ft.id] = true;
        continue;
      }
      errors.push_back(e);
      by_len[std::min(ft.track_length / 10, 9)].push_back(e);
    }
  }
  for (int b = 0; b < 10; ++b) {
    auto& v = by_len[b];
    if (v.empty()) continue;
    std::sort(v.begin(), v.end());
    std::printf("track length %d-%d: n %zu median %.3f p99 %.3f\n", 10 * b, 10 * b + 9, v.size(), v[v.size() / 2],
                v[v.size() * 99 / 100]);
  }
  TrackAccuracy acc;
  if (errors.empty() || vertical.empty()) return acc;
  std::sort(errors.begin(), errors.end());
  std::sort(vertical.begin(), vertical.end());
  acc.median = errors[errors.size() / 2];
  acc.p99 = errors[errors.size() * 99 / 100];
  acc.steps = errors.size();
  acc.switch_rate = static_cast<double>(switches) / steps;
  acc.v99 = vertical[vertical.size() * 99 / 100];
  std::printf(
      "tracking over 100 frames: %zu track steps, median error %.3f px, p99 %.3f px, id switches %zu "
      "(%.3f%%); stereo matches %zu, vertical residual p99 %.3f px\n",
      steps, acc.median, acc.p99, switches, 100 * acc.switch_rate, stereo_total, acc.v99);
  return acc;
}

TEST(FeatureTracker, TracksFollowTheTrueProjectionsOnAStaticSequence) {
  // Measured: 9083 steps, median 0.071 px, p99 0.646 px, no id switch.
  const TrackAccuracy acc = measureTrackAccuracy();
  ASSERT_GT(acc.steps, 3000u);
  EXPECT_LT(acc.median, 0.1);
  EXPECT_LT(acc.p99, 1.0);  // the front-end issue's target was 1.5 px; KLT alone: 2.09 px
  EXPECT_LT(acc.switch_rate, 0.001);
  EXPECT_LT(acc.v99, 1.0);
}

TEST(FeatureTracker, CornersAtTheBorderWithACutFirstPatchStayAccurate) {
  // Corners up to 2 px from the border, their first patch cut where the image ends, and
  // tracks aligned up to the border (patch_min_inside 0.5), against the default (no
  // corner within 9 px, the whole patch asked): the tracks near the border are kept
  // (more track steps) and stay about as accurate. Measured: 9430 vs 9083 steps, median
  // 0.077 vs 0.071 px, p99 0.608 vs 0.646 px; within 12 px of the border median 0.082 px.
  const TrackAccuracy near = measureTrackAccuracy([](TrackerParams& cut) {
    cut.corner_margin_px = 2;
    cut.patch_min_inside = 0.5;
  });
  const TrackAccuracy away = measureTrackAccuracy();
  EXPECT_GT(near.steps, away.steps + away.steps / 50);
  EXPECT_LT(near.p99, 1.0);
  EXPECT_LT(near.median, 0.1);
}

TEST(FeatureTracker, TracksFollowTheTrueProjectionsAtRealismEuroc) {
  // The same measure on images with the euroc realism preset (vignetting, 10 % darker
  // right camera, auto-exposure, motion blur, defocus, shot/read noise, plain ground and
  // walls). Clean images above: see TracksFollowTheTrueProjectionsOnAStaticSequence.
  const TrackAccuracy acc = measureTrackAccuracy({}, "euroc");
  RecordProperty("median_px", std::to_string(acc.median));
  RecordProperty("p99_px", std::to_string(acc.p99));
  RecordProperty("switch_rate", std::to_string(acc.switch_rate));
  // Measured: 8836 steps, median 0.132 px, p99 0.828 px, no id switch (clean images:
  // 9083, 0.071 px, 0.646 px); when added, before corners were kept off the image border:
  // 8584 steps, median 0.164 px, p99 2.52 px, id switches 0.08 %.
  ASSERT_GT(acc.steps, 6000u);
  EXPECT_LT(acc.median, 0.2);
  EXPECT_LT(acc.p99, 1.2);
  EXPECT_LT(acc.switch_rate, 0.001);
}

/// Right-image matches against the true disparity (rendered depth at the left pixel,
/// smooth surfaces only): signed horizontal error of the right match (px; < 0: disparity
/// overestimated, the point seen too near), over 100 frames of city none seed 1.
struct StereoAccuracy {
  std::size_t n = 0;
  double mean = 0, median = 0, mad = 0, p99_abs = 0;
  double near_mean = 0, far_mean = 0;  ///< mean signed error at depth < 10 m and >= 10 m
  /// Mean signed error and count per true disparity: < 2, 2-5, 5-10, >= 10 px.
  std::array<double, 4> bin_mean{};
  std::array<std::size_t, 4> bin_n{};
};

int disparityBin(double disparity_px) {
  return disparity_px < 2 ? 0 : disparity_px < 5 ? 1 : disparity_px < 10 ? 2 : 3;
}

StereoAccuracy summarize(std::vector<double> err, const std::array<std::vector<double>, 4>& bins, double near_sum,
                         std::size_t near_n, double far_sum, std::size_t far_n, const std::string& label) {
  StereoAccuracy acc;
  if (err.empty()) return acc;
  acc.n = err.size();
  acc.mean = std::accumulate(err.begin(), err.end(), 0.0) / static_cast<double>(err.size());
  acc.near_mean = near_n ? near_sum / static_cast<double>(near_n) : 0;
  acc.far_mean = far_n ? far_sum / static_cast<double>(far_n) : 0;
  std::vector<double> sorted = err, dev;
  std::sort(sorted.begin(), sorted.end());
  acc.median = sorted[sorted.size() / 2];
  for (double e : err) dev.push_back(std::abs(e - acc.median));
  std::sort(dev.begin(), dev.end());
  acc.mad = dev[dev.size() / 2];
  for (double& e : sorted) e = std::abs(e);
  std::sort(sorted.begin(), sorted.end());
  acc.p99_abs = sorted[sorted.size() * 99 / 100];
  for (std::size_t b = 0; b < bins.size(); ++b) {
    acc.bin_n[b] = bins[b].size();
    acc.bin_mean[b] = bins[b].empty()
                          ? 0
                          : std::accumulate(bins[b].begin(), bins[b].end(), 0.0) / static_cast<double>(bins[b].size());
  }
  std::printf(
      "stereo (%s): %zu matches, signed error mean %+.4f px (near %+.4f, far %+.4f), median %+.4f, MAD %.4f, "
      "p99 |e| %.3f px; by true disparity < 2 / 2-5 / 5-10 / >= 10 px: %+.4f (%zu) / %+.4f (%zu) / %+.4f (%zu) / "
      "%+.4f (%zu)\n",
      label.c_str(), acc.n, acc.mean, acc.near_mean, acc.far_mean, acc.median, acc.mad, acc.p99_abs, acc.bin_mean[0],
      acc.bin_n[0], acc.bin_mean[1], acc.bin_n[1], acc.bin_mean[2], acc.bin_n[2], acc.bin_mean[3], acc.bin_n[3]);
  return acc;
}

/// One rendering, one tracker per entry of `refine` (stereo_refine 0/1/2) on the same frames.
std::vector<StereoAccuracy> measureStereoAccuracy(const std::string& realism, const std::vector<int>& refine) {
  sim::SimOptions o = options("city", sim::Level::kNone, 5.0);
  o.realism = sim::realismPreset(realism);
  const sim::Scene scene(o);
  const Config& rig = scene.rig();
  std::vector<std::unique_ptr<FeatureTracker>> trackers;
  for (int r : refine) {
    Config c = rig;
    c.tracker.stereo_refine = r;
    trackers.push_back(std::make_unique<FeatureTracker>(c.rig(), c.tracker));
  }
  const auto cam1 = camera::makeCamera(rig.cams[1]);
  const Eigen::Isometry3d T_c1_c0 = rig.T_b_c[1].inverse() * rig.T_b_c[0];
  const std::size_t m = refine.size();
  std::vector<std::vector<double>> err(m);
  std::vector<std::array<std::vector<double>, 4>> bins(m);
  std::vector<double> near_sum(m, 0), far_sum(m, 0);
  std::vector<std::size_t> near_n(m, 0), far_n(m, 0);
  for (std::size_t k = 0; k < 101; ++k) {
    const sim::SceneFrame f = scene.renderFrame(k);
    for (std::size_t t = 0; t < m; ++t) {
      const FeatureFrame out = trackers[t]->track(stereo(f), MotionPrior{}, nullptr);
      for (const Feature& ft : out.features) {
        double z;
        if (!ft.has_right || !smoothDepth(f.cam[0].depth, ft.uv, z)) continue;
        Vector2d uv_r;
        if (!cam1->project(T_c1_c0 * (Vector3d(ft.xy.x(), ft.xy.y(), 1.0) * z), uv_r)) continue;
        const double e = ft.uv_right.x() - uv_r.x();
        if (std::abs(e) > 3.0) continue;  // a wrong match, not a bias
        err[t].push_back(e);
        bins[t][static_cast<std::size_t>(disparityBin(ft.uv.x() - uv_r.x()))].push_back(e);
        (z < 10 ? near_sum[t] : far_sum[t]) += e;
        ++(z < 10 ? near_n[t] : far_n[t]);
      }
    }
  }
  std::vector<StereoAccuracy> out;
  for (std::size_t t = 0; t < m; ++t)
    out.push_back(summarize(err[t], bins[t], near_sum[t], near_n[t], far_sum[t], far_n[t],
                            realism + ", stereo_refine " + std::to_string(refine[t])));
  return out;
}

TEST(FeatureTracker, StereoRefinementTightensRightMatchesAtRealism) {
  // Right matches against the rendered depth (100 frames of city none seed 1, smooth
  // surfaces, corners at least patch_half + 2 px inside the image). Clean renders: KLT is
  // unbiased in every disparity band. At realism euroc KLT sees near points too near or too
  // far by a fraction of a pixel (vignetting at the two image positions, the right camera's
  // gain: the brightness differences a global compensation leaves); a gain- and
  // bias-invariant refinement (stereo_refine 1: affine, 2: translation) takes it down.
  const std::vector<StereoAccuracy> clean = measureStereoAccuracy("none", {0, 2});
  const std::vector<StereoAccuracy> euroc = measureStereoAccuracy("euroc", {0, 1, 2});
  const StereoAccuracy& real = euroc[0];
  for (const StereoAccuracy& a : clean) {
    ASSERT_GT(a.n, 5000u);
    EXPECT_LT(std::abs(a.near_mean), 0.01);
    EXPECT_LT(std::abs(a.far_mean), 0.01);
    EXPECT_LT(a.mad, 0.04);
    for (std::size_t b = 0; b < a.bin_n.size(); ++b) {  // every band that holds 1 % of the matches
      if (a.bin_n[b] * 100 < a.n) continue;
      EXPECT_LT(std::abs(a.bin_mean[b]), 0.02) << "disparity band " << b;
    }
  }
  ASSERT_GT(real.n, 5000u);
  EXPECT_GT(std::abs(real.near_mean), 0.025);  // KLT on realistic images: biased near points
  for (const StereoAccuracy* refined : {&euroc[1], &euroc[2]}) {
    ASSERT_GT(refined->n, 5000u);
    EXPECT_LT(std::abs(refined->near_mean), std::abs(real.near_mean));
    EXPECT_LT(std::abs(refined->far_mean), 0.5 * std::abs(real.far_mean));
    EXPECT_LT(refined->mad, 0.8 * real.mad);
  }
}

TEST(FeatureTracker, FirstPatchAlignmentRemovesKltDrift) {
  const TrackAccuracy klt = measureTrackAccuracy([](TrackerParams& p) { p.align_first_patch = false; });
  const TrackAccuracy aligned = measureTrackAccuracy();
  EXPECT_GT(klt.p99, 1.5);  // translation-only KLT drifts on oblique facades and the near ground
  EXPECT_LT(aligned.p99, 0.75 * klt.p99);
  EXPECT_LT(aligned.median, 0.5 * klt.median);
  // Dropping the tracks whose patch no longer matches must not cost most of the tracking.
  EXPECT_GT(static_cast<double>(aligned.steps), 0.6 * static_cast<double>(klt.steps));
}

TEST(FeatureTracker, KeepsMaxCountAndMinDistance) {
  const sim::Scene scene(options("parking_lot", sim::Level::kNone, 0.5));
  FeatureTracker tracker(scene.rig().rig(), scene.rig().tracker);
  FeatureFrame out;
  for (std::size_t k = 0; k < 6; ++k) out = tracker.track(stereo(scene.renderFrame(k)), MotionPrior{}, nullptr);
  EXPECT_LE(out.features.size(), 150u);
  EXPECT_GE(out.features.size(), 120u);
  std::size_t too_close = 0;
  for (std::size_t i = 0; i < out.features.size(); ++i)
    for (std::size_t j = i + 1; j < out.features.size(); ++j)
      too_close += (out.features[i].uv - out.features[j].uv).norm() < 29.0;
  EXPECT_EQ(too_close, 0u);
  for (const auto& f : out.features) EXPECT_NE(f.label, FeatureLabel::kEliminated);
}

TEST(FeatureTracker, ACircularFisheyeSees185DegreesAndNoCornerComesNearItsRim) {
  // simulate --lens kb185: the lens circle 2 px inside the image's height, 92.5° at its rim,
  // dark outside; rays past 90° are rendered (surfaces behind the camera's plane: depth < 0).
  sim::SimOptions o = options("city", sim::Level::kNone, 0.5);
  o.lens = sim::Lens::kKannalaBrandtCircle;
  const sim::Scene scene(o);
  const camera::CameraParams& k = scene.rig().cams[0];
  const auto cam = camera::makeCamera(k);
  Eigen::Vector3d ray;
  const double rim = 0.5 * k.height - 2.0;
  ASSERT_TRUE(cam->liftToRay({k.cx + rim, k.cy}, ray));
  EXPECT_NEAR(std::acos(ray.z()) * 180.0 / M_PI, 92.5, 1e-6);
  Eigen::Vector2d uv90;
  ASSERT_TRUE(cam->project({1.0, 0.0, 1e-9}, uv90));
  const double r90 = uv90.x() - k.cx;  // the normalized plane ends here
  const sim::SceneFrame f = scene.renderFrame(3);
  int outside = 0, dark = 0, behind = 0;
  for (int v = 0; v < k.height; ++v)
    for (int u = 0; u < k.width; ++u) {
      const double r = std::hypot(u - k.cx, v - k.cy);
      if (r > rim + 1.5) {
        ++outside;
        dark += f.cam[0].image.at<std::uint8_t>(v, u) < 35 && f.cam[0].depth.at<float>(v, u) == 0.f;
      } else if (r > r90 + 1.0 && r < rim - 1.0) {
        behind += f.cam[0].depth.at<float>(v, u) < 0.f;
      }
    }
  EXPECT_EQ(dark, outside) << "nothing outside the lens circle";
  EXPECT_GT(behind, 1000) << "the ground and facades beside the camera, past 90 degrees";
  // The tracker's lens mask: corners at least corner_margin_px inside the max_ray_angle_deg circle.
  const TrackerParams& params = scene.rig().tracker;
  const double a = params.max_ray_angle_deg * M_PI / 180.0;
  Eigen::Vector2d uv_max;
  ASSERT_TRUE(cam->project({std::sin(a), 0.0, std::cos(a)}, uv_max));
  const double r_max = uv_max.x() - k.cx;
  const cv::Mat mask = lensMask(*cam, k.width, k.height, params.corner_margin_px, params.max_ray_angle_deg);
  ASSERT_FALSE(mask.empty());
  EXPECT_EQ(mask.at<std::uint8_t>(cvRound(k.cy), cvRound(k.cx + r_max - params.corner_margin_px - 2)), 255);
  EXPECT_EQ(mask.at<std::uint8_t>(cvRound(k.cy), cvRound(k.cx + r_max - params.corner_margin_px + 2)), 0);
  const cv::Mat plane = lensMask(*cam, k.width, k.height, params.corner_margin_px, 90.0);
  EXPECT_EQ(plane.at<std::uint8_t>(cvRound(k.cy), cvRound(k.cx + r90 - params.corner_margin_px - 2)), 255);
  EXPECT_EQ(plane.at<std::uint8_t>(cvRound(k.cy), cvRound(k.cx + r90 - params.corner_margin_px + 2)), 0);
  FeatureTracker tracker(scene.rig().rig(), params);
  FeatureFrame out;
  std::size_t seen = 0;
  for (std::size_t i = 0; i < 6; ++i) {
    out = tracker.track(stereo(scene.renderFrame(i)), MotionPrior{}, nullptr);
    for (const auto& ft : out.features) {
      ++seen;
      EXPECT_LT((ft.uv - Eigen::Vector2d(k.cx, k.cy)).norm(), r_max) << "within max_ray_angle_deg";
    }
  }
  EXPECT_GE(out.features.size(), 60u);
  EXPECT_GT(seen, 400u);
  // Full-frame lenses and pinholes need no lens mask.
  o.lens = sim::Lens::kKannalaBrandt;
  const camera::CameraParams full = sim::rigConfig(o).cams[0];
  EXPECT_TRUE(lensMask(*camera::makeCamera(full), full.width, full.height, 9, 80.0).empty()) << "75 degrees at most";
  o.lens = sim::Lens::kPinhole;
  const camera::CameraParams pin = sim::rigConfig(o).cams[0];
  EXPECT_TRUE(lensMask(*camera::makeCamera(pin), pin.width, pin.height, 9, 80.0).empty());
}

/// Removes every tracked feature left of the image centre at one frame, nothing else.
class RemoveLeftHalfOnce final : public FeatureFilter {
 public:
  explicit RemoveLeftHalfOnce(int at_call) : at_call_(at_call) {}
  void apply(const FilterContext&, std::vector<FilterItem>& items) override {
    const bool now = calls_++ == at_call_;
    for (auto& it : items)
      if (now && it.tracked && it.feature->uv.x() < 376) it.remove = true;
  }

 private:
  int at_call_, calls_ = 0;
};

/// Runs 10 frames; the filter removes the left half's tracks at frame 3. Returns, for
/// frames 4-9, the new corners closer than `radius` to a feature eliminated at frame 3
/// (at its current position), and checks that eliminated ids never come back as features.
int newCornersNearEliminated(bool keep_following, double radius, std::size_t& followed_reported) {
  const sim::Scene scene(options("parking_lot", sim::Level::kNone, 0.6));
  TrackerParams params = scene.rig().tracker;
  params.follow_eliminated = keep_following;
  FeatureTracker tracker(scene.rig().rig(), params);
  RemoveLeftHalfOnce filter(2 * 3);  // apply() runs twice per frame (tracked, then fresh corners)
  std::set<std::uint64_t> eliminated;
  std::vector<FeatureFrame> frames;
  followed_reported = 0;
  for (std::size_t k = 0; k < 10; ++k) {
    frames.push_back(tracker.track(stereo(scene.renderFrame(k)), MotionPrior{}, &filter));
    const FeatureFrame& out = frames.back();
    if (k == 3)
      for (const auto& f : out.removed) eliminated.insert(f.id);
    if (k <= 3) continue;
    for (const auto& f : out.features)
      EXPECT_EQ(eliminated.count(f.id), 0u) << "eliminated id " << f.id << " came back";
    for (const auto& f : out.removed) {
      EXPECT_EQ(f.label, FeatureLabel::kEliminated);
      followed_reported += eliminated.count(f.id);
    }
  }
  // New corners of frame k near an eliminated feature's position at frame k. Without
  // following, that is where it was when eliminated (frame 3); with following, only the
  // features still followed at frame k + 1 count (the others were lost by KLT, which
  // legitimately frees their place).
  int near = 0;
  std::map<std::uint64_t, Vector2d> at_elimination;
  for (const auto& f : frames[3].removed) at_elimination[f.id] = f.uv;
  for (std::size_t k = 4; k + 1 < frames.size(); ++k) {
    std::vector<Vector2d> occupied;
    if (keep_following) {
      std::set<std::uint64_t> still;
      for (const auto& f : frames[k + 1].removed) still.insert(f.id);
      for (const auto& f : frames[k].removed)
        if (still.count(f.id)) occupied.push_back(f.uv);
    } else if (k == 4) {
      for (const auto& [id, uv] : at_elimination) occupied.push_back(uv);
    }
    for (const auto& f : frames[k].features) {
      if (f.track_length != 1) continue;
      for (const auto& uv : occupied)
        if ((uv - f.uv).norm() < radius) {
          ++near;
          break;
        }
    }
  }
  EXPECT_GT(eliminated.size(), 20u);
  return near;
}

TEST(FeatureTracker, FollowsEliminatedFeaturesSoNoNewCornerIsSeededOnThem) {
  // IDY modes: an eliminated feature never comes back as a feature, is reported as
  // removed while it is followed, and keeps its place (no new corner within min_dist).
  std::size_t followed = 0, followed_off = 0;
  const int near_on = newCornersNearEliminated(true, 25.0, followed);
  const int near_off = newCornersNearEliminated(false, 25.0, followed_off);
  std::printf(
      "new corners within 25 px of eliminated features: %d followed, %d not followed; "
      "followed observations reported %zu\n",
      near_on, near_off, followed);
  EXPECT_EQ(near_on, 0);
  EXPECT_GT(near_off, 0);  // without following, some freed places are refilled at once (3 here)
  EXPECT_GT(followed, 100u);
  EXPECT_EQ(followed_off, 0u);
}

/// Eliminates tracked features on a moving object once they are three frames long (a
/// stand-in for the IDY filter, which needs a few frames to judge).
class EliminateOnMaskFromThirdFrame final : public FeatureFilter {
 public:
  void apply(const FilterContext& context, std::vector<FilterItem>& items) override {
    for (auto& it : items) {
      if (!it.tracked || it.feature->track_length < 3 || !context.mask) continue;
      const int u = static_cast<int>(std::lround(it.feature->uv.x())),
                v = static_cast<int>(std::lround(it.feature->uv.y()));
      if (context.mask->at<std::uint8_t>(v, u) != 0) it.remove = true;
    }
  }
};

TEST(FeatureTracker, CornersPrunedNextToAnEliminatedTrackThatMovedWithThemAreJudgedMoving) {
  // A truck overtakes the rig and drives away ahead of it: it shrinks in the image, its
  // corners draw together. Its tracks are eliminated in their third frame and followed; a
  // corner in its second frame that the min_dist pruning drops next to one of them,
  // having moved with it, is reported as moving (lost_moving).
  const sim::Scene scene =
      crossingVehicleScene(3.0, "truck", Vector3d(8.0, 2.5, 3.0), Vector3d(6.0, -1.5, 0.0), 10.0, Vector3d::UnitX());
  std::size_t counts[2][2] = {{0, 0}, {0, 0}};  // [move_with_eliminated on][on the truck]
  for (const bool on : {true, false}) {
    TrackerParams params = scene.rig().tracker;
    params.follow_eliminated = true;
    params.lost_track_test = true;
    params.move_with_eliminated_px = on ? TrackerParams{}.move_with_eliminated_px : 0.0;
    FeatureTracker tracker(scene.rig().rig(), params);
    EliminateOnMaskFromThirdFrame filter;
    std::map<std::uint64_t, bool> on_truck;  // the corners output in their first frame
    for (std::size_t k = 0; k < 61; ++k) {
      const sim::SceneFrame f = scene.renderFrame(k);
      const FeatureFrame out = tracker.track(stereo(f), MotionPrior{}, &filter, &f.cam[0].mask);
      for (const auto& ft : out.lost_moving) {
        ASSERT_TRUE(on_truck.count(ft.id)) << "only corners output in the previous frame";
        ++counts[on][on_truck[ft.id]];
      }
      on_truck.clear();
      for (const auto& ft : out.features)
        if (ft.track_length == 1)
          on_truck[ft.id] = f.cam[0].mask.at<std::uint8_t>(static_cast<int>(std::lround(ft.uv.y())),
                                                           static_cast<int>(std::lround(ft.uv.x()))) != 0;
    }
  }
  std::printf("judged moving with an eliminated neighbour: %zu on the truck, %zu static (off: %zu, %zu)\n",
              counts[1][1], counts[1][0], counts[0][1], counts[0][0]);
  // Measured when added (move_with_eliminated_px 6): 18 on the truck, none static.
  EXPECT_EQ(counts[0][0] + counts[0][1], 0u);
  EXPECT_GT(counts[1][1], 10u);
  EXPECT_LT(counts[1][0] * 10, counts[1][1]);
}

/// Stereo matches of static corners in city high with the ZNCC check off, split by
/// their patch ZNCC: `wrong` = the true right projection of the corner's pixel is hidden
/// (something nearer in cam1) or more than 1 px from the match; `vehicle` = a moving
/// object's pixel inside the corner's patch.
struct StereoMatchCounts {
  std::size_t total = 0, wrong = 0, vehicle = 0;
};

TEST(FeatureTracker, StereoMatchesWithLowZnccAreMoreOftenWrongOrBesideAVehicle) {
  const sim::Scene scene(options("city", sim::Level::kHigh, 3.0));
  const Config& rig = scene.rig();
  const auto cam1 = camera::makeCamera(rig.cams[1]);
  const Eigen::Isometry3d T_c1_c0 = rig.T_b_c[1].inverse() * rig.T_b_c[0];
  TrackerParams params = rig.tracker;
  const double min_zncc = params.stereo_min_zncc;
  params.stereo_min_zncc = -1.0;
  FeatureTracker tracker(rig.rig(), params);
  StereoMatchCounts low, high;
  for (std::size_t k = 0; k < 61; ++k) {
    const sim::SceneFrame f = scene.renderFrame(k);
    const FeatureFrame out = tracker.track(stereo(f), MotionPrior{}, nullptr);
    for (const Feature& ft : out.features) {
      if (!ft.has_right) continue;
      const int u = static_cast<int>(std::lround(ft.uv.x())), v = static_cast<int>(std::lround(ft.uv.y()));
      double z;
      // At an occlusion edge: the depth of the corner's own pixel.
      if (!smoothDepth(f.cam[0].depth, ft.uv, z, 2)) z = f.cam[0].depth.at<float>(v, u);
      if (f.cam[0].mask.at<std::uint8_t>(v, u) != 0 || z <= 0) continue;
      const Vector3d p_c1 = T_c1_c0 * (Vector3d(ft.xy.x(), ft.xy.y(), 1.0) * z);
      Vector2d uv_true;
      bool wrong = !cam1->project(p_c1, uv_true) || (uv_true - ft.uv_right).norm() > 1.0;
      if (!wrong) {
        const float z1 = f.cam[1].depth.at<float>(static_cast<int>(std::lround(uv_true.y())),
                                                  static_cast<int>(std::lround(uv_true.x())));
        wrong = z1 > 0 && z1 < 0.97 * p_c1.z();
      }
      StereoMatchCounts& n =
          patchZncc(f.cam[0].image, ft.uv, f.cam[1].image, ft.uv_right, params.patch_half) < min_zncc ? low : high;
      ++n.total;
      n.wrong += wrong;
      const cv::Rect patch(u - params.patch_half, v - params.patch_half, 2 * params.patch_half + 1,
                           2 * params.patch_half + 1);
      n.vehicle += cv::countNonZero(f.cam[0].mask(patch & cv::Rect(0, 0, f.cam[0].mask.cols, f.cam[0].mask.rows))) > 0;
    }
  }
  std::printf(
      "stereo matches of static corners, ZNCC < %.2f: %zu (%zu wrong, %zu with a vehicle in the patch); "
      "the others: %zu (%zu wrong, %zu with a vehicle)\n",
      min_zncc, low.total, low.wrong, low.vehicle, high.total, high.wrong, high.vehicle);
  // Measured at 6537e71: 296 of 7516 below 0.8, 3.4 % of them wrong against 1.2 % of the
  // others, 4.4 % with a vehicle in the patch against 2.3 %. Since no corner is detected
  // where its first patch cannot be cut (most low-ZNCC matches were corners at the image
  // border): 35 of 7511, 29 % wrong against 1.2 %, 31 % with a vehicle against 2.2 %.
  ASSERT_GT(low.total, 20u);
  EXPECT_LT(low.total, (low.total + high.total) * 6 / 100);  // it costs few matches
  const auto rate = [](std::size_t a, const StereoMatchCounts& n) { return static_cast<double>(a) / n.total; };
  EXPECT_GT(rate(low.wrong, low), 2.0 * rate(high.wrong, high));
  EXPECT_GT(rate(low.vehicle, low), 1.5 * rate(high.vehicle, high));
}

TEST(FeatureTracker, LowZnccRightMatchesOnlyLeaveTheMotionTests) {
  // stereo_zncc_motion_only: a right match below stereo_min_zncc is not a right match for
  // the motion tests (has_right false, exactly as when the check drops it) but is handed on
  // (right_low_zncc) with its KLT position for the estimator.
  const sim::Scene scene(options("city", sim::Level::kHigh, 2.0));
  const Config& rig = scene.rig();
  TrackerParams dropped = rig.tracker, kept = rig.tracker;
  dropped.stereo_zncc_motion_only = false;
  kept.stereo_zncc_motion_only = true;
  FeatureTracker a(rig.rig(), dropped), b(rig.rig(), kept);
  std::size_t low = 0, verified = 0;
  for (std::size_t k = 0; k < 41; ++k) {
    const sim::SceneFrame f = scene.renderFrame(k);
    const FeatureFrame fa = a.track(stereo(f), MotionPrior{}, nullptr);
    const FeatureFrame fb = b.track(stereo(f), MotionPrior{}, nullptr);
    ASSERT_EQ(fa.features.size(), fb.features.size()) << "frame " << k;
    for (std::size_t i = 0; i < fa.features.size(); ++i) {
      const Feature &x = fa.features[i], &y = fb.features[i];
      ASSERT_EQ(x.id, y.id);
      EXPECT_EQ(x.has_right, y.has_right) << "frame " << k << " id " << x.id;
      EXPECT_FALSE(x.right_low_zncc);
      EXPECT_FALSE(y.has_right && y.right_low_zncc);
      if (x.has_right) {
        EXPECT_EQ(x.uv_right, y.uv_right);
        ++verified;
      }
      if (!y.right_low_zncc) continue;
      ++low;
      EXPECT_LT(patchZncc(f.cam[0].image, y.uv, f.cam[1].image, y.uv_right, kept.patch_half), kept.stereo_min_zncc);
      EXPECT_GT(y.uv.x(), y.uv_right.x());  // a positive disparity: a right match, not a placeholder
    }
  }
  std::printf("right matches: %zu passing the ZNCC check, %zu below it kept for the estimator\n", verified, low);
  EXPECT_GT(low, 10u);
  EXPECT_GT(verified, 20 * low);
}

TEST(FeatureTracker, EveryEndedTrackIsCountedOnceWithItsReason) {
  // A truck crossing 7-9 m ahead at 20 m/s (about 1 m per frame): KLT loses its corners, the
  // street's tracks leave the image or are pruned. Every id of frame k - 1 missing at frame k
  // must be counted once in lost_tracks (and in lost_new when it was a new corner).
  const sim::Scene scene = crossingVehicleScene(3.0, "truck", Vector3d(8.0, 2.5, 3.0), Vector3d(9.0, -30.0, 0.0), 20.0);
  FeatureTracker tracker(scene.rig().rig(), scene.rig().tracker);
  TrackLosses sum_all, sum_new;
  std::size_t ended = 0, ended_new = 0;
  std::map<std::uint64_t, int> prev;  // id -> track length at frame k - 1
  for (std::size_t k = 0; k < 61; ++k) {
    const FeatureFrame out = tracker.track(stereo(scene.renderFrame(k)), MotionPrior{}, nullptr);
    std::set<std::uint64_t> now;
    for (const auto& f : out.features) now.insert(f.id);
    std::size_t gone = 0, gone_new = 0;
    for (const auto& [id, length] : prev)
      if (!now.count(id)) {
        ++gone;
        gone_new += length == 1;
      }
    EXPECT_EQ(out.lost_tracks.total(), gone) << "frame " << k;
    EXPECT_EQ(out.lost_new.total(), gone_new) << "frame " << k;
    ended += gone;
    ended_new += gone_new;
    sum_all += out.lost_tracks;
    sum_new += out.lost_new;
    prev.clear();
    for (const auto& f : out.features) prev[f.id] = f.track_length;
  }
  std::printf("ended: %zu tracks (%zu new corners): klt %zu, border %zu, backward %zu, alignment %zu, pruned %zu\n",
              ended, ended_new, sum_all.klt, sum_all.border, sum_all.backward, sum_all.alignment, sum_all.pruned);
  ASSERT_GT(ended, 100u);
  EXPECT_GT(sum_all.klt + sum_all.backward, 0u);  // the truck's corners
  EXPECT_GT(sum_all.alignment, 0u);
  EXPECT_GT(sum_all.border, 0u);  // the street leaving the image
  EXPECT_GT(sum_all.pruned, 0u);
  EXPECT_LE(sum_new.total(), sum_all.total());
}

TEST(Rejection, SegDropsExactlyTheFeaturesOnMaskedPixels) {
  const sim::Scene scene(options("city", sim::Level::kHigh, 3.0));
  TrackerParams params = scene.rig().tracker;
  params.follow_eliminated = params.lost_track_test = false;  // as mode seg runs the tracker (config/modes.h)
  FeatureTracker tracker(scene.rig().rig(), params);
  SegFilter seg;
  std::size_t removed = 0, kept = 0;
  for (std::size_t k = 0; k < 61; ++k) {
    const sim::SceneFrame f = scene.renderFrame(k);
    const FeatureFrame out = tracker.track(stereo(f), MotionPrior{}, &seg, &f.cam[0].mask);
    auto on_mask = [&](const Feature& ft) {
      return f.cam[0].mask.at<std::uint8_t>(static_cast<int>(std::lround(ft.uv.y())),
                                            static_cast<int>(std::lround(ft.uv.x()))) != 0;
    };
    for (const auto& ft : out.features) EXPECT_FALSE(on_mask(ft)) << "frame " << k << " id " << ft.id;
    for (const auto& ft : out.removed) EXPECT_TRUE(on_mask(ft)) << "frame " << k << " id " << ft.id;
    removed += out.removed.size();
    kept += out.features.size();
  }
  std::printf("seg: %zu features removed on moving objects, %zu kept\n", removed, kept);
  EXPECT_GT(removed, 50u);
}

TEST(Rejection, RansacRejectsMostFeaturesOnACrossingVehicle) {
  // A car crosses the static street 15-20 m ahead of the drone.
  const sim::Scene scene = crossingVehicleScene(4.0, "car", Vector3d(4.5, 1.8, 1.5), Vector3d(20.0, -14.0, 0.0), 6.0);
  FeatureTracker tracker(scene.rig().rig(), scene.rig().tracker);
  RansacFilter ransac(scene.rig().tracker.f_threshold);
  std::size_t on_vehicle = 0, on_vehicle_rejected = 0, static_total = 0, static_rejected = 0;
  for (std::size_t k = 0; k < 81; ++k) {
    const sim::SceneFrame f = scene.renderFrame(k);
    const FeatureFrame out = tracker.track(stereo(f), MotionPrior{}, &ransac);
    auto on_mask = [&](const Feature& ft) {
      return f.cam[0].mask.at<std::uint8_t>(static_cast<int>(std::lround(ft.uv.y())),
                                            static_cast<int>(std::lround(ft.uv.x()))) != 0;
    };
    for (const auto& ft : out.features) {
      if (ft.track_length == 1) continue;  // only tracked features go through RANSAC
      (on_mask(ft) ? on_vehicle : static_total) += 1;
    }
    for (const auto& ft : out.removed) {
      if (on_mask(ft)) {
        ++on_vehicle;
        ++on_vehicle_rejected;
      } else {
        ++static_total;
        ++static_rejected;
      }
    }
  }
  std::printf("ransac: %zu of %zu tracked observations on the vehicle rejected; %zu of %zu static ones\n",
              on_vehicle_rejected, on_vehicle, static_rejected, static_total);
  ASSERT_GT(on_vehicle, 30u);
  EXPECT_GT(on_vehicle_rejected, on_vehicle / 2);
  EXPECT_LT(static_rejected, static_total / 20);
}

TEST(FeatureTracker, RunsOnTheRealEurocExcerpt) {
  // Real images with strong distortion: tracks survive, stereo matches are found.
  const Config c = loadConfig(std::string(IDYVINS_SOURCE_DIR) + "/config/euroc/euroc_stereo_imu_config.yaml");
  const io::EurocDataset ds = io::readEurocDataset(std::string(IDYVINS_SHARED_DATA) + "/euroc_v101_micro");
  io::EurocSource source(ds, 752, 480);
  FeatureTracker tracker(c.rig(), c.tracker);
  std::size_t frames = 0, stereo_matches = 0, features = 0, long_tracks = 0;
  while (auto m = source.next()) {
    const auto* f = std::get_if<StereoFrame>(&*m);
    if (!f) continue;
    const FeatureFrame out = tracker.track(*f, MotionPrior{}, nullptr);
    ++frames;
    features += out.features.size();
    for (const auto& ft : out.features) {
      stereo_matches += ft.has_right;
      long_tracks += ft.track_length >= 20;
    }
  }
  EXPECT_EQ(frames, 95u);
  EXPECT_GT(features / frames, 120u);
  EXPECT_GT(static_cast<double>(stereo_matches) / features, 0.15);  // see HoldsOnTheRealEurocExcerpt
  EXPECT_GT(long_tracks, 1000u);                                    // the platform sits still: tracks live long
}

TEST(FeatureTracker, HoldsOnTheRealEurocExcerpt) {
  // The real EuRoC V1_01 excerpt with its shipped config: EuRoC's right camera is about
  // 10 % darker than the left, its images low-contrast in places. Measured at the commit
  // that added this test: 50 % of the features with a right match, epipolar distance of
  // the matches median 0.12 px and p99 0.79 px, median track length 95 frames (the
  // platform hardly moves in these 4.75 s); 18 % right matches before gain compensation
  // and equalization. With stereo_refine (on in this config): 51 %, median 0.10 px, p99
  // 0.64 px; without it 50 %, 0.12 px and 0.79 px. With corners kept off the border
  // (e94ba2e): 53 %, 0.10 px, 0.63 px; without refinement 52 %, 0.125 px, 0.785 px.
  const std::string cfg_path = std::string(IDYVINS_SOURCE_DIR) + "/config/euroc/euroc_stereo_imu_config.yaml";
  const io::EurocDataset ds = io::readEurocDataset(std::string(IDYVINS_SHARED_DATA) + "/euroc_v101_micro");
  auto measure = [&](bool equalize, bool gain_compensation, bool refine = true) {
    Config c = loadConfig(cfg_path);
    c.tracker.equalize = equalize;
    c.tracker.stereo_gain_compensation = gain_compensation;
    c.tracker.stereo_refine = refine;
    io::EurocSource source(ds, 752, 480);
    FeatureTracker tracker(c.rig(), c.tracker);
    TrackQuality quality(c.rig());
    while (auto m = source.next())
      if (const auto* f = std::get_if<StereoFrame>(&*m)) quality.add(tracker.track(*f, MotionPrior{}, nullptr));
    return quality.summary();
  };
  const TrackQualitySummary q = measure(true, true);
  EXPECT_EQ(q.frames, 95u);
  EXPECT_GT(static_cast<double>(q.features) / static_cast<double>(q.frames), 140.0);
  EXPECT_GE(q.right_fraction, 0.45);
  EXPECT_LE(q.epipolar_median_px, 0.3);
  EXPECT_LE(q.epipolar_p99_px, 1.0);
  EXPECT_GE(q.track_length_median, 50.0);
  RecordProperty("right_fraction", std::to_string(q.right_fraction));
  RecordProperty("epipolar_median_px", std::to_string(q.epipolar_median_px));
  RecordProperty("epipolar_p99_px", std::to_string(q.epipolar_p99_px));
  RecordProperty("track_length_median", std::to_string(q.track_length_median));
  // Each of the two measures carries part of it.
  const TrackQualitySummary no_gain = measure(true, false), neither = measure(false, false);
  EXPECT_LT(no_gain.right_fraction + 0.05, q.right_fraction);
  EXPECT_LT(neither.right_fraction + 0.15, q.right_fraction);
  // Refining the right matches tightens them against the calibrated epipolar geometry.
  const TrackQualitySummary unrefined = measure(true, true, false);
  std::printf("right matches: refined %.3f, median %.3f px, p99 %.3f px; unrefined %.3f, median %.3f px, p99 %.3f px\n",
              q.right_fraction, q.epipolar_median_px, q.epipolar_p99_px, unrefined.right_fraction,
              unrefined.epipolar_median_px, unrefined.epipolar_p99_px);
  EXPECT_LT(q.epipolar_p99_px, 0.9 * unrefined.epipolar_p99_px);
  EXPECT_LE(q.epipolar_median_px, unrefined.epipolar_median_px);
}

TEST(FeatureTracker, EqualizationLeavesTheCallersImagesAlone) {
  Config c = loadConfig(std::string(IDYVINS_SOURCE_DIR) + "/config/euroc/euroc_stereo_imu_config.yaml");
  ASSERT_TRUE(c.tracker.equalize);
  const io::EurocDataset ds = io::readEurocDataset(std::string(IDYVINS_SHARED_DATA) + "/euroc_v101_micro");
  io::EurocSource source(ds, 752, 480);
  FeatureTracker tracker(c.rig(), c.tracker);
  for (int frames = 0; frames < 3;) {
    auto m = source.next();
    ASSERT_TRUE(m.has_value());
    const auto* f = std::get_if<StereoFrame>(&*m);
    if (!f) continue;
    const cv::Mat left = f->left.clone(), right = f->right.clone();
    tracker.track(*f, MotionPrior{}, nullptr);
    EXPECT_EQ(cv::norm(left, f->left, cv::NORM_INF), 0.0);
    EXPECT_EQ(cv::norm(right, f->right, cv::NORM_INF), 0.0);
    ++frames;
  }
}

TEST(MatchBrightness, MapsGainAndOffsetOntoTheReferenceAndLeavesAgreeingImagesAlone) {
  cv::Mat reference(60, 80, CV_8UC1);
  cv::RNG rng(3);
  rng.fill(reference, cv::RNG::UNIFORM, 40, 200);
  cv::Mat darker;
  reference.convertTo(darker, CV_8U, 0.8, -5.0);  // a darker camera: gain 0.8, offset -5
  const cv::Mat matched = matchBrightness(darker, reference);
  cv::Mat diff;
  cv::absdiff(matched, reference, diff);
  double max_diff = 0;
  cv::minMaxLoc(diff, nullptr, &max_diff);
  EXPECT_LE(max_diff, 2.0) << "rounding of the darker image, scaled back by 1.25";
  const cv::Mat same = matchBrightness(reference, reference);
  EXPECT_EQ(same.data, reference.data) << "agreeing images are returned as they are";
  cv::Mat flat(60, 80, CV_8UC1, cv::Scalar(100));
  EXPECT_EQ(matchBrightness(flat, reference).data, flat.data) << "a flat image has no gain to estimate";
}

TEST(TrackQuality, EpipolarDistanceIsThePixelDistanceToTheLine) {
  // Pure x translation (rectified pair): epipolar lines are rows; the distance is the
  // row offset times the focal length.
  const Eigen::Vector3d t(-0.1, 0, 0);
  Eigen::Matrix3d E;
  E << 0, -t.z(), t.y(), t.z(), 0, -t.x(), -t.y(), t.x(), 0;
  EXPECT_NEAR(epipolarDistancePx(E, 400.0, {0.1, 0.2}, {0.05, 0.2}), 0.0, 1e-12);
  EXPECT_NEAR(epipolarDistancePx(E, 400.0, {0.1, 0.2}, {0.05, 0.2025}), 1.0, 1e-9);
}

}  // namespace
}  // namespace idyvins::frontend
