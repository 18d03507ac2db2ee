// pipeline::System driven as an embedding user would (no CLI, no files): a short rendered
// city-high sequence in memory, trajectory against ground truth, labels against the masks.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <set>
#include <sstream>

#include "config/modes.h"
#include "core/error.h"
#include "eval/trajectory_metrics.h"
#include "pipeline/front_end.h"
#include "pipeline/observers.h"
#include "pipeline/outputs.h"
#include "pipeline/stereo_sync.h"
#include "pipeline/system.h"
#include "sim/simulator.h"

namespace idyvins::pipeline {
namespace {

/// Counts the frames it sees and checks they come in order, once each; keeps the static
/// points each frame gives.
class OrderObserver final : public FrameObserver {
 public:
  void onFrame(const StereoFrame& input, const FrameOutput& out) override {
    EXPECT_EQ(out.index, frames);
    EXPECT_EQ(out.t_ns, input.t_ns);
    ++frames;
    streamed_static.insert(streamed_static.end(), out.new_static_points.begin(), out.new_static_points.end());
    if (const auto& kf = out.estimate.left_window) {
      ++keyframes_left;
      for (const auto& o : kf->observations)
        (o.label == FeatureLabel::kStatic ? left_static : left_not_static).insert({kf->t_ns, o.id});
    }
  }
  std::size_t frames = 0, keyframes_left = 0;
  std::vector<backend::MapPoint> streamed_static;
  std::set<std::pair<TimeNs, std::uint64_t>> left_static, left_not_static;  ///< (keyframe time, landmark id)
};

struct SceneRun {
  Result result;
  eval::DynamicClassification classification;
  std::vector<StampedPose> truth;
  std::size_t observed_frames = 0, outputs_with_pose = 0;
  std::size_t polled = 0;                          ///< frames System::poll() processed
  std::vector<backend::MapPoint> streamed_static;  ///< FrameOutput::new_static_points, in order
  std::size_t keyframes_left = 0;                  ///< FrameResult::left_window events
  std::set<std::pair<TimeNs, std::uint64_t>> left_static, left_not_static;
};

/// Runs a rendered city-high sequence. Offline order: each frame after the IMU samples up
/// to its stamp. `live`: as a driver whose images come before the IMU: each frame before
/// those samples, System::poll() after every sample.
SceneRun runScene(Mode mode, double duration_s, const RunOptions& run_options = {},
                  const std::function<void(std::vector<ImuSample>&)>& corrupt_imu = {}, bool live = false,
                  const std::function<bool(StereoFrame&)>& corrupt_frame = {},
                  const std::function<void(Config&)>& configure = {},
                  const std::function<void(const System&)>& inspect = {}) {
  sim::SimOptions o;
  o.scene.scene = "city";
  o.scene.level = sim::Level::kHigh;
  o.scene.seed = 2;
  o.duration_s = duration_s;
  const sim::Scene scene(o);
  std::vector<ImuSample> imu;
  std::vector<GroundTruthState> gt;
  sim::synthesizeImu(scene.trajectory(), o, imu, gt);
  if (corrupt_imu) corrupt_imu(imu);
  Config config = scene.rig();
  config.estimator.max_solver_time_s = 1000;  // iterations, not the wall clock, end each solve
  config.mode = mode;
  if (configure) configure(config);

  System system(config, run_options);
  ObservationRecorder recorder(/*has_masks=*/true);
  OrderObserver order;
  system.addObserver(recorder);
  system.addObserver(order);
  SceneRun run;
  std::size_t next_imu = 0;
  for (std::size_t k = 0; k < scene.frameCount(); ++k) {
    const sim::SceneFrame f = scene.renderFrame(k);
    auto imuUpTo = [&](TimeNs t) {
      while (next_imu < imu.size() && imu[next_imu].t_ns <= t) {
        system.addImu(imu[next_imu++]);
        if (live) run.polled += system.poll();
      }
    };
    StereoFrame frame;
    frame.t_ns = f.t_ns;
    frame.index = k;
    frame.left = f.cam[0].image;
    frame.right = f.cam[1].image;
    frame.left_mask = f.cam[0].mask;
    if (corrupt_frame && !corrupt_frame(frame)) continue;  // false: the frame is lost
    if (!live) imuUpTo(frame.t_ns);
    const FrameOutput* out = system.addFrame(frame);
    if (out && out->estimate.initialized) ++run.outputs_with_pose;
    if (live) imuUpTo(frame.t_ns);
  }
  for (const auto& g : gt) run.truth.push_back({g.t_ns, g.p_w_b, g.q_w_b});
  run.result = system.finish();
  if (inspect) inspect(system);
  run.classification = recorder.classify(run.result);
  run.observed_frames = order.frames;
  run.streamed_static = std::move(order.streamed_static);
  run.keyframes_left = order.keyframes_left;
  run.left_static = std::move(order.left_static);
  run.left_not_static = std::move(order.left_not_static);
  return run;
}

double ate(const SceneRun& run) {
  std::vector<StampedPose> est;
  for (const auto& s : run.result.trajectory) est.push_back(toStampedPose(s));
  return eval::computeAte(run.truth, est, eval::AlignMode::kSe3, 1'000'000).stats.rmse;
}

TEST(PipelineSystem, ImpossibleAndOutOfOrderImuSamplesAreDroppedAndCounted) {
  // Spikes of 1e30 m/s², a NaN rate and a repeated stamp in a 4 s sequence: dropped,
  // counted, and the run goes on as if those samples were missing.
  const SceneRun clean = runScene(Mode::kBaseline, 4.0);
  std::size_t spikes = 0;
  const SceneRun faulty = runScene(Mode::kBaseline, 4.0, {}, [&](std::vector<ImuSample>& imu) {
    for (std::size_t k = 101; k < imu.size(); k += 97, ++spikes) imu[k].acc_b.x() = 1e30;
    imu[333].gyr_b.z() = std::numeric_limits<double>::quiet_NaN();
    imu[400].gyr_b = Eigen::Vector3d(0, 0, 40.0);  // beyond 35 rad/s
    imu.insert(imu.begin() + 500, imu[499]);       // the same stamp twice
  });
  EXPECT_EQ(clean.result.summary.imu_out_of_range + clean.result.summary.imu_out_of_order, 0u);
  EXPECT_EQ(faulty.result.summary.imu_out_of_range, spikes + 2);
  EXPECT_EQ(faulty.result.summary.imu_out_of_order, 1u);
  for (const auto& r : faulty.result.summary.resets) ADD_FAILURE() << "reset at frame " << r.frame << ": " << r.why;
  EXPECT_EQ(faulty.result.trajectory.size(), clean.result.trajectory.size());
  EXPECT_LT(ate(faulty), 1.5 * ate(clean) + 0.005) << "clean " << ate(clean);
}

TEST(PipelineSystem, ShortImuSpikesWithinTheLimitsAreDroppedAndCounted) {
  // Three 25 ms spikes of 10 g (within imu_max_acc) in a 4 s sequence: the spike gate drops
  // them, the run goes on as if those samples were missing; with the gate off they are
  // integrated and cost the trajectory.
  const SceneRun clean = runScene(Mode::kBaseline, 4.0);
  const auto spike = [](std::vector<ImuSample>& imu) {
    for (std::size_t start : {250u, 420u, 610u})
      for (std::size_t k = start; k < start + 5; ++k) imu[k].acc_b.x() += 100.0;
  };
  const SceneRun gated = runScene(Mode::kBaseline, 4.0, {}, spike);
  const SceneRun ungated =
      runScene(Mode::kBaseline, 4.0, {}, spike, false, {}, [](Config& c) { c.imu.spike.max_ms = 0; });
  EXPECT_EQ(clean.result.summary.imu_spikes, 0u);
  EXPECT_EQ(gated.result.summary.imu_spikes, 3u);
  EXPECT_EQ(gated.result.summary.imu_spike_samples, 15u);
  EXPECT_EQ(gated.result.summary.imu_out_of_range, 0u);
  EXPECT_EQ(ungated.result.summary.imu_spikes, 0u);
  for (const auto& r : gated.result.summary.resets) ADD_FAILURE() << "reset at frame " << r.frame << ": " << r.why;
  EXPECT_EQ(gated.result.trajectory.size(), clean.result.trajectory.size());
  EXPECT_LT(ate(gated), 1.5 * ate(clean) + 0.005) << "clean " << ate(clean);
  EXPECT_GT(ate(ungated), 3 * ate(gated)) << "gated " << ate(gated);
}

TEST(PipelineSystem, FramesBetweenImuSamplesAreReachedByInterpolation) {
  // No IMU sample at any frame's stamp (an IMU not synchronized with the cameras): each
  // frame waits for the next sample and is integrated to by interpolation, no reset.
  const SceneRun clean = runScene(Mode::kBaseline, 4.0);
  const SceneRun between = runScene(Mode::kBaseline, 4.0, {}, [](std::vector<ImuSample>& imu) {
    std::vector<ImuSample> kept;
    for (std::size_t k = 0; k < imu.size(); ++k)
      if (k % 10 != 0) kept.push_back(imu[k]);  // 200 Hz IMU, 20 Hz frames: the samples at frame times
    imu = kept;
  });
  for (const auto& r : between.result.summary.resets) ADD_FAILURE() << "reset at frame " << r.frame << ": " << r.why;
  // The last frame: runScene feeds no IMU after it, and its own-time sample is gone.
  EXPECT_EQ(between.result.summary.frames_beyond_imu, 1u);
  EXPECT_GE(between.result.trajectory.size() + 5, clean.result.trajectory.size());  // measured 68 vs 71
  EXPECT_LT(ate(between), 1.5 * ate(clean) + 0.005) << "clean " << ate(clean);
}

TEST(PipelineSystem, IdyThroughTheLibraryApiTracksTheTruthAndLabelsTheMovingTraffic) {
  const SceneRun idy = runScene(Mode::kIdy, 6.0);
  const Summary& s = idy.result.summary;
  EXPECT_EQ(s.frames, 121u);
  EXPECT_EQ(idy.observed_frames, 121u);
  EXPECT_EQ(idy.result.trajectory.size(), idy.outputs_with_pose);
  EXPECT_GT(idy.result.trajectory.size(), 100u);  // initialized within the first second
  EXPECT_TRUE(s.resets.empty());
  const double error = ate(idy);
  EXPECT_LT(error, 0.06) << "ATE over about 12 m";
  // Labels against the masks, the same measure as `idyvins run` reports.
  EXPECT_GT(idy.classification.observations_on_moving, 1000u);
  EXPECT_GT(idy.classification.recall, 0.75);
  EXPECT_LT(idy.classification.static_flagged, 0.05);
  EXPECT_LT(idy.classification.static_map_fraction_on_moving, 0.02);
  EXPECT_GT(idy.result.static_map.size(), 200u);
  std::size_t eliminated = 0;
  for (const auto& p : idy.result.dynamic_map) eliminated += p.label == frontend::FeatureLabel::kEliminated;
  EXPECT_GT(eliminated, 100u) << "eliminated features triangulated into the dynamic map";
  std::printf("idy: ATE %.4f m, moving flagged %.1f %%, static flagged %.2f %%, static map on moving %.2f %%\n", error,
              100 * idy.classification.recall, 100 * idy.classification.static_flagged,
              100 * idy.classification.static_map_fraction_on_moving);
}

TEST(PipelineSystem, BaselineThroughTheLibraryApiFlagsNothing) {
  const SceneRun base = runScene(Mode::kBaseline, 3.0);
  EXPECT_EQ(base.classification.true_positives + base.classification.false_positives, 0u);
  EXPECT_TRUE(
      base.result.dynamic_map.empty() ||
      std::all_of(base.result.dynamic_map.begin(), base.result.dynamic_map.end(),
                  [](const backend::MapPoint& p) { return p.label == frontend::FeatureLabel::kConfirmedDynamic; }));
  EXPECT_GT(base.result.trajectory.size(), 40u);
}

bool sameTrajectory(const Result& a, const Result& b) {
  if (a.trajectory.size() != b.trajectory.size()) return false;
  for (std::size_t i = 0; i < a.trajectory.size(); ++i) {
    const imu::NavState &x = a.trajectory[i].state, &y = b.trajectory[i].state;
    if (a.trajectory[i].t_ns != b.trajectory[i].t_ns || x.p_w_b != y.p_w_b || x.q_w_b.coeffs() != y.q_w_b.coeffs() ||
        x.v_w != y.v_w || x.ba != y.ba || x.bg != y.bg)
      return false;
  }
  return true;
}

bool sameMap(const std::vector<backend::MapPoint>& a, const std::vector<backend::MapPoint>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i)
    if (a[i].p_w != b[i].p_w || a[i].label != b[i].label || a[i].id != b[i].id) return false;
  return true;
}

TEST(PipelineSystem, PipelinedRunEqualsTheSequentialRunWithTheSameFeedbackDelay) {
  // Two threads (front end of frame k+1 beside the back end of frame k) against one thread
  // with the same data flow (feedback delay 1): bit-identical states, maps and labels.
  const SceneRun one = runScene(Mode::kIdy, 4.0, RunOptions{false, 1});
  const SceneRun two = runScene(Mode::kIdy, 4.0, RunOptions::twoThreads());
  EXPECT_TRUE(sameTrajectory(one.result, two.result));
  EXPECT_TRUE(sameMap(one.result.static_map, two.result.static_map));
  EXPECT_TRUE(sameMap(one.result.dynamic_map, two.result.dynamic_map));
  EXPECT_EQ(one.classification.true_positives, two.classification.true_positives);
  EXPECT_EQ(one.classification.false_positives, two.classification.false_positives);
  EXPECT_EQ(two.observed_frames, 81u) << "every frame reaches the observers, the last one at finish()";
  EXPECT_EQ(one.result.summary.frames_without_prior, two.result.summary.frames_without_prior);
  // What the one-frame-older prior changes: not the first frames (no prior yet), the
  // trajectory a little, the labels a little; both runs stay accurate.
  const SceneRun zero = runScene(Mode::kIdy, 4.0);
  EXPECT_FALSE(sameTrajectory(zero.result, one.result));
  EXPECT_EQ(one.result.summary.frames_without_prior, zero.result.summary.frames_without_prior + 1)
      << "the older prior exists one frame later";
  EXPECT_LT(ate(one), 0.05);
  EXPECT_LT(ate(zero), 0.05);
  EXPECT_NEAR(one.classification.recall, zero.classification.recall, 0.05);
  EXPECT_NEAR(one.classification.static_flagged, zero.classification.static_flagged, 0.01);
  std::printf("feedback delay 0 / 1: ATE %.4f / %.4f m, moving flagged %.1f / %.1f %%, static flagged %.2f / %.2f %%\n",
              ate(zero), ate(one), 100 * zero.classification.recall, 100 * one.classification.recall,
              100 * zero.classification.static_flagged, 100 * one.classification.static_flagged);
}

TEST(PipelineSystem, PollProcessesAWaitingFrameAsSoonAsItsImuIsHereWithTheSameOutputs) {
  // Images before their IMU samples, as a live driver may get them: each frame waits in the
  // system until poll() after the sample at its stamp processes it. The outputs are those
  // of the offline order, bit for bit.
  const SceneRun offline = runScene(Mode::kIdy, 4.0, RunOptions::twoThreads());
  const SceneRun live = runScene(Mode::kIdy, 4.0, RunOptions::twoThreads(), {}, /*live=*/true);
  EXPECT_EQ(offline.polled, 0u);
  EXPECT_EQ(live.polled, 81u) << "every frame processed by poll(), none held until the next frame";
  EXPECT_TRUE(sameTrajectory(offline.result, live.result));
  EXPECT_TRUE(sameMap(offline.result.static_map, live.result.static_map));
  EXPECT_TRUE(sameMap(offline.result.dynamic_map, live.result.dynamic_map));
  EXPECT_GT(live.result.trajectory.size(), 60u);
  // The static points given frame by frame are the static map but for the landmarks still in
  // the window at the end (finish() adds those).
  const auto& map = live.result.static_map;
  ASSERT_GT(live.streamed_static.size(), 50u);
  ASSERT_LT(live.streamed_static.size(), map.size());
  EXPECT_TRUE(sameMap(live.streamed_static, {map.begin(), map.begin() + live.streamed_static.size()}));
}

// Faults a robot meets (issue: one continuous trajectory through faults). An 8 s city-high
// sequence, the fault at 4 s; the run must complete, report the reset and its cause, and
// keep one trajectory in one world frame.
constexpr double kFaultSeqS = 8.0;
constexpr TimeNs kFaultAt = 1'700'000'004'000'000'000;  // 4 s into the sequence (SimOptions::t0_ns + 4 s)

struct FaultCheck {
  std::size_t resets = 0;
  std::string why, continued_by;
  double ate_whole = 0;       ///< ATE over the whole file
  double worst_excess_m = 0;  ///< largest step between consecutive poses beyond the truth's step
};

FaultCheck checkFault(const SceneRun& run, TimeNs shift_after = std::numeric_limits<TimeNs>::max(), TimeNs shift = 0) {
  FaultCheck c;
  const auto& resets = run.result.summary.resets;
  c.resets = resets.size();
  if (!resets.empty()) {
    c.why = resets.front().why;
    c.continued_by = resets.front().continued_by;
    std::printf("reset at %+.3f s, resumed at %+.3f s, last status %s\n",
                1e-9 * static_cast<double>(resets.front().t_ns - kFaultAt),
                1e-9 * static_cast<double>(resets.front().resumed_t_ns - kFaultAt),
                run.result.summary.last_status.c_str());
  }
  std::vector<StampedPose> truth = run.truth, est;
  for (auto& g : truth)  // ground truth on the shifted clock (time jump)
    if (g.t_ns >= shift_after) g.t_ns += shift;
  for (const auto& s : run.result.trajectory) est.push_back(toStampedPose(s));
  c.ate_whole = eval::computeAte(truth, est, eval::AlignMode::kSe3, 1'000'000).stats.rmse;
  auto truthAt = [&](TimeNs t) {
    const auto it =
        std::lower_bound(truth.begin(), truth.end(), t, [](const StampedPose& p, TimeNs x) { return p.t_ns < x; });
    return it == truth.end() ? truth.back().p_w_b : it->p_w_b;
  };
  for (std::size_t i = 1; i < est.size(); ++i) {
    const double step = (est[i].p_w_b - est[i - 1].p_w_b).norm();
    const double truth_step = (truthAt(est[i].t_ns) - truthAt(est[i - 1].t_ns)).norm();
    c.worst_excess_m = std::max(c.worst_excess_m, step - truth_step);
  }
  std::printf("resets %zu (%s; continued by %s), ATE whole file %.3f m, largest step beyond the truth's %.3f m\n",
              c.resets, c.why.c_str(), c.continued_by.c_str(), c.ate_whole, c.worst_excess_m);
  return c;
}

TEST(PipelineSystem, LoopClosureKeyframeDatabaseHoldsStaticLandmarksOnly) {
  // City with heavy traffic: keyframes leave the window seeing candidates and moving points too.
  std::vector<std::pair<TimeNs, std::uint64_t>> stored;
  std::size_t database_keyframes = 0, kept_apart = 0;
  const SceneRun run = runScene(
      Mode::kIdy, 6.0, RunOptions::twoThreads(), {}, false, {}, [](Config& c) { c.loop.enabled = true; },
      [&](const System& system) {
        ASSERT_NE(system.loopCloser(), nullptr);
        // every keyframe that left the window was taken or skipped as too near the last one
        database_keyframes = system.loopCloser()->database().size() + system.loopCloser()->stats().keyframes_skipped;
        kept_apart = system.loopCloser()->stats().candidates_kept_apart;
        for (const auto& kf : system.loopCloser()->database().keyframes())
          for (const auto& l : kf.landmarks) stored.emplace_back(kf.t_ns, l.id);
      });
  EXPECT_EQ(database_keyframes, run.keyframes_left);
  EXPECT_GT(run.left_not_static.size(), 0u) << "the test needs keyframes that saw non-static landmarks";
  EXPECT_GT(stored.size(), 100u);
  EXPECT_GT(kept_apart, 0u) << "candidates reach the loop closer and stay out of its database";
  for (const auto& s : stored) {
    EXPECT_EQ(run.left_not_static.count(s), 0u) << "landmark " << s.second << " at " << s.first;
    EXPECT_EQ(run.left_static.count(s), 1u) << "landmark " << s.second << " at " << s.first;
  }
  EXPECT_TRUE(run.result.loop_enabled);
  EXPECT_EQ(run.result.loop_trajectory.size(), run.result.trajectory.size());
}

TEST(Faults, TheFaultTimeIsInsideTheSequence) { EXPECT_EQ(kFaultAt, sim::SimOptions{}.t0_ns + 4'000'000'000); }

/// The IMU samples of (kFaultAt, kFaultAt + duration) removed.
std::function<void(std::vector<ImuSample>&)> imuGap(TimeNs duration) {
  return [duration](std::vector<ImuSample>& imu) {
    imu.erase(std::remove_if(imu.begin(), imu.end(),
                             [&](const ImuSample& s) { return s.t_ns > kFaultAt && s.t_ns < kFaultAt + duration; }),
              imu.end());
  };
}

/// The fault-free run's ATE over the whole file (the gap tests' reference).
double faultFreeAte() {
  static const double ate = checkFault(runScene(Mode::kIdy, kFaultSeqS, RunOptions::twoThreads())).ate_whole;
  return ate;
}

TEST(Faults, ImuGapsOfHalfASecondAndTwoSecondsAreCarriedByStereoAloneInOnePiece) {
  for (const TimeNs gap : {TimeNs{500'000'000}, TimeNs{2'000'000'000}}) {
    SCOPED_TRACE(gap);
    const SceneRun run = runScene(Mode::kIdy, kFaultSeqS, RunOptions::twoThreads(), imuGap(gap));
    const FaultCheck c = checkFault(run);
    EXPECT_EQ(c.resets, 0u) << c.why << ": no reset, no new segment (bridge_imu_gaps)";
    EXPECT_GE(run.result.summary.frames_stereo_only, static_cast<std::size_t>(gap / 50'000'000) - 1)
        << "every frame of the gap entered on stereo alone";
    EXPECT_LT(c.worst_excess_m, 0.2) << "one piece: no step beyond the motion";
    EXPECT_LE(c.ate_whole, 2 * faultFreeAte() + 0.01) << "fault-free " << faultFreeAte();
  }
}

TEST(Faults, WithoutBridgingAnImuGapOfHalfASecondEndsTheSegmentAndTheNextGoesOnFromTheLastGoodState) {
  const SceneRun run = runScene(Mode::kIdy, kFaultSeqS, RunOptions::twoThreads(), imuGap(500'000'000), false, {},
                                [](Config& c) { c.estimator.bridge_imu_gaps = false; });
  const FaultCheck c = checkFault(run);
  EXPECT_EQ(c.resets, 1u);
  EXPECT_NE(c.why.find("IMU gap of 0.5"), std::string::npos) << c.why;
  EXPECT_EQ(c.continued_by, "extrapolated") << "a 0.5 s IMU dropout: bridged at constant velocity";
  EXPECT_EQ(run.result.summary.frames_stereo_only, 0u);
  EXPECT_LT(c.worst_excess_m, 0.2) << "one piece: no step beyond the motion";
  EXPECT_LT(c.ate_whole, 0.1);
}

TEST(Faults, BlackImagesDuringAnImuGapEndTheSegmentCleanly) {
  // No stereo tracks while the IMU is silent: nothing carries the window, the segment ends.
  const SceneRun run =
      runScene(Mode::kIdy, kFaultSeqS, RunOptions::twoThreads(), imuGap(500'000'000), false, [](StereoFrame& f) {
        if (f.t_ns > kFaultAt && f.t_ns < kFaultAt + 500'000'000) {
          f.left = cv::Mat::zeros(f.left.size(), CV_8UC1);
          f.right = cv::Mat::zeros(f.right.size(), CV_8UC1);
        }
        return true;
      });
  const FaultCheck c = checkFault(run);
  EXPECT_GE(c.resets, 1u);
  EXPECT_LT(c.worst_excess_m, 0.2);
  EXPECT_LT(c.ate_whole, 0.1);
  for (const auto& s : run.result.trajectory) ASSERT_TRUE(s.state.p_w_b.allFinite());
}

TEST(Faults, OneSecondOfBlackImagesEndsTheSegmentAndTheNextGoesOnWithTheImu) {
  const SceneRun run = runScene(Mode::kIdy, kFaultSeqS, RunOptions::twoThreads(), {}, false, [](StereoFrame& f) {
    if (f.t_ns >= kFaultAt && f.t_ns < kFaultAt + 1'000'000'000) {
      f.left = cv::Mat::zeros(f.left.size(), CV_8UC1);
      f.right = cv::Mat::zeros(f.right.size(), CV_8UC1);
    }
    return true;
  });
  const FaultCheck c = checkFault(run);
  EXPECT_GE(c.resets, 1u);
  EXPECT_EQ(c.continued_by, "imu");
  EXPECT_LT(c.worst_excess_m, 0.2);
  EXPECT_LT(c.ate_whole, 0.1);
}

TEST(Faults, ATwoSecondTimeJumpOnCamerasAndImuIsDetectedAndBridgedByHolding) {
  constexpr TimeNs kJump = 2'000'000'000;
  const SceneRun run = runScene(
      Mode::kIdy, kFaultSeqS, RunOptions::twoThreads(),
      [](std::vector<ImuSample>& imu) {
        for (auto& s : imu)
          if (s.t_ns >= kFaultAt) s.t_ns += kJump;
      },
      false,
      [](StereoFrame& f) {
        if (f.t_ns >= kFaultAt) f.t_ns += kJump;
        return true;
      });
  const FaultCheck c = checkFault(run, kFaultAt, kJump);
  EXPECT_EQ(c.resets, 1u);
  EXPECT_NE(c.why.find("no frame for 2.05"), std::string::npos) << c.why;
  EXPECT_EQ(c.continued_by, "held");
  EXPECT_LT(c.worst_excess_m, 0.2);
  EXPECT_LT(c.ate_whole, 0.1);
}

TEST(Faults, CamerasAndImuSilentForHalfASecondStayInOnePieceWithoutNaN) {
  // The frames after the silence still track the ones before it: stereo carries the window
  // across the IMU gap (no reset), in one piece.
  const SceneRun run = runScene(Mode::kIdy, kFaultSeqS, RunOptions::twoThreads(), imuGap(500'000'000), false,
                                [](StereoFrame& f) { return !(f.t_ns > kFaultAt && f.t_ns < kFaultAt + 500'000'000); });
  const FaultCheck c = checkFault(run);
  EXPECT_EQ(c.resets, 0u) << c.why;
  EXPECT_GE(run.result.summary.frames_stereo_only, 1u);
  EXPECT_LT(c.worst_excess_m, 0.2);
  EXPECT_LE(c.ate_whole, 2 * faultFreeAte() + 0.01) << "fault-free " << faultFreeAte();
  for (const auto& s : run.result.trajectory) ASSERT_TRUE(s.state.p_w_b.allFinite());
}

/// A walked static street rendered once: frames stamped with an image clock td_true behind
/// the IMU's (image stamp + td_true = capture time on the IMU clock).
struct OffsetSequence {
  Config rig;
  std::vector<sim::SceneFrame> frames;
  std::vector<ImuSample> imu;
  std::vector<StampedPose> truth;
  TimeNs td_true_ns = 10'000'000;
};

const OffsetSequence& offsetSequence() {
  static const OffsetSequence seq = [] {
    OffsetSequence s;
    sim::SimOptions o;
    o.family = sim::Family::kValidation;
    o.scene.scene = "city";
    o.scene.level = sim::Level::kNone;
    o.scene.seed = 1;
    o.duration_s = 15.0;
    const sim::Scene scene(o);
    std::vector<GroundTruthState> gt;
    sim::synthesizeImu(scene.trajectory(), o, s.imu, gt);
    for (const auto& g : gt) s.truth.push_back({g.t_ns, g.p_w_b, g.q_w_b});
    for (std::size_t k = 0; k < scene.frameCount(); ++k) s.frames.push_back(scene.renderFrame(k));
    s.rig = scene.rig();
    s.rig.estimator.max_solver_time_s = 1000;
    return s;
  }();
  return seq;
}

struct OffsetRun {
  Result result;
  std::vector<double> td_s;        ///< the offset after each frame
  std::vector<TimeNs> frame_t_ns;  ///< each frame's time (IMU clock) as output
  std::size_t stamp_shift_errors = 0;
  std::optional<backend::ExtrinsicEstimate> extrinsic;  ///< the newest (estimate_extrinsic)
};

OffsetRun runWithOffset(double config_td_s, bool estimate);

/// Feeds the sequence as a reader would (IMU and images merged by their stamps), with the rig's
/// config changed by `edit`.
OffsetRun runOffsetSequence(const std::function<void(Config&)>& edit) {
  const OffsetSequence& seq = offsetSequence();
  Config config = seq.rig;
  // One measurement model for every run: with estimate_td right observations are not judged
  // alone (EstimatorOptions::stereo_outlier_px), so neither are they here with td known.
  config.estimator.stereo_outlier_px = 0.0;
  config.mode = Mode::kBaseline;
  edit(config);
  System system(config);
  struct Recorder final : FrameObserver {
    OffsetRun* run;
    void onFrame(const StereoFrame& input, const FrameOutput& out) override {
      run->td_s.push_back(out.estimate.td_s);
      if (out.estimate.extrinsic) run->extrinsic = out.estimate.extrinsic;
      run->frame_t_ns.push_back(out.t_ns);
      // The output's time is the stamp moved by the offset the frame was stamped with.
      if (out.t_ns != input.t_ns + static_cast<TimeNs>(std::llround(out.features.td_s * 1e9)))
        ++run->stamp_shift_errors;
    }
  } recorder;
  OffsetRun run;
  recorder.run = &run;
  system.addObserver(recorder);
  std::size_t next_imu = 0;
  for (const sim::SceneFrame& f : seq.frames) {
    const TimeNs stamp = f.t_ns - seq.td_true_ns;
    while (next_imu < seq.imu.size() && seq.imu[next_imu].t_ns <= stamp) system.addImu(seq.imu[next_imu++]);
    StereoFrame frame;
    frame.t_ns = stamp;
    frame.index = f.index;
    frame.left = f.cam[0].image;
    frame.right = f.cam[1].image;
    system.addFrame(frame);
  }
  while (next_imu < seq.imu.size()) system.addImu(seq.imu[next_imu++]);
  run.result = system.finish();
  return run;
}

OffsetRun runWithOffset(double config_td_s, bool estimate) {
  return runOffsetSequence([&](Config& c) {
    c.estimator.td_s = config_td_s;
    c.estimator.estimate_td = estimate;
  });
}

double ate(const OffsetRun& run) {
  std::vector<StampedPose> est;
  for (const auto& s : run.result.trajectory) est.push_back(toStampedPose(s));
  return eval::computeAte(offsetSequence().truth, est, eval::AlignMode::kSe3, 1'000'000).stats.rmse;
}

TEST(PipelineTimeOffset, AppliesTdAndEstimatesAnOffsetFortyMillisecondsFromTheConfigsWithTheAccuracyOfTheRightOne) {
  const OffsetRun right = runWithOffset(0.010, false);  // the config knows the offset
  const OffsetRun ignored = runWithOffset(0.0, false);  // the offset unknown, not estimated
  // Estimated from a config 40 ms off: the initialization's search over 2 s of poses finds it.
  const OffsetRun estimated = runWithOffset(-0.030, true);
  // The last frame's time on the IMU clock may lie past the last IMU sample: left out, counted.
  ASSERT_EQ(estimated.td_s.size() + estimated.result.summary.frames_beyond_imu, offsetSequence().frames.size());
  EXPECT_LE(estimated.result.summary.frames_beyond_imu, 1u);
  EXPECT_EQ(right.stamp_shift_errors + ignored.stamp_shift_errors + estimated.stamp_shift_errors, 0u);
  for (double td : right.td_s) EXPECT_EQ(td, 0.010);
  // With td 10 ms each frame needs the IMU sample after its stamp: fed in stamp order, frames
  // wait for the next call, and every frame reaches the observers in order, on the IMU clock.
  ASSERT_EQ(right.frame_t_ns.size(), offsetSequence().frames.size());
  EXPECT_EQ(right.result.summary.frames_beyond_imu, 0u) << "the IMU runs to the last capture time";
  for (std::size_t k = 0; k < right.frame_t_ns.size(); ++k)
    EXPECT_EQ(right.frame_t_ns[k], offsetSequence().frames[k].t_ns);
  // The estimate over the last 5 s of 15.
  double sum = 0;
  std::size_t n = 0;
  for (std::size_t k = 0; k < estimated.td_s.size(); ++k)
    if (k >= estimated.td_s.size() - 100) sum += estimated.td_s[k], ++n;
  const double mean_td = sum / static_cast<double>(n);
  EXPECT_NEAR(mean_td, 0.010, 0.0005);
  // The bound is 1.5x; measured 1.21x (its poses start at 2.5 s, after the
  // search's 2 s of poses, those with td known at 0.5 s).
  EXPECT_LE(ate(estimated), 1.3 * ate(right));
  EXPECT_GT(ate(ignored), 1.5 * ate(right)) << "a 10 ms offset left in the data costs accuracy";
  EXPECT_TRUE(estimated.result.summary.resets.empty());

  std::printf(
      "10 ms offset: ATE %.4f m with td known, %.4f m ignored, %.4f m estimated from -30 ms (mean of the last 5 s: "
      "%.3f ms)\n",
      ate(right), ate(ignored), ate(estimated), 1e3 * mean_td);
}

/// The rig moved against the IMU: both cameras' mounts turned by `deg` about (1,−1,1) and shifted
/// `cm` along (1,1,−1) (as `idyvins perturb --fault extrinsic`), the stereo pair unchanged.
void moveRig(Config& c, double deg, double cm) {
  const Eigen::Isometry3d error = Eigen::Translation3d(0.01 * cm * Eigen::Vector3d(1, 1, -1).normalized()) *
                                  Eigen::AngleAxisd(deg * M_PI / 180, Eigen::Vector3d(1, -1, 1).normalized());
  for (Eigen::Isometry3d& T : c.T_b_c) T = error * T;
}

TEST(PipelineExtrinsic, AMountOffByTwoDegreesAndTwoCentimetresIsRefinedOnlineToTheTruth) {
  const auto withTd = [](Config& c) { c.estimator.td_s = 0.010; };
  const OffsetRun right = runOffsetSequence(withTd);
  const OffsetRun wrong = runOffsetSequence([&](Config& c) {
    withTd(c);
    moveRig(c, 2.0, 2.0);
  });
  const OffsetRun refined = runOffsetSequence([&](Config& c) {
    withTd(c);
    moveRig(c, 2.0, 2.0);
    c.estimator.estimate_extrinsic = 1;
  });
  EXPECT_FALSE(right.extrinsic) << "no estimate without estimate_extrinsic";
  ASSERT_TRUE(refined.extrinsic);
  EXPECT_TRUE(refined.extrinsic->open);
  const Eigen::Isometry3d& truth = offsetSequence().rig.T_b_c[0];
  const double rot_err_deg = Eigen::Quaterniond(truth.linear()).angularDistance(refined.extrinsic->q_b_c0) * 180 / M_PI;
  const double t_err_m = (truth.translation() - refined.extrinsic->t_b_c0).norm();
  EXPECT_LT(rot_err_deg, 0.3);
  EXPECT_LT(t_err_m, 0.015);
  EXPECT_GT(refined.extrinsic->sigma_rot_deg, 0.0);
  EXPECT_GT(ate(wrong), 1.5 * ate(right)) << "the moved rig costs accuracy when not refined";
  EXPECT_LE(ate(refined), 1.3 * ate(right));
  EXPECT_TRUE(refined.result.summary.resets.empty());
  std::printf("rig off 2 deg, 2 cm: ATE %.4f m exact, %.4f m as written, %.4f m refined (%.3f deg, %.2f cm off)\n",
              ate(right), ate(wrong), ate(refined), rot_err_deg, 100 * t_err_m);
}

TEST(Modes, EveryModeHasARowAndTheRowsAreThePapersTableI) {
  const std::string names = modeNames();
  std::size_t start = 0, rows = 0;
  while (start <= names.size()) {
    const std::size_t end = std::min(names.find('|', start), names.size());
    Mode mode;
    ASSERT_TRUE(parseMode(names.substr(start, end - start), mode));
    EXPECT_NO_THROW(traitsOf(mode));
    ++rows;
    start = end + 1;
  }
  EXPECT_EQ(rows, 6u);
  // idy = preprocessing (elimination) + robust BA (weights, post-processing); the ablations drop one each.
  EXPECT_TRUE(traitsOf(Mode::kIdy).eliminate && traitsOf(Mode::kIdy).weights_and_post);
  EXPECT_TRUE(traitsOf(Mode::kIdyPre).eliminate && !traitsOf(Mode::kIdyPre).weights_and_post);
  EXPECT_TRUE(!traitsOf(Mode::kIdyBa).eliminate && traitsOf(Mode::kIdyBa).weights_and_post);
  EXPECT_EQ(traitsOf(Mode::kBaseline).filter, FilterKind::kNone);
  EXPECT_TRUE(traitsOf(Mode::kSeg).needs_masks);
}

TEST(Modes, FollowEliminatedKeyEndsEliminatedTracksOnlyWhereTheModeFollowsThem) {
  Config c = sim::rigConfig(sim::SimOptions{});
  for (Mode mode : {Mode::kIdy, Mode::kIdyPre, Mode::kIdyBa, Mode::kBaseline}) {
    c.mode = mode;
    const bool follows = traitsOf(mode).follow_eliminated;
    c.tracker.follow_eliminated = true;
    EXPECT_EQ(optionsFor(c).tracker.follow_eliminated, follows) << toString(mode);
    c.tracker.follow_eliminated = false;
    const ModeOptions off = optionsFor(c);
    EXPECT_FALSE(off.tracker.follow_eliminated) << toString(mode);
    // The lost-corner test does not depend on it.
    EXPECT_EQ(off.tracker.lost_track_test, follows && c.tracker.lost_track_test) << toString(mode);
  }
}

TEST(PipelineSystem, RejectsConfigsAndFramesItCannotRun) {
  sim::SimOptions o;
  Config config = sim::rigConfig(o);
  config.num_cam = 1;
  EXPECT_THROW(System{config}, InputError);
  config = sim::rigConfig(o);
  config.mode = Mode::kSeg;
  System seg(config);
  StereoFrame frame;
  frame.t_ns = 1;
  frame.left = cv::Mat(config.image_height, config.image_width, CV_8UC1, cv::Scalar(0));
  frame.right = frame.left.clone();
  EXPECT_THROW(seg.addFrame(frame), InputError) << "seg mode without a mask";
  EXPECT_THROW((System{sim::rigConfig(o), RunOptions{true, 0}}), std::invalid_argument)
      << "a pipelined run has a feedback delay of one frame";
  config = sim::rigConfig(o);  // imu: 0 has no offset to estimate
  config.use_imu = config.estimator.use_imu = false;
  config.mode = Mode::kIdy;
  EXPECT_NO_THROW(System{config}) << "idy without the IMU: the constant-velocity prior";
  config.mode = Mode::kBaseline;
  config.estimator.estimate_td = true;
  EXPECT_THROW(System{config}, InputError) << "no offset to estimate without an IMU";
  config.estimator.estimate_td = false;
  EXPECT_NO_THROW(System{config});
}

TEST(PipelineSystem, ARigWhoseCam0IsTheRightCameraRunsAsTheSameRigNamedTheOtherWay) {
  // VINS-Fusion's vi_car names its right camera cam0. The same rig with cam0 and cam1 swapped
  // in the config and in the frames gives the very run of the rig as named left to right, and
  // the refined mounts come back under the config's names.
  auto refine = [](Config& c) { c.estimator.estimate_extrinsic = 1; };
  const SceneRun named = runScene(Mode::kIdy, 3.0, {}, {}, false, {}, refine);
  const SceneRun swapped = runScene(
      Mode::kIdy, 3.0, {}, {}, false,
      [](StereoFrame& f) {
        std::swap(f.left, f.right);
        f.left_mask = cv::Mat();  // a dataset's cam0 masks would be the right image's
        return true;
      },
      [&](Config& c) {
        refine(c);
        std::swap(c.cams[0], c.cams[1]);
        std::swap(c.T_b_c[0], c.T_b_c[1]);
        c.cam0_right = true;  // what loadConfig derives from such mounts (test_vins_rigs)
      });
  ASSERT_GT(named.result.trajectory.size(), 40u);
  EXPECT_TRUE(sameTrajectory(named.result, swapped.result));
  EXPECT_TRUE(sameMap(named.result.static_map, swapped.result.static_map));
  EXPECT_TRUE(sameMap(named.result.dynamic_map, swapped.result.dynamic_map));
  ASSERT_TRUE(named.result.summary.extrinsic && swapped.result.summary.extrinsic);
  const ExtrinsicSummary &a = *named.result.summary.extrinsic, &b = *swapped.result.summary.extrinsic;
  EXPECT_TRUE(a.T_b_c[0].isApprox(b.T_b_c[1], 1e-12));
  EXPECT_TRUE(a.T_b_c[1].isApprox(b.T_b_c[0], 1e-12));
  EXPECT_TRUE(b.estimate.t_b_c0.isApprox(b.T_b_c[0].translation(), 1e-12)) << "t_b_c0 is the config's cam0";
  EXPECT_LT(ate(swapped), 0.05);
  Config seg = sim::rigConfig(sim::SimOptions{});
  seg.cam0_right = true;
  seg.mode = Mode::kSeg;
  EXPECT_THROW(System{seg}, InputError) << "seg: a dataset's masks are cam0's, the right camera's";
}

TEST(PipelineSystem, StereoAloneWithoutTheImuRunsAStreetInOnePiece) {
  // imu: 0 (VINS-Fusion's stereo-only configs): every frame without an IMU factor, the first
  // frame the world; the IMU samples the data has are not used.
  const SceneRun run = runScene(Mode::kBaseline, 6.0, RunOptions::twoThreads(), {}, false, {},
                                [](Config& c) { c.use_imu = c.estimator.use_imu = false; });
  EXPECT_EQ(run.result.summary.resets.size(), 0u);
  EXPECT_EQ(run.result.trajectory.size(), run.result.summary.frames) << "a pose from the first frame on";
  const FaultCheck c = checkFault(run);
  EXPECT_LT(c.ate_whole, 0.05);
  EXPECT_LT(c.worst_excess_m, 0.05);
}

TEST(Outputs, FilesAreWrittenUnderATemporaryNameAndRenamedWhenComplete) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::path(::testing::TempDir()) / "idyvins_outputs";
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ofstream(dir / "trajectory.tum") << "old run\n";
  Result r;
  for (int k = 0; k < 3; ++k) {
    StampedState s;
    s.t_ns = 1'000'000'000 + k * 50'000'000;
    s.state.p_w_b = Eigen::Vector3d(k, 0, 0);
    r.trajectory.push_back(s);
  }
  writeResultFiles(dir.string(), r);
  auto text = [&](const char* name) {
    std::ifstream in(dir / name);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  };
  const std::string tum = text("trajectory.tum");  // a header line and the new run's three poses
  EXPECT_EQ(tum.find("old run"), std::string::npos) << tum;
  EXPECT_EQ(std::count(tum.begin(), tum.end(), '\n'), 4) << tum;
  for (const auto& e : fs::directory_iterator(dir)) EXPECT_NE(e.path().extension(), ".part") << e.path();
  // A write that fails (here: its temporary name is taken by a folder) throws and leaves
  // the file under the final name as it was, never cut.
  std::ofstream(dir / "trajectory.tum") << "old run\n";
  fs::create_directories(dir / "trajectory.tum.part" / "x");
  EXPECT_THROW(writeResultFiles(dir.string(), r), InputError);
  EXPECT_EQ(text("trajectory.tum"), "old run\n");
  fs::remove_all(dir);
}

TEST(Outputs, AteGivesTheScaleErrorOfAPathTooLongAndTheErrorLeftWithoutIt) {
  std::vector<StampedPose> gt;
  Result r;
  for (int k = 0; k < 200; ++k) {
    StampedPose g;
    g.t_ns = 1'000'000'000 + static_cast<TimeNs>(k) * 50'000'000;
    g.p_w_b = Eigen::Vector3d(0.1 * k, 2.0 * std::sin(0.05 * k), 0.3 * std::cos(0.03 * k));
    gt.push_back(g);
    StampedState s;
    s.t_ns = g.t_ns;
    s.state.p_w_b = 1.01 * g.p_w_b + Eigen::Vector3d(5, -2, 1);  // 1 % too long, elsewhere
    r.trajectory.push_back(s);
  }
  nlohmann::json summary;
  addAte(summary, gt, r);
  ASSERT_TRUE(summary.contains("ate_sim3_rmse_m") && summary.contains("scale_error")) << summary.dump();
  EXPECT_NEAR(summary["scale_error"].get<double>(), 0.01, 1e-9);
  EXPECT_LT(summary["ate_sim3_rmse_m"].get<double>(), 1e-9);
  EXPECT_GT(summary["ate_rmse_m"].get<double>(), 0.02);  // SE3 cannot absorb the scale
  // A path 1 % too short: −1 % (1/s − 1 with p_ref ≈ s R p_est + t).
  for (auto& s : r.trajectory) s.state.p_w_b *= 0.99 / 1.01;
  addAte(summary, gt, r);
  EXPECT_NEAR(summary["scale_error"].get<double>(), -0.01, 1e-9);
}

TEST(StatsRecorder, WritesOneLinePerFrameAndAParseableDocument) {
  for (const int n : {0, 1, 3}) {
    std::ostringstream os;
    StatsRecorder stats(os);
    for (int k = 0; k < n; ++k) {
      FrameOutput out;
      out.estimate.t_ns = 100 + k;
      stats.onFrame(StereoFrame{}, out);
    }
    stats.finish({{"frames", n}, {"nested", {{"a", 1}}}});
    const nlohmann::json doc = nlohmann::json::parse(os.str());
    ASSERT_EQ(doc["frames"].size(), static_cast<std::size_t>(n)) << os.str();
    for (int k = 0; k < n; ++k) EXPECT_EQ(doc["frames"][k]["t_ns"], 100 + k);
    EXPECT_EQ(doc["summary"]["nested"]["a"], 1);
    EXPECT_EQ(stats.frames(), static_cast<std::size_t>(n));
    // One line per frame, plus the document's own: 3 around the array, 5 of the summary, 2 closing.
    const std::string text = os.str();
    EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), n ? n + 10 : 9) << text;
  }
}

cv::Mat grayOf(int value) { return cv::Mat(4, 4, CV_8UC1, cv::Scalar(value)); }

TEST(StereoSync, PairsImagesByStampInWhicheverOrderTheyArrive) {
  StereoSync sync(1'000'000);
  EXPECT_TRUE(sync.add(1, 100'000'000, grayOf(11)));  // right first
  EXPECT_FALSE(sync.next());
  EXPECT_TRUE(sync.add(0, 100'000'400, grayOf(10)));  // 0.4 ms apart: a pair
  EXPECT_TRUE(sync.add(0, 150'000'000, grayOf(20)));
  const auto p = sync.next();
  ASSERT_TRUE(p);
  EXPECT_EQ(p->t_ns, 100'000'400) << "the pair has the left image's stamp";
  EXPECT_EQ(p->index, 0u);
  EXPECT_EQ(p->left.at<std::uint8_t>(0, 0), 10);
  EXPECT_EQ(p->right.at<std::uint8_t>(0, 0), 11);
  EXPECT_FALSE(sync.next()) << "the second left image waits for its partner";
  EXPECT_EQ(sync.waiting(0), 1u);
  EXPECT_TRUE(sync.add(1, 150'000'000, grayOf(21)));
  const auto q = sync.next();
  ASSERT_TRUE(q);
  EXPECT_EQ(q->index, 1u);
  EXPECT_EQ(q->right.at<std::uint8_t>(0, 0), 21);
  EXPECT_EQ(sync.unpaired(0) + sync.unpaired(1), 0u);
}

TEST(StereoSync, DropsAndCountsImagesWhosePartnerCannotComeAndImagesOutOfOrder) {
  StereoSync sync(1'000'000);
  sync.add(0, 100'000'000, grayOf(1));  // its right image is lost
  sync.add(0, 150'000'000, grayOf(2));
  sync.add(1, 150'000'000, grayOf(3));
  const auto p = sync.next();
  ASSERT_TRUE(p);
  EXPECT_EQ(p->t_ns, 150'000'000);
  EXPECT_EQ(sync.unpaired(0), 1u);
  sync.add(1, 200'000'000, grayOf(4));  // its left image is lost
  sync.add(1, 250'000'000, grayOf(5));
  sync.add(0, 250'000'000, grayOf(6));
  ASSERT_TRUE(sync.next());
  EXPECT_EQ(sync.unpaired(1), 1u);
  sync.add(0, 301'500'000, grayOf(7));  // 1.5 ms apart: beyond the tolerance, not a pair
  sync.add(1, 300'000'000, grayOf(8));
  sync.add(1, 350'000'000, grayOf(9));
  EXPECT_FALSE(sync.next());
  EXPECT_EQ(sync.unpaired(0), 2u);
  EXPECT_EQ(sync.unpaired(1), 2u);
  EXPECT_FALSE(sync.add(1, 350'000'000, grayOf(10))) << "a stamp not after the previous one of its camera";
  EXPECT_FALSE(sync.add(0, 250'000'000, grayOf(10)));
  EXPECT_EQ(sync.outOfOrder(0), 1u);
  EXPECT_EQ(sync.outOfOrder(1), 1u);
  EXPECT_THROW(sync.add(2, 400'000'000, grayOf(0)), std::invalid_argument);
}

TEST(FrontEndDropout, WithheldTracksAreAFixedShareOfTheIds) {
  std::size_t none = 0, all = 0, some = 0, both = 0;
  for (std::uint64_t id = 0; id < 100000; ++id) {
    none += withheldTrack(id, 1, 0);
    all += withheldTrack(id, 1, 1000);
    const bool a = withheldTrack(id, 1, 20), b = withheldTrack(id, 2, 20);
    some += a;
    both += a && b;
  }
  EXPECT_EQ(none, 0u);
  EXPECT_EQ(all, 100000u);
  EXPECT_NEAR(static_cast<double>(some) / 100000, 0.020, 0.003);
  EXPECT_LT(both, some / 5);  // another seed withholds other tracks (independent: 2 % of them)
  std::size_t nested = 0;     // a larger share withholds the smaller share's tracks and more
  for (std::uint64_t id = 0; id < 10000; ++id)
    if (withheldTrack(id, 4, 20)) nested += withheldTrack(id, 4, 300) ? 1 : 1000000;
  EXPECT_GT(nested, 100u);
  EXPECT_LT(nested, 1000000u);
}

TEST(FrontEndDropout, OnlyTheWithheldTracksLeaveTheOutput) {
  // The tracker follows the withheld tracks (no new corner in their place): every other
  // feature comes out exactly as without the probe, frame after frame.
  sim::SimOptions o;
  o.scene.scene = "city";
  o.scene.level = sim::Level::kNone;
  o.scene.seed = 1;
  o.duration_s = 1.0;
  const sim::Scene scene(o);
  Config plain_config = scene.rig();
  plain_config.mode = Mode::kBaseline;
  Config probe_config = plain_config;
  probe_config.tracker.track_dropout_permille = 200;
  probe_config.tracker.track_dropout_seed = 5;
  FrontEnd plain(plain_config), probe(probe_config);
  std::size_t withheld = 0, kept = 0;
  for (std::size_t k = 0; k < 12; ++k) {
    const sim::SceneFrame f = scene.renderFrame(k);
    StereoFrame frame;
    frame.t_ns = f.t_ns;
    frame.index = f.index;
    frame.left = f.cam[0].image;
    frame.right = f.cam[1].image;
    const frontend::FeatureFrame a = plain.track(frame, {}), b = probe.track(frame, {});
    std::vector<frontend::Feature> expected;
    for (const auto& feature : a.features) {
      if (withheldTrack(feature.id, 5, 200)) {
        ++withheld;
      } else {
        expected.push_back(feature);
      }
    }
    ASSERT_EQ(b.features.size(), expected.size()) << "frame " << k;
    for (std::size_t i = 0; i < expected.size(); ++i) {
      EXPECT_EQ(b.features[i].id, expected[i].id);
      EXPECT_EQ(b.features[i].uv, expected[i].uv);
      EXPECT_EQ(b.features[i].uv_right, expected[i].uv_right);
    }
    kept += expected.size();
  }
  EXPECT_GT(kept, 500u);
  EXPECT_NEAR(static_cast<double>(withheld) / static_cast<double>(withheld + kept), 0.2, 0.06);
}

}  // namespace
}  // namespace idyvins::pipeline
