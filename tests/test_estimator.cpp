// The sliding-window estimator end to end on short rendered sequences (in memory),
// plus its pure helpers (triangulation, alignment).

#include <gtest/gtest.h>

#include <map>
#include <optional>
#include <random>
#include <set>

#include "backend/estimator.h"
#include "backend/initializer.h"
#include "eval/trajectory_metrics.h"
#include "frontend/feature_tracker.h"
#include "sim/simulator.h"

namespace idyvins::backend {
namespace {

using Eigen::Vector2d;
using Eigen::Vector3d;

struct RunResult {
  std::vector<StampedPose> estimate, truth;
  int first_init_frame = -1, resets = 0, keyframes = 0, non_keyframes = 0;
  double init_tilt_error_deg = -1, init_speed_error = -1;  ///< at the first initialized frame
  double path = 0, ate = 0;
  double yaw_offset_range_deg = 0;  ///< max - min over the run of (estimated yaw - true yaw)
};

double yawDeg(const Eigen::Quaterniond& q) {
  const Eigen::Matrix3d R = q.toRotationMatrix();
  return std::atan2(R(1, 0), R(0, 0)) * 180.0 / M_PI;
}

/// Renders a sequence, synthesizes its IMU, runs tracker + estimator; `hook` may
/// replace the features of a frame (to provoke failures).
RunResult runSequence(const sim::SimOptions& o,
                      const std::function<void(std::size_t, frontend::FeatureFrame&)>& hook = {},
                      const EstimatorOptions& est_options = {},
                      const std::function<void(const Estimator&)>& at_end = {},
                      const std::function<void(const FrameResult&)>& per_frame = {});
RunResult runSequence(const sim::SimOptions& o, const std::function<void(std::size_t, frontend::FeatureFrame&)>& hook,
                      const EstimatorOptions& est_options, const std::function<void(const Estimator&)>& at_end,
                      const std::function<void(const FrameResult&)>& per_frame) {
  const sim::Scene scene(o);
  std::vector<ImuSample> imu;
  std::vector<GroundTruthState> gt;
  sim::synthesizeImu(scene.trajectory(), o, imu, gt);
  frontend::FeatureTracker tracker(scene.rig().rig(), scene.rig().tracker);
  Estimator estimator(scene.rig().rig(), scene.rig().imu.noise, est_options);
  RunResult out;
  std::size_t next_imu = 0;
  for (std::size_t k = 0; k < scene.frameCount(); ++k) {
    const sim::SceneFrame f = scene.renderFrame(k);
    while (next_imu < imu.size() && imu[next_imu].t_ns <= f.t_ns) estimator.addImu(imu[next_imu++]);
    StereoFrame sf;
    sf.t_ns = f.t_ns;
    sf.left = f.cam[0].image;
    sf.right = f.cam[1].image;
    frontend::FeatureFrame ff = tracker.track(sf, frontend::MotionPrior{}, nullptr);
    if (hook) hook(k, ff);
    const FrameResult r = estimator.addFrame(ff);
    if (per_frame) per_frame(r);
    if (r.reset) {
      ++out.resets;
      tracker.reset();
    }
    if (!r.initialized) continue;
    const GroundTruthState& g = gt[k * 10];  // IMU at 200 Hz, frames at 20 Hz
    if (out.first_init_frame < 0) {
      out.first_init_frame = static_cast<int>(k);
      const Vector3d up_est = r.state.q_w_b.conjugate() * Vector3d::UnitZ();
      const Vector3d up_gt = g.q_w_b.conjugate() * Vector3d::UnitZ();
      out.init_tilt_error_deg = std::acos(std::min(1.0, up_est.dot(up_gt))) * 180.0 / M_PI;
      out.init_speed_error = std::abs(r.state.v_w.norm() - g.v_w.norm());
    }
    (r.keyframe ? out.keyframes : out.non_keyframes) += 1;
    out.estimate.push_back({r.t_ns, r.state.p_w_b, r.state.q_w_b});
    EXPECT_EQ(g.t_ns, f.t_ns);
    out.truth.push_back({g.t_ns, g.p_w_b, g.q_w_b});
  }
  if (at_end) {
    estimator.flushMap();
    at_end(estimator);
  }
  if (out.estimate.size() > 2) {
    out.ate = eval::computeAte(out.truth, out.estimate, eval::AlignMode::kSe3, 1000).stats.rmse;
    out.path = eval::pathLength(out.truth);
    double lo = 1e9, hi = -1e9;
    for (std::size_t i = 0; i < out.estimate.size(); ++i) {
      double d = yawDeg(out.estimate[i].q_w_b) - yawDeg(out.truth[i].q_w_b);
      d = std::remainder(d - (yawDeg(out.estimate[0].q_w_b) - yawDeg(out.truth[0].q_w_b)), 360.0);
      lo = std::min(lo, d);
      hi = std::max(hi, d);
    }
    out.yaw_offset_range_deg = hi - lo;
  }
  return out;
}

sim::SimOptions options(const std::string& scene, double duration, bool opening = false) {
  sim::SimOptions o;
  o.scene.scene = scene;
  o.scene.seed = 1;
  o.scene.opening_vehicle = opening;
  o.duration_s = duration;
  return o;
}

TEST(Estimator, ShortCitySequenceEndToEnd) {
  const RunResult r = runSequence(options("city", 6.0));
  std::printf(
      "city 6 s: initialized at frame %d, %zu poses, ATE %.4f m over %.1f m (%.2f%%), %d keyframes, "
      "%d non-keyframes, %d resets, yaw offset range %.3f deg\n",
      r.first_init_frame, r.estimate.size(), r.ate, r.path, 100 * r.ate / r.path, r.keyframes, r.non_keyframes,
      r.resets, r.yaw_offset_range_deg);
  ASSERT_GE(r.first_init_frame, 0);
  EXPECT_LE(r.first_init_frame, 60);  // within 3 s
  EXPECT_EQ(r.resets, 0);
  EXPECT_LT(r.ate, 0.01 * r.path);
  // Yaw is unobservable: the window must not wander in it (backend/gauge.h). With the
  // gauge left free the same run wanders by 3.9 degrees (ATE 0.030 m instead of 0.015 m).
  EXPECT_LT(r.yaw_offset_range_deg, 0.5);
  EXPECT_GT(r.keyframes + r.non_keyframes, 100);
  EXPECT_GT(r.keyframes, 10);  // oldest-frame marginalization ran
  EXPECT_GT(r.non_keyframes,
            10);  // second-newest-frame marginalization ran  // the window slid (marginalization ran) many times
}

TEST(Estimator, EstimatedAnchorRaysSolveAndMarginalizeOnTheShortCitySequence) {
  // estimate_anchor_ray: three-parameter landmarks through the solves, the oldest-frame
  // marginalization (their blocks marginalized with the frame) and the re-anchoring.
  EstimatorOptions o;
  o.estimate_anchor_ray = true;
  const RunResult r = runSequence(options("city", 6.0), {}, o);
  std::printf("city 6 s, estimated anchor rays: ATE %.4f m over %.1f m, %d keyframes, %d resets\n", r.ate, r.path,
              r.keyframes, r.resets);
  ASSERT_GE(r.first_init_frame, 0);
  EXPECT_EQ(r.resets, 0);
  EXPECT_LT(r.ate, 0.01 * r.path);
  EXPECT_GT(r.keyframes, 10);
}

TEST(Estimator, LandmarkShareKeepsTheRelinkedObservationsOutOfThePriorTwice) {
  // prior_landmark_share: a landmark that lives on after its anchor keyframe leaves brings
  // 1/m of its information into the prior. The prior ends up holding less information, the
  // run stays as accurate (docs/method.md, The estimator).
  const auto priorInformation = [](const Estimator& e, double& out) {
    ASSERT_NE(e.prior(), nullptr);
    out = (e.prior()->J0.transpose() * e.prior()->J0).trace();
  };
  double info_all = 0, info_share = 0;
  EstimatorOptions vins;
  vins.prior_landmark_share = false;
  const RunResult all =
      runSequence(options("city", 6.0), {}, vins, [&](const Estimator& e) { priorInformation(e, info_all); });
  EstimatorOptions o;
  o.prior_landmark_share = true;
  const RunResult share =
      runSequence(options("city", 6.0), {}, o, [&](const Estimator& e) { priorInformation(e, info_share); });
  std::printf("city 6 s: prior information trace %.3g (all) vs %.3g (share); ATE %.4f vs %.4f m\n", info_all,
              info_share, all.ate, share.ate);
  EXPECT_EQ(share.resets, 0);
  EXPECT_LT(share.ate, 0.01 * share.path);
  EXPECT_LT(info_share, 0.7 * info_all);
}

TEST(FeatureManager, APriorShareBelowOneOnlyForLandmarksThatLiveOnReanchored) {
  Landmark lm;
  lm.obs.resize(1);
  EXPECT_EQ(lm.priorShare(), 1.0);  // leaves with its keyframe (removeOldest erases it)
  lm.obs.resize(2);
  EXPECT_EQ(lm.priorShare(), 0.5);
  lm.obs.resize(8);
  EXPECT_EQ(lm.priorShare(), 0.125);
}

TEST(Estimator, InitializesDespiteAVehicleCrossingCloseInFront) {
  // A truck crosses 5-8 m ahead during the first seconds (up to ~40 % of the view).
  // Initialization itself must stay right: gravity direction and speed at the first
  // initialized frame. (What the truck does to the baseline afterwards is the
  // dynamic-scene problem idy mode addresses; the ATE is printed, not asserted.)
  const RunResult r = runSequence(options("city", 5.0, true));
  std::printf(
      "opening vehicle: initialized at frame %d (tilt error %.3f deg, speed error %.3f m/s), "
      "ATE %.4f m over %.1f m, %d resets\n",
      r.first_init_frame, r.init_tilt_error_deg, r.init_speed_error, r.ate, r.path, r.resets);
  ASSERT_GE(r.first_init_frame, 0);
  EXPECT_LE(r.first_init_frame, 60);
  EXPECT_LT(r.init_tilt_error_deg, 1.0);
  EXPECT_LT(r.init_speed_error, 0.1);
}

TEST(Estimator, ResetsOnLostTrackingAndReinitializes) {
  // Frames 60-62 lose every feature (a blackout): the estimator must detect it, reset,
  // and initialize again afterwards.
  const RunResult r = runSequence(options("parking_lot", 5.0), [](std::size_t k, frontend::FeatureFrame& ff) {
    if (k >= 40 && k <= 42) ff.features.clear();
  });
  std::printf("blackout: %d resets, %zu poses\n", r.resets, r.estimate.size());
  EXPECT_GE(r.resets, 1);
  ASSERT_FALSE(r.estimate.empty());
  EXPECT_GT(r.estimate.back().t_ns, 1'700'000'004'500'000'000);  // tracking again near the end
}

TEST(Estimator, AFailureInsideTheFirstWindowsTransientRestartsTheBiasesInsteadOfTyingThem) {
  // The last good state's biases are trusted after a failure only once its segment has solved
  // kSettledFrames frames; a blackout right after the first initialization restarts them.
  auto firstReanchor = [](std::size_t from, std::size_t to) {
    std::optional<FrameResult> first;
    int first_init = -1, frame = 0;
    runSequence(
        options("parking_lot", 4.0),
        [&](std::size_t k, frontend::FeatureFrame& ff) {
          if (k >= from && k <= to) ff.features.clear();
        },
        {}, {},
        [&](const FrameResult& r) {
          if (r.initialized && first_init < 0) first_init = frame;
          if (!r.reanchored.empty() && !first) first = r;
          ++frame;
        });
    EXPECT_GE(first_init, 0);
    EXPECT_LT(first_init, 14) << "the early blackout must fall inside the first segment's transient";
    return first;
  };
  const std::optional<FrameResult> early = firstReanchor(14, 16), late = firstReanchor(50, 52);
  ASSERT_TRUE(early.has_value());
  ASSERT_TRUE(late.has_value());
  EXPECT_FALSE(early->biases_from_last_good);
  EXPECT_TRUE(late->biases_from_last_good);
}

TEST(Estimator, PostProcessingConfirmsMovingCandidatesAndClearsStaticOnes) {
  // DESIGN §4.6 on a static 6 s city run: from frame 40 on, a set of tracks is dragged
  // by 2 px per frame across the epipolar lines of the forward-moving camera
  // (tangentially around the image centre; a slowly moving object) and marked
  // candidate; another set is marked candidate at frames 40-41 only (a brief false
  // alarm). The dragged ones must be confirmed dynamic, leave the window for good (a
  // confirmed track is never confirmed twice) and stay out of the static map; the
  // false alarms must be cleared and reach the static map.
  std::set<std::uint64_t> moved, labelled;
  std::map<std::uint64_t, Vector2d> direction;
  std::map<std::uint64_t, std::size_t> last_seen;
  auto hook = [&](std::size_t k, frontend::FeatureFrame& ff) {
    if (k == 40)
      for (const auto& f : ff.features) {
        if (f.track_length < 3 || f.xy.norm() < 0.15) continue;
        if (f.id % 4 == 0 && moved.size() < 12) {
          moved.insert(f.id);
          direction[f.id] = Vector2d(-f.xy.y(), f.xy.x()).normalized();
        } else if (f.id % 4 == 1 && labelled.size() < 12) {
          labelled.insert(f.id);
        }
      }
    if (k < 40) return;
    const double shift = 2.0 * static_cast<double>(k - 39) / 460.0;  // normalized units, about 2 px per frame
    for (auto& f : ff.features) {
      if (moved.count(f.id)) last_seen[f.id] = k;
      if (moved.count(f.id)) {
        f.xy += shift * direction[f.id];
        f.xy_right += shift * direction[f.id];
        f.label = frontend::FeatureLabel::kCandidate;
      } else if (labelled.count(f.id) && k <= 41) {
        f.label = frontend::FeatureLabel::kCandidate;
      }
    }
  };
  EstimatorOptions opt;
  opt.candidate_weights = opt.post_process = true;
  std::set<std::uint64_t> confirmed, in_static;
  int confirmations = 0, cleared = 0;
  const RunResult r = runSequence(
      options("city", 6.0), hook, opt,
      [&](const Estimator& e) {
        for (const auto& p : e.staticMap()) in_static.insert(p.id);
      },
      [&](const FrameResult& fr) {
        for (const auto& p : fr.confirmed_points) confirmed.insert(p.id);
        confirmations += fr.confirmed_dynamic;
        cleared += fr.cleared;
      });
  // Judged on the dragged tracks the tracker kept for 2+ frames after marking (a track
  // that ends at once cannot be confirmed; it has no observations since marking).
  int moved_long = 0, moved_confirmed = 0, moved_static = 0, labelled_static = 0, labelled_confirmed = 0;
  for (auto id : moved) {
    moved_static += in_static.count(id);
    if (last_seen[id] < 42) continue;
    ++moved_long;
    moved_confirmed += confirmed.count(id);
  }
  for (auto id : labelled) labelled_static += in_static.count(id), labelled_confirmed += confirmed.count(id);
  std::printf(
      "moved (seen 2+ frames after marking): %d/%d confirmed, %d of %zu in the static map; labelled only: %d/%zu in "
      "the static map, %d confirmed; "
      "%d confirmations, %zu confirmed ids, %d cleared; ATE %.4f m\n",
      moved_confirmed, moved_long, moved_static, moved.size(), labelled_static, labelled.size(), labelled_confirmed,
      confirmations, confirmed.size(), cleared, r.ate);
  ASSERT_EQ(moved.size(), 12u);
  ASSERT_EQ(labelled.size(), 12u);
  EXPECT_GE(moved_long, 8);
  EXPECT_GE(moved_confirmed, moved_long - 1);
  EXPECT_EQ(moved_static, 0);
  EXPECT_GE(labelled_static, 8);
  EXPECT_LE(labelled_confirmed, 1);
  EXPECT_EQ(confirmations, static_cast<int>(confirmed.size()));  // a confirmed track never comes back
  EXPECT_GT(cleared, 8);
  EXPECT_LT(r.ate, 0.01 * r.path);
}

TEST(Estimator, OutliersConfirmedDynamicOnlyWhenEnabled) {
  // The §4.6 extension (EstimatorOptions::confirm_outliers): tracks dragged 2 px per frame
  // from frame 40 on but never marked candidate fail the 3 px outlier test. Enabled, each
  // is removed once, lands in the dynamic map and never in the static map; disabled (the
  // paper's post-processing alone), a removed track comes back as a new landmark from its
  // next observation and is removed again.
  // 16 tracks dragged; judged on those the tracker kept for 6+ frames of dragging (12 px off
  // their static position; a track lost sooner may leave the window as a static point).
  auto run = [](bool confirm, std::map<std::uint64_t, int>& removals, std::set<std::uint64_t>& moved,
                std::set<std::uint64_t>& confirmed, std::set<std::uint64_t>& in_static, int& outliers_confirmed) {
    std::map<std::uint64_t, Vector2d> direction;
    std::map<std::uint64_t, std::size_t> last_seen;
    auto hook = [&](std::size_t k, frontend::FeatureFrame& ff) {
      if (k == 40)
        for (const auto& f : ff.features)
          if (f.track_length >= 3 && f.xy.norm() >= 0.15 && f.id % 4 == 0 && moved.size() < 16) {
            moved.insert(f.id);
            direction[f.id] = Vector2d(-f.xy.y(), f.xy.x()).normalized();
          }
      if (k < 40) return;
      const double shift = 2.0 * static_cast<double>(k - 39) / 460.0;
      for (auto& f : ff.features)
        if (moved.count(f.id)) {
          last_seen[f.id] = k;
          f.xy += shift * direction[f.id];
          f.xy_right += shift * direction[f.id];
        }
    };
    EstimatorOptions opt;
    opt.candidate_weights = opt.post_process = true;
    opt.confirm_outliers = confirm;
    const RunResult r = runSequence(
        options("city", 4.0), hook, opt,
        [&](const Estimator& e) {
          for (const auto& p : e.staticMap()) in_static.insert(p.id);
        },
        [&](const FrameResult& fr) {
          for (const auto& p : fr.confirmed_points) confirmed.insert(p.id);
          for (auto id : fr.outlier_ids) ++removals[id];
          outliers_confirmed += fr.outliers_confirmed;
        });
    for (auto it = moved.begin(); it != moved.end();) it = last_seen[*it] >= 46 ? std::next(it) : moved.erase(it);
    return r;
  };
  std::map<std::uint64_t, int> removals_on, removals_off;
  std::set<std::uint64_t> moved_on, moved_off, confirmed_on, confirmed_off, static_on, static_off;
  int oc_on = 0, oc_off = 0;
  const RunResult on = run(true, removals_on, moved_on, confirmed_on, static_on, oc_on);
  const RunResult off = run(false, removals_off, moved_off, confirmed_off, static_off, oc_off);
  int on_removed = 0, on_confirmed = 0, on_static = 0, on_twice = 0, off_twice = 0, off_confirmed = 0;
  for (auto id : moved_on) {
    on_removed += removals_on.count(id) > 0;
    on_confirmed += confirmed_on.count(id);
    on_static += static_on.count(id);
    on_twice += removals_on.count(id) && removals_on[id] > 1;
  }
  for (auto id : moved_off) {
    off_twice += removals_off.count(id) && removals_off[id] > 1;
    off_confirmed += confirmed_off.count(id);
  }
  std::printf(
      "enabled: %d of %zu long dragged tracks removed, %d confirmed, %d in the static map, %d removed twice, %d "
      "outliers confirmed in all, ATE %.4f m; disabled: %d removed twice, %d confirmed, 0 == %d, ATE %.4f m\n",
      on_removed, moved_on.size(), on_confirmed, on_static, on_twice, oc_on, on.ate, off_twice, off_confirmed, oc_off,
      off.ate);
  ASSERT_GE(moved_on.size(), 8u);
  ASSERT_GE(moved_off.size(), 8u);
  EXPECT_EQ(on_removed, static_cast<int>(moved_on.size()));
  EXPECT_EQ(on_confirmed, on_removed);  // every removed dragged track went to the dynamic map
  EXPECT_EQ(on_static, 0);
  EXPECT_EQ(on_twice, 0);   // a confirmed track never comes back
  EXPECT_GE(off_twice, 4);  // without the extension the removed tracks return
  EXPECT_EQ(off_confirmed, 0);
  EXPECT_EQ(oc_off, 0);
  EXPECT_LT(on.ate, 0.01 * on.path);
}

TEST(Estimator, RightMatchesThatSlidDropOutAndTheLeftTrackStays) {
  // EstimatorOptions::stereo_outlier_px: from frame 50 on, the right matches of every third
  // track then 10+ frames old slide 3 px along the epipolar line (as along an edge). Judged
  // alone, those right observations drop out after a solve and their landmarks stay (the
  // whole-landmark outlier test reads the left observations only); not judged, they bias
  // the depths.
  auto run = [](double stereo_outlier_px, bool slide, int& corrupted, int& dropped, int& removed) {
    std::set<std::uint64_t> slid;
    auto hook = [&, slide](std::size_t k, frontend::FeatureFrame& ff) {
      if (!slide || k < 50) return;
      for (auto& f : ff.features) {
        if (k == 50 && f.has_right && f.track_length >= 10 && f.id % 3 == 0) slid.insert(f.id);
        if (!f.has_right || !slid.count(f.id)) continue;
        f.xy_right.x() += 3.0 / 460.0;
        ++corrupted;
      }
    };
    EstimatorOptions opt;
    opt.stereo_outlier_px = stereo_outlier_px;
    return runSequence(options("city", 4.0), hook, opt, {}, [&](const FrameResult& fr) {
      dropped += fr.right_outliers;
      removed += static_cast<int>(fr.outlier_ids.size());
    });
  };
  int c_clean = 0, d_clean = 0, r_clean = 0, c_on = 0, d_on = 0, r_on = 0, c_off = 0, d_off = 0, r_off = 0;
  const RunResult clean = run(1.0, false, c_clean, d_clean, r_clean);
  const RunResult on = run(1.0, true, c_on, d_on, r_on);
  const RunResult off = run(0.0, true, c_off, d_off, r_off);
  std::printf(
      "clean: %d right observations dropped, ATE %.4f m; slid (%d): judged alone %d dropped, %d landmarks "
      "removed (clean %d), ATE %.4f m; not judged: %d dropped, ATE %.4f m\n",
      d_clean, clean.ate, c_on, d_on, r_on, r_clean, on.ate, d_off, off.ate);
  ASSERT_GT(c_on, 300);
  EXPECT_EQ(d_off, 0);
  EXPECT_GE(d_on - d_clean, c_on * 85 / 100);  // nearly every slid right match dropped
  EXPECT_LE(r_on, r_clean + 5);                // their landmarks stay
  EXPECT_LT(on.ate, off.ate);
  EXPECT_LT(on.ate, 1.5 * clean.ate);
}

TEST(Initializer, AlignmentRecoversGravityAndVelocityFromExactData) {
  sim::SimOptions o = options("city", 1.0);
  o.imu.scale = 0.0;
  const sim::Trajectory traj("city", 2);
  std::vector<ImuSample> imu;
  std::vector<GroundTruthState> gt;
  sim::synthesizeImu(traj, o, imu, gt);
  // Visual poses in a frame rotated by R_v_w (yaw, roll, pitch unknown to the aligner).
  const Eigen::Quaterniond R_v_w(Eigen::AngleAxisd(0.7, Vector3d(1, 2, 3).normalized()));
  std::vector<Eigen::Isometry3d> T;
  std::vector<std::unique_ptr<imu::Preintegration>> pre;
  std::vector<const imu::Preintegration*> ptrs;
  for (int i = 0; i <= 10; ++i) {
    const GroundTruthState& g = gt[i * 10];
    Eigen::Isometry3d Ti = Eigen::Isometry3d::Identity();
    Ti.linear() = (R_v_w * g.q_w_b).toRotationMatrix();
    Ti.translation() = R_v_w * g.p_w_b;
    T.push_back(Ti);
    pre.push_back(i == 0 ? nullptr
                         : std::make_unique<imu::Preintegration>(
                               imu::integrateBetween(imu, gt[(i - 1) * 10].t_ns, g.t_ns, Vector3d::Zero(),
                                                     Vector3d::Zero(), ImuNoise{0.1, 0.01, 0.001, 0.0001, 9.81})));
    ptrs.push_back(pre.back().get());
  }
  const Alignment a = alignVelocityGravity(T, ptrs, 9.81);
  ASSERT_TRUE(a.ok);
  EXPECT_NEAR(a.g_norm_estimated, 9.81, 0.01);
  EXPECT_LT((a.g_w - R_v_w * Vector3d(0, 0, 9.81)).norm(), 0.01);
  for (int i = 0; i <= 10; ++i) EXPECT_LT((a.v_w[i] - R_v_w * gt[i * 10].v_w).norm(), 0.005) << i;
  // Gyro bias: a constant bias added to the samples is recovered.
  std::vector<ImuSample> biased = imu;
  const Vector3d bg(0.01, -0.02, 0.015);
  for (auto& s : biased) s.gyr_b += bg;
  std::vector<std::unique_ptr<imu::Preintegration>> pre_b;
  std::vector<const imu::Preintegration*> ptrs_b;
  std::vector<Eigen::Quaterniond> q;
  for (int i = 0; i <= 10; ++i) {
    q.push_back(gt[i * 10].q_w_b);
    pre_b.push_back(i == 0 ? nullptr
                           : std::make_unique<imu::Preintegration>(
                                 imu::integrateBetween(biased, gt[(i - 1) * 10].t_ns, gt[i * 10].t_ns, Vector3d::Zero(),
                                                       Vector3d::Zero(), ImuNoise{0.1, 0.01, 0.001, 0.0001, 9.81})));
    ptrs_b.push_back(pre_b.back().get());
  }
  EXPECT_LT((solveGyroBias(q, ptrs_b) - bg).norm(), 2e-4);
  // Intervals last propagated with other biases (a start that failed and is tried again, a new
  // frame at zero) give the same bias, not a correction of theirs.
  for (int i = 1; i <= 10; ++i) pre_b[i]->repropagate(Vector3d::Zero(), i % 2 ? bg : Vector3d(0.03, 0.01, -0.02));
  EXPECT_LT((solveGyroBias(q, ptrs_b) - bg).norm(), 2e-4);
}

TEST(Initializer, RotationAlignmentRecoversTheCameraImuTimeOffset) {
  // A walked trajectory (its rotation rate changes with the gait and the look-around), a
  // gyroscope bias, frames stamped td before their capture on the IMU clock.
  sim::SimOptions o = options("city", 1.5);
  o.imu.scale = 0.0;
  const sim::Trajectory traj("city", 1, 9.81, sim::TrajectoryStyle::kHandheld);
  std::vector<ImuSample> imu;
  std::vector<GroundTruthState> gt;
  sim::synthesizeImu(traj, o, imu, gt);
  for (auto& s : imu) s.gyr_b += Vector3d(0.01, -0.02, 0.015);
  for (double td : {-0.012, 0.0, 0.0074, 0.02}) {
    std::vector<Eigen::Quaterniond> q;
    std::vector<TimeNs> t;
    for (int k = 0; k <= 10; ++k) {
      const double t_capture = 0.2 + 0.05 * k;
      q.push_back(traj.at(t_capture).q_w_b);
      t.push_back(imu.front().t_ns + static_cast<TimeNs>(std::llround((t_capture - td) * 1e9)));
    }
    const std::optional<double> found = alignRotationTimes(q, t, imu, 0.03);
    ASSERT_TRUE(found.has_value()) << td;
    EXPECT_NEAR(*found, td, 2e-4) << td;
  }
  // Out of range: the best shift lies on the edge and nothing is returned.
  std::vector<Eigen::Quaterniond> q;
  std::vector<TimeNs> t;
  for (int k = 0; k <= 10; ++k) {
    q.push_back(traj.at(0.2 + 0.05 * k).q_w_b);
    t.push_back(imu.front().t_ns + static_cast<TimeNs>(std::llround((0.2 + 0.05 * k - 0.06) * 1e9)));
  }
  EXPECT_FALSE(alignRotationTimes(q, t, imu, 0.03).has_value());
}

TEST(Initializer, RotationAlignmentOverTwoSecondsFindsFiftyMillisecondsAndKnowsWhenItCannot) {
  // The initialization's search (estimate_td): ±60 ms over 2 s of poses at 20 Hz.
  sim::SimOptions o = options("city", 3.5);
  o.imu.scale = 0.0;
  const sim::Trajectory traj("city", 2, 9.81, sim::TrajectoryStyle::kHandheld);
  std::vector<ImuSample> imu;
  std::vector<GroundTruthState> gt;
  sim::synthesizeImu(traj, o, imu, gt);
  for (auto& s : imu) s.gyr_b += Vector3d(0.01, -0.02, 0.015);
  const auto poses = [&](double td, std::vector<Eigen::Quaterniond>& q, std::vector<TimeNs>& t) {
    q.clear();
    t.clear();
    for (int k = 0; k <= 40; ++k) {
      const double t_capture = 0.5 + 0.05 * k;
      q.push_back(traj.at(t_capture).q_w_b);
      t.push_back(imu.front().t_ns + static_cast<TimeNs>(std::llround((t_capture - td) * 1e9)));
    }
  };
  std::vector<Eigen::Quaterniond> q;
  std::vector<TimeNs> t;
  for (double td : {-0.05, 0.031, 0.05}) {
    poses(td, q, t);
    double contrast = 0;
    const std::optional<double> found = alignRotationTimes(q, t, imu, 0.06, 0.001, &contrast);
    ASSERT_TRUE(found.has_value()) << td;
    EXPECT_NEAR(*found, td, 2e-4) << td;
    EXPECT_GT((contrast - 1.0) * static_cast<double>(q.size() - 4), 10 * kTdSignificance)
        << "a walk's rotations tell the offset";
  }
  // At rest (one orientation, the gyroscope reading its bias and noise): nothing tells the
  // shift, and the contrast says so.
  std::vector<ImuSample> still = imu;
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 0.002);
  for (auto& s : still) s.gyr_b = Vector3d(0.01, -0.02, 0.015) + Vector3d(noise(rng), noise(rng), noise(rng));
  poses(0.02, q, t);
  for (auto& qk : q) qk = q.front();
  double contrast = 0;
  const std::optional<double> found = alignRotationTimes(q, t, still, 0.06, 0.001, &contrast);
  if (found) {
    EXPECT_LT((contrast - 1.0) * static_cast<double>(q.size() - 4), kTdSignificance)
        << "the estimator keeps the config's offset";
  }
}

TEST(FeatureManager, TriangulationAndReanchoring) {
  Rig rig;
  rig.T_b_c0.q_b_c = Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Vector3d::UnitY()));
  rig.T_b_c1 = rig.T_b_c0;
  rig.T_b_c1.t_b_c = rig.T_b_c0.q_b_c * Vector3d(0.11, 0, 0);
  Eigen::Isometry3d T0 = Eigen::Isometry3d::Identity(), T1 = Eigen::Isometry3d::Identity();
  T1.translation() = Vector3d(0.4, 0.1, 0.2);
  T1.linear() = Eigen::AngleAxisd(0.1, Vector3d::UnitZ()).toRotationMatrix();
  const Vector3d p_w(1.0, -0.5, 6.0);
  auto observe = [&](const Eigen::Isometry3d& T_w_b, const Extrinsic& e) {
    const Vector3d p = cameraPose(T_w_b, e).inverse() * p_w;
    return Vector2d(p.x() / p.z(), p.y() / p.z());
  };
  EXPECT_LT((triangulateTwoViews(cameraPose(T0, rig.T_b_c0), observe(T0, rig.T_b_c0), cameraPose(T1, rig.T_b_c0),
                                 observe(T1, rig.T_b_c0)) -
             p_w)
                .norm(),
            1e-9);
  FeatureManager fm;
  for (int frame = 0; frame < 2; ++frame) {
    frontend::FeatureFrame ff;
    frontend::Feature f;
    f.id = 7;
    f.xy = observe(frame ? T1 : T0, rig.T_b_c0);
    f.has_right = true;
    f.xy_right = observe(frame ? T1 : T0, rig.T_b_c1);
    ff.features.push_back(f);
    fm.addFrame(frame, ff, 10.0, 460.0);
  }
  fm.triangulate({T0, T1}, rig);
  const Landmark& lm = fm.landmarks().at(7);
  EXPECT_NEAR(1.0 / lm.inv_depth, (cameraPose(T0, rig.T_b_c0).inverse() * p_w).z(), 1e-9);
  fm.removeOldest({T0, T1}, rig);
  const Landmark& moved = fm.landmarks().at(7);
  EXPECT_EQ(moved.start_frame, 0);
  EXPECT_EQ(moved.obs.size(), 1u);
  EXPECT_NEAR(1.0 / moved.inv_depth, (cameraPose(T1, rig.T_b_c0).inverse() * p_w).z(), 1e-9);
}

