#include <gtest/gtest.h>

#include <random>

#include "core/so3.h"
#include "eval/dynamic_metrics.h"
#include "eval/trajectory_metrics.h"

namespace idyvins::eval {
namespace {

using Eigen::Vector3d;

StampedPose at(TimeNs t, const Vector3d& p = Vector3d::Zero()) {
  StampedPose s;
  s.t_ns = t;
  s.p_w_b = p;
  return s;
}

std::vector<StampedPose> randomWalk(int n, TimeNs dt_ns, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  std::vector<StampedPose> out;
  StampedPose p;
  p.t_ns = 1'000'000'000;
  for (int i = 0; i < n; ++i) {
    p.p_w_b += Vector3d(1.0 + 0.3 * g(rng), 0.5 * g(rng), 0.2 * g(rng)) * 0.1;
    p.q_w_b = (p.q_w_b * expQuat(Vector3d(g(rng), g(rng), g(rng)) * 0.05)).normalized();
    out.push_back(p);
    p.t_ns += dt_ns;
  }
  return out;
}

std::vector<StampedPose> transformed(const std::vector<StampedPose>& in, const Similarity& T) {
  std::vector<StampedPose> out = in;
  for (auto& p : out) {
    p.p_w_b = T.apply(p.p_w_b);
    p.q_w_b = Eigen::Quaterniond(T.R * p.q_w_b.toRotationMatrix());
  }
  return out;
}

TEST(Alignment, RecoversKnownSe3AndSim3Exactly) {
  const auto ref = randomWalk(200, 50'000'000, 1);
  for (bool with_scale : {false, true}) {
    Similarity T;
    T.R = expQuat(Vector3d(0.3, -1.2, 2.0)).toRotationMatrix();
    T.t = Vector3d(4.0, -2.0, 7.5);
    T.s = with_scale ? 0.37 : 1.0;
    // est = T⁻¹(ref): aligning est onto ref must give T back.
    Similarity inv;
    inv.R = T.R.transpose();
    inv.s = 1.0 / T.s;
    inv.t = -inv.s * (inv.R * T.t);
    const auto est = transformed(ref, inv);
    const AteResult r = computeAte(ref, est, with_scale ? AlignMode::kSim3 : AlignMode::kSe3, 1000);
    EXPECT_LT((r.alignment.R - T.R).norm(), 1e-9);
    EXPECT_LT((r.alignment.t - T.t).norm(), 1e-9);
    EXPECT_NEAR(r.alignment.s, T.s, 1e-9);
    EXPECT_LT(r.stats.max, 1e-9);
    EXPECT_EQ(r.stats.n, 200u);
  }
}

TEST(Alignment, PositionYawKeepsRollAndPitch) {
  const auto ref = randomWalk(100, 50'000'000, 2);
  Similarity yaw_only;
  yaw_only.R = Eigen::AngleAxisd(-2.1, Vector3d::UnitZ()).toRotationMatrix();
  yaw_only.t = Vector3d(1, 2, 3);
  const auto est = transformed(ref, yaw_only);
  const AteResult r = computeAte(ref, est, AlignMode::kPosYaw, 1000);
  EXPECT_LT(r.stats.max, 1e-9);
  EXPECT_NEAR(r.alignment.R(2, 2), 1.0, 1e-12);  // a rotation about z only
  // With a roll/pitch difference the 4-DoF alignment must not absorb it.
  Similarity tilted = yaw_only;
  tilted.R = Eigen::AngleAxisd(0.2, Vector3d::UnitX()).toRotationMatrix() * yaw_only.R;
  const AteResult r2 = computeAte(ref, transformed(ref, tilted), AlignMode::kPosYaw, 1000);
  EXPECT_NEAR(r2.alignment.R(2, 2), 1.0, 1e-12);
  EXPECT_NEAR(r2.alignment.R.col(2).z(), 1.0, 1e-12);
  EXPECT_GT(r2.stats.rmse, 0.01);
  const AteResult r3 = computeAte(ref, transformed(ref, tilted), AlignMode::kSe3, 1000);
  EXPECT_LT(r3.stats.rmse, 1e-9);  // SE3 does absorb it
}

TEST(Ate, HandComputedCase) {
  std::vector<StampedPose> ref(3), est(3);
  const double err[3] = {0.1, 0.2, 0.2};
  for (int i = 0; i < 3; ++i) {
    ref[i].t_ns = est[i].t_ns = 1000 * (i + 1);
    ref[i].p_w_b = Vector3d(i, 0, 0);
    est[i].p_w_b = Vector3d(i, err[i], 0);
  }
  const AteResult r = computeAte(ref, est, AlignMode::kNone, 0);
  EXPECT_NEAR(r.stats.rmse, std::sqrt(0.09 / 3.0), 1e-15);
  EXPECT_NEAR(r.stats.mean, 0.5 / 3.0, 1e-15);
  EXPECT_NEAR(r.stats.median, 0.2, 1e-15);
  EXPECT_NEAR(r.stats.std, std::sqrt(((0.1 - 0.5 / 3) * (0.1 - 0.5 / 3) + 2 * (0.2 - 0.5 / 3) * (0.2 - 0.5 / 3)) / 3),
              1e-15);
  EXPECT_NEAR(r.stats.min, 0.1, 1e-15);
  EXPECT_NEAR(r.stats.max, 0.2, 1e-15);
  EXPECT_NEAR(r.stats.sse, 0.09, 1e-15);
  EXPECT_NEAR(computeStats({1, 2, 3, 4}).median, 2.5, 1e-15);  // even count: mean of the middle two
}

TEST(Association, UnequalRatesAndGaps) {
  // Reference at 100 Hz; estimate at 20 Hz, 3 ms late, with a 1 s gap.
  std::vector<StampedPose> ref, est;
  for (int i = 0; i < 500; ++i) ref.push_back(at(i * 10'000'000LL, Vector3d(i, 0, 0)));
  for (int i = 0; i < 100; ++i) {
    if (i >= 40 && i < 60) continue;  // gap
    est.push_back(at(i * 50'000'000LL + 3'000'000, Vector3d(i, 0, 0)));
  }
  const auto pairs = associate(ref, est, 10'000'000);
  ASSERT_EQ(pairs.size(), est.size());  // every estimate finds a reference within 10 ms
  for (const auto& [i, j] : pairs) EXPECT_EQ(ref[i].t_ns, est[j].t_ns - 3'000'000);
  // A tighter threshold drops them all; the shorter trajectory drives the loop.
  EXPECT_TRUE(associate(ref, est, 2'000'000).empty());
  const auto swapped = associate(est, ref, 10'000'000);  // estimate longer now: reference drives
  EXPECT_EQ(swapped.size(), est.size());
  // Ties go to the earlier stamp, as numpy's argmin does.
  const std::vector<StampedPose> a = {at(100), at(200)};
  const std::vector<StampedPose> b = {at(150)};
  const auto tie = associate(a, b, 100);
  ASSERT_EQ(tie.size(), 1u);
  EXPECT_EQ(tie[0].first, 0u);
}

TEST(Rpe, HandComputedScaleDrift) {
  // Reference moves 1 m per pose along x, the estimate 1.1 m: every 1 m pair has error 0.1.
  std::vector<StampedPose> ref, est;
  for (int i = 0; i < 11; ++i) {
    ref.push_back(at(i * 1000LL, Vector3d(i, 0, 0)));
    est.push_back(at(i * 1000LL, Vector3d(1.1 * i, 0, 0)));
  }
  const ErrorStats s = computeRpe(ref, est, 1.0);
  EXPECT_EQ(s.n, 9u);  // ids 1..10 (the first pose is never an id), 9 consecutive pairs
  EXPECT_NEAR(s.rmse, 0.1, 1e-12);
  const ErrorStats s2 = computeRpe(ref, est, 2.0);  // ids every 2 poses (2.2 m >= 2): 2,4,..,10
  EXPECT_EQ(s2.n, 4u);
  EXPECT_NEAR(s2.mean, 0.2, 1e-12);
}

TEST(DynamicClassification, HandCountedCase) {
  // Track 1: on a vehicle, 3 observations, eliminated at the third -> all 3 flagged.
  // Track 2: on a vehicle, 2 observations, confirmed dynamic -> flagged.
  // Track 3: on a vehicle, seen once, never judged -> missed (only in the strict recall).
  // Track 4: static, 4 observations, confirmed dynamic by mistake -> 4 false positives.
  // Track 5: static background, 5 observations, the last one on a vehicle's edge; in the static map.
  // Track 6: mostly on a vehicle (2 of 3), never flagged; in the static map.
  std::vector<MaskedObservation> obs = {{1, true, false},  {1, true, false},  {1, true, true},   {2, true, false},
                                        {2, true, false},  {3, true, false},  {4, false, false}, {4, false, false},
                                        {4, false, false}, {4, false, false}, {6, true, false},  {6, true, false},
                                        {6, false, false}};
  for (int k = 0; k < 4; ++k) obs.push_back({5, false, false});
  obs.push_back({5, true, false});
  const DynamicClassification c = classifyDynamic(obs, {2, 4}, {5, 6});
  EXPECT_EQ(c.observations_on_moving, 9u);
  EXPECT_EQ(c.observations_static, 9u);
  EXPECT_EQ(c.true_positives, 5u);
  EXPECT_EQ(c.false_positives, 4u);
  EXPECT_DOUBLE_EQ(c.recall, 5.0 / 9.0);
  EXPECT_DOUBLE_EQ(c.static_flagged, 4.0 / 9.0);
  EXPECT_EQ(c.observations_on_moving_tracked, 8u);
  EXPECT_DOUBLE_EQ(c.recall_tracked, 5.0 / 8.0);
  EXPECT_DOUBLE_EQ(c.precision, 5.0 / 9.0);
  EXPECT_EQ(c.static_map_points, 2u);
  EXPECT_EQ(c.static_map_on_moving, 1u);       // track 6 only
  EXPECT_EQ(c.static_map_ever_on_moving, 2u);  // tracks 5 and 6
  EXPECT_DOUBLE_EQ(c.static_map_fraction_on_moving, 0.5);
}

}  // namespace
}  // namespace idyvins::eval