TEST(FeatureManager, TriangulateViewsFindsThePointAndRefusesOneView) {
  const Vector3d p_w(0.7, -0.4, 9.0);
  std::vector<Eigen::Isometry3d> T_w_c;
  std::vector<Vector2d> xy;
  for (int k = 0; k < 4; ++k) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.translation() = Vector3d(0.3 * k, 0.05 * k, 0.2 * k);
    T.linear() = Eigen::AngleAxisd(0.02 * k, Vector3d::UnitY()).toRotationMatrix();
    const Vector3d p = T.inverse() * p_w;
    T_w_c.push_back(T);
    xy.emplace_back(p.x() / p.z(), p.y() / p.z());
  }
  const auto found = triangulateViews(T_w_c, xy);
  ASSERT_TRUE(found.has_value());
  EXPECT_LT((*found - p_w).norm(), 1e-9);
  EXPECT_FALSE(triangulateViews({T_w_c[0]}, {xy[0]}).has_value());
  EXPECT_FALSE(triangulateViews({T_w_c[0], T_w_c[0]}, {xy[0], xy[0]}).has_value());  // no baseline
  // Observations 0.5 px off (f = 460) in alternating directions: the fit stays within
  // what the noise allows and sees the point in front of every view.
  for (std::size_t k = 0; k < xy.size(); ++k) xy[k].x() += (k % 2 ? 0.5 : -0.5) / 460.0;
  const auto noisy = triangulateViews(T_w_c, xy);
  ASSERT_TRUE(noisy.has_value());
  EXPECT_LT((*noisy - p_w).norm(), 0.5);
  EXPECT_GT((*noisy - p_w).norm(), 1e-6);
}

TEST(FeatureManager, ReanchoringCanKeepTheMultiViewPointInsteadOfTheNextRay) {
  // 40 points seen by 8 frames walking forward, every observation 0.3 px noisy (f = 460).
  // As VINS-Fusion, a re-anchored landmark moves onto its next (noisy) ray at its depth;
  // with retriangulate it keeps the point that fits all its observations, which the new
  // anchor ray then points at.
  Rig rig;
  rig.T_b_c1.t_b_c = Vector3d(0.11, 0, 0);
  std::vector<Eigen::Isometry3d> T(8, Eigen::Isometry3d::Identity());
  for (int k = 0; k < 8; ++k) T[k].translation() = Vector3d(0.02 * k, 0.0, 0.15 * k);
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, 0.3 / 460.0);
  auto observe = [&](const Vector3d& p_w, const Eigen::Isometry3d& T_w_b, const Extrinsic& e) {
    const Vector3d p = cameraPose(T_w_b, e).inverse() * p_w;
    return Vector2d(p.x() / p.z() + noise(rng), p.y() / p.z() + noise(rng));
  };
  std::vector<Vector3d> points;
  std::uniform_real_distribution<double> lateral(-3.0, 3.0), depth(5.0, 15.0);
  for (int i = 0; i < 40; ++i) points.emplace_back(lateral(rng), 0.3 * lateral(rng), depth(rng));
  std::vector<frontend::FeatureFrame> frames(8);
  for (int frame = 0; frame < 8; ++frame)
    for (std::size_t i = 0; i < points.size(); ++i) {
      frontend::Feature f;
      f.id = i;
      f.xy = observe(points[i], T[frame], rig.T_b_c0);
      f.has_right = true;
      f.xy_right = observe(points[i], T[frame], rig.T_b_c1);
      frames[frame].features.push_back(f);
    }
  auto meanError = [&](bool retriangulate) {
    FeatureManager fm;
    for (int frame = 0; frame < 8; ++frame) fm.addFrame(frame, frames[frame], 10.0, 460.0);
    fm.triangulate(T, rig);
    fm.removeOldest(T, rig, retriangulate);
    double sum = 0;
    for (std::size_t i = 0; i < points.size(); ++i) {
      const Landmark& lm = fm.landmarks().at(i);
      const Vector2d measured = frames[1].features[i].xy;
      EXPECT_EQ((lm.obs[0].xy - measured).norm() == 0.0, !retriangulate);  // the ray: measured or estimated
      const Vector3d p_c(lm.obs[0].xy.x() / lm.inv_depth, lm.obs[0].xy.y() / lm.inv_depth, 1.0 / lm.inv_depth);
      sum += (cameraPose(T[1], rig.T_b_c0) * p_c - points[i]).norm();
    }
    return sum / static_cast<double>(points.size());
  };
  const double moved_to_ray = meanError(false), kept = meanError(true);
  EXPECT_GT(moved_to_ray, 0.05);
  EXPECT_LT(kept, 0.5 * moved_to_ray);
}

TEST(FeatureManager, AnEstimatedRayKeepsThePointAndTheMeasurementWhenReanchored) {
  // estimate_anchor_ray: a re-anchored landmark stays where it was (same world point), its
  // new anchor ray points at it, and the new anchor observation stays the measurement (a
  // residual in the next solve). Without it the ray is the measurement.
  Rig rig;
  rig.T_b_c1.t_b_c = Vector3d(0.11, 0, 0);
  std::vector<Eigen::Isometry3d> T(3, Eigen::Isometry3d::Identity());
  for (int k = 0; k < 3; ++k) T[k].translation() = Vector3d(0.05 * k, 0.0, 0.3 * k);
  const Vector3d p_w(1.0, -0.5, 9.0);
  auto project = [&](int k, const Vector2d& offset) {
    const Vector3d p = cameraPose(T[k], rig.T_b_c0).inverse() * p_w;
    return Vector2d(p.head<2>() / p.z() + offset);
  };
  for (bool ray_estimates : {false, true}) {
    FeatureManager fm;
    for (int k = 0; k < 3; ++k) {
      frontend::FeatureFrame ff;
      frontend::Feature f;
      f.id = 7;
      f.xy = project(k, k == 1 ? Vector2d(2e-3, -1e-3) : Vector2d::Zero());  // frame 1: ~1 px off
      ff.features.push_back(f);
      fm.addFrame(k, ff, 10.0, 460.0);
    }
    Landmark& lm = fm.landmarks().at(7);
    lm.inv_depth = 1.0 / (cameraPose(T[0], rig.T_b_c0).inverse() * p_w).z();  // the exact depth
    fm.removeOldest(T, rig, false, ray_estimates);
    const Landmark& moved = fm.landmarks().at(7);
    EXPECT_EQ(moved.ray_estimated, ray_estimates);
    EXPECT_LT((moved.obs[0].xy - project(1, Vector2d(2e-3, -1e-3))).norm(), 1e-15);  // measurement untouched
    const Vector3d p_after = cameraPose(T[1], rig.T_b_c0) * moved.anchorPoint();
    if (ray_estimates) {
      EXPECT_LT((p_after - p_w).norm(), 1e-9);
      EXPECT_LT((moved.anchorRay() - project(1, Vector2d::Zero())).norm(), 1e-12);
    } else {
      EXPECT_GT((p_after - p_w).norm(), 0.01);  // moved onto the noisy ray
    }
  }
}

TEST(FeatureManager, RightMatchesKeptOutOfTheMotionTestsAreStereoObservations) {
  // A right match that failed only the tracker's patch-correlation check
  // (stereo_zncc_motion_only) reaches the estimator: the anchor is triangulated from it.
  Rig rig;
  rig.T_b_c1.t_b_c = Vector3d(0.11, 0, 0);
  const Vector3d p_c0(0.5, -0.2, 7.0);
  frontend::FeatureFrame ff;
  frontend::Feature f;
  f.id = 3;
  f.xy = Vector2d(p_c0.x() / p_c0.z(), p_c0.y() / p_c0.z());
  f.right_low_zncc = true;  // has_right stays false: no motion test sees it
  f.xy_right = Vector2d((p_c0.x() - 0.11) / p_c0.z(), p_c0.y() / p_c0.z());
  ff.features.push_back(f);
  FeatureManager fm;
  fm.addFrame(0, ff, 10.0, 460.0);
  const Landmark& lm = fm.landmarks().at(3);
  ASSERT_TRUE(lm.obs.front().has_right);
  fm.triangulate({Eigen::Isometry3d::Identity()}, rig);
  EXPECT_TRUE(lm.usable());
  EXPECT_NEAR(1.0 / fm.landmarks().at(3).inv_depth, p_c0.z(), 1e-9);
}

}  // namespace
}  // namespace idyvins::backend
