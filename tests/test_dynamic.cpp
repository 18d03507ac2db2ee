// DESIGN §4.1-4.4: motion prior, minimum projection error, elimination, marking.

#include <gtest/gtest.h>

#include <functional>
#include <numeric>
#include <random>

#include "core/so3.h"
#include "dynamic/dynamic.h"

namespace idyvins::dynamic {
namespace {

using Eigen::Matrix2d;
using Eigen::Matrix3d;
using Eigen::Vector2d;
using Eigen::Vector3d;

constexpr double kF = 380.0;

struct Motion {
  Matrix3d R;  ///< R_prev_cur
  Vector3d t;  ///< t_prev_cur: p_prev = R p_cur + t
};

Motion randomMotion(std::mt19937& rng) {
  std::normal_distribution<double> g(0.0, 1.0);
  return {expQuat(Vector3d(g(rng), g(rng), g(rng)) * 0.03).toRotationMatrix(),
          Vector3d(0.02 * g(rng), 0.02 * g(rng), 0.1 + 0.02 * g(rng))};
}

Vector2d project(const Vector3d& p) { return p.head<2>() / p.z(); }

/// The simulator's left camera (752x480, f = 380 px, no distortion).
std::unique_ptr<camera::CameraModel> pinholeCamera() {
  camera::CameraParams cp;
  cp.fx = cp.fy = kF;
  cp.cx = 376;
  cp.cy = 240;
  cp.width = 752;
  cp.height = 480;
  return camera::makeCamera(cp);
}

TEST(MinProjectionError, StaticPointsGiveZero) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int i = 0; i < 1000; ++i) {
    const Motion m = randomMotion(rng);
    const Vector3d p_prev(3 * u(rng), 2 * u(rng), 5 + 10 * (u(rng) + 1));
    const Vector3d p_cur = m.R.transpose() * (p_prev - m.t);
    EXPECT_LT(epipolarErrorPx2(project(p_prev), project(p_cur), m.R, m.t, kF, kF), 0.1);
    EXPECT_LT(epipolarErrorPx2(project(p_prev), project(p_cur), m.R, m.t, kF, kF), 1e-12);
  }
}

TEST(MinProjectionError, MovingPointGivesItsSquaredDistanceToTheEpipolarLine) {
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int i = 0; i < 200; ++i) {
    const Motion m = randomMotion(rng);
    const Vector3d p_prev(3 * u(rng), 2 * u(rng), 5 + 10 * (u(rng) + 1));
    const Vector2d x0 = project(p_prev);
    // The epipolar line in the current image (pixels), from two depths along x0's ray.
    const Vector2d a = kF * project(m.R.transpose() * (Vector3d(x0.x(), x0.y(), 1) * 2.0 - m.t));
    const Vector2d b = kF * project(m.R.transpose() * (Vector3d(x0.x(), x0.y(), 1) * 40.0 - m.t));
    // The object moved: its current pixel is off the line by a known distance.
    const Vector2d dir = (b - a).normalized(), normal(-dir.y(), dir.x());
    const double dist_px = 0.5 + 5.0 * (u(rng) + 1);
    const Vector2d p1 = kF * project(m.R.transpose() * (p_prev - m.t)) + normal * dist_px + dir * 3.0 * u(rng);
    const double d = epipolarErrorPx2(x0, p1 / kF, m.R, m.t, kF, kF);
    EXPECT_NEAR(d, dist_px * dist_px, 1e-6 * dist_px * dist_px + 1e-9);
  }
}

TEST(MotionPrior, ExactConjugationWithTheExtrinsic) {
  imu::RelativeMotion body;
  body.q_bi_bj = expQuat(Vector3d(0.02, -0.05, 0.1));
  body.p_bi_bj = Vector3d(0.1, 0.02, -0.01);
  body.cov_p = Matrix3d::Identity() * 1e-6;
  Eigen::Isometry3d T_b_c = Eigen::Isometry3d::Identity();
  T_b_c.linear() << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  T_b_c.translation() = Vector3d(0.05, 0.055, 0.0);
  const frontend::MotionPrior p = cameraMotionPrior(body, T_b_c);
  Eigen::Isometry3d T_b = Eigen::Isometry3d::Identity();
  T_b.linear() = body.q_bi_bj.toRotationMatrix();
  T_b.translation() = body.p_bi_bj;
  const Eigen::Isometry3d T_c = T_b_c.inverse() * T_b * T_b_c;
  EXPECT_LT((p.q_prev_cur.toRotationMatrix() - T_c.linear()).norm(), 1e-12);
  EXPECT_LT((p.t_prev_cur - T_c.translation()).norm(), 1e-12);
  // Σ = (1 + σ_P/‖t‖)².
  const double s = std::sqrt(3e-6) / T_c.translation().norm();
  EXPECT_NEAR(credibility(p), (1 + s) * (1 + s), 1e-12);
}

TEST(ConstantVelocityMotion, ExtrapolatesTheNewestTwistAndGrowsItsUncertaintyWithTheInterval) {
  // A body turning at 0.4 rad/s about its z while moving 2 m/s along its x: over 50 ms the
  // relative motion is the same whichever 50 ms it is.
  const auto pose = [](double t) {
    const double yaw = 0.4 * t;
    return Eigen::Translation3d(Vector3d(2.0 * t, 0.1 * t, 0)) * Eigen::AngleAxisd(yaw, Vector3d::UnitZ());
  };
  const TimeNs a = 1'000'000'000, b = 1'050'000'000;
  const Eigen::Isometry3d Ta(pose(1.0)), Tb(pose(1.05));
  const imu::RelativeMotion m = constantVelocityMotion(Ta, a, Tb, b, b, b + 50'000'000, 2.0);
  const Eigen::Isometry3d rel = Ta.inverse() * Tb;
  EXPECT_LT(m.q_bi_bj.angularDistance(Eigen::Quaterniond(rel.linear())), 1e-12);
  EXPECT_LT((m.p_bi_bj - rel.translation()).norm(), 1e-12);
  EXPECT_NEAR(std::sqrt(m.cov_p(0, 0)), 0.5 * 2.0 * 0.05 * 0.05, 1e-15);
  // Twice the interval: twice the rotation angle and the translation, four times the σ.
  const imu::RelativeMotion m2 = constantVelocityMotion(Ta, a, Tb, b, b, b + 100'000'000, 2.0);
  EXPECT_NEAR(Eigen::AngleAxisd(m2.q_bi_bj).angle(), 2 * 0.4 * 0.05, 1e-12);
  EXPECT_LT((m2.p_bi_bj - 2 * rel.translation()).norm(), 1e-12);
  EXPECT_NEAR(std::sqrt(m2.cov_p(2, 2)), 4 * std::sqrt(m.cov_p(2, 2)), 1e-15);
  // Out-of-order times give no motion rather than a wrong one.
  EXPECT_EQ(constantVelocityMotion(Tb, b, Ta, a, b, b + 1, 2.0).p_bi_bj.norm(), 0.0);
}

TEST(Elimination, RecursionsEqualDirectRecomputation) {
  std::mt19937 rng(3);
  std::chi_squared_distribution<double> chi(1.0);
  std::vector<double> d(150);
  for (auto& v : d) v = chi(rng);
  for (int k = 0; k < 6; ++k) d[k] = 30.0 * std::pow(1.8, k);  // dynamic outliers, spread out
  const Elimination e = eliminate(d, 4.0);
  ASSERT_FALSE(e.removed.empty());
  std::vector<double> rest;
  std::vector<bool> gone(d.size(), false);
  for (auto i : e.removed) gone[i] = true;
  for (std::size_t i = 0; i < d.size(); ++i)
    if (!gone[i]) rest.push_back(d[i]);
  const double mu = std::accumulate(rest.begin(), rest.end(), 0.0) / rest.size();
  double var = 0;
  for (double v : rest) var += (v - mu) * (v - mu);
  var /= rest.size();
  EXPECT_NEAR(e.mean_after, mu, 1e-9);
  EXPECT_NEAR(e.var_after, var, 1e-9);
  EXPECT_NEAR(e.cv_after, std::sqrt(var) / mu, 1e-9);
  for (int k = 0; k < 6; ++k) EXPECT_TRUE(gone[k]) << k;  // every outlier removed
}

TEST(Elimination, StopsAtTheThreshold) {
  // Largest value 3.9 <= λ = 4 although the CV is far above √2: nothing removed.
  std::vector<double> d(100, 0.01);
  d[0] = 3.9;
  const Elimination e = eliminate(d, 4.0);
  EXPECT_GT(e.cv_before, std::sqrt(2.0));
  EXPECT_TRUE(e.removed.empty());
  EXPECT_EQ(e.stop, StopRule::kThreshold);
}

TEST(Elimination, StopsWhenCvReachesSqrt2) {
  // Uniform-ish values have CV < √2 from the start: nothing removed even above λ.
  std::vector<double> d;
  for (int i = 0; i < 100; ++i) d.push_back(5.0 + i);
  const Elimination e = eliminate(d, 4.0);
  EXPECT_LE(e.cv_before, std::sqrt(2.0));
  EXPECT_TRUE(e.removed.empty());
  EXPECT_EQ(e.stop, StopRule::kCvReached);
}

TEST(Elimination, StopsWhenRemovalWouldNotLowerCv) {
  // Two groups: most values 0, a few large and equal. Removing one of the equal large
  // values first lowers the CV; once a near-zero mean remains... construct so that
  // the largest value is below the mean-driven break-even: d = {0 x 98, 10, 10}.
  // CV before is 6.9; removing a 10 gives CV 9.9 (higher): stop by the third rule.
  std::vector<double> d(98, 0.0);
  d.push_back(10.0);
  d.push_back(10.0);
  const Elimination e = eliminate(d, 4.0);
  EXPECT_GT(e.cv_before, std::sqrt(2.0));
  EXPECT_TRUE(e.removed.empty());
  EXPECT_EQ(e.stop, StopRule::kCvNotLowered);
}

TEST(Elimination, StaticNoisyTracksHaveCvNearSqrt2AndAreKept) {
  // 100 frames of 150 static features with 0.5 px pixel noise in both frames and the
  // true motion as prior: d_s is ~chi-square(1), CV ~√2, at most 2 % eliminated.
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::normal_distribution<double> noise(0.0, 0.5 / kF);
  double cv_sum = 0;
  std::size_t total = 0, removed = 0;
  for (int frame = 0; frame < 100; ++frame) {
    const Motion m = randomMotion(rng);
    std::vector<double> d;
    for (int i = 0; i < 150; ++i) {
      const Vector3d p_prev(4 * u(rng), 3 * u(rng), 4 + 8 * (u(rng) + 1));
      const Vector2d x0 = project(p_prev) + Vector2d(noise(rng), noise(rng));
      const Vector2d x1 = project(m.R.transpose() * (p_prev - m.t)) + Vector2d(noise(rng), noise(rng));
      d.push_back(epipolarErrorPx2(x0, x1, m.R, m.t, kF, kF));
    }
    const Elimination e = eliminate(d, 4.0);
    cv_sum += e.cv_before;
    total += d.size();
    removed += e.removed.size();
  }
  const double cv = cv_sum / 100;
  std::printf("static noisy tracks: mean CV %.3f (sqrt2 = 1.414), eliminated %.2f %%\n", cv, 100.0 * removed / total);
  EXPECT_NEAR(cv, std::sqrt(2.0), 0.15 * std::sqrt(2.0));
  EXPECT_LE(removed, total / 50);
}

TEST(CandidateWeight, InformationIsOneOverMFlooredAtOnePixel) {
  EXPECT_DOUBLE_EQ(candidateInformation(4.0), 0.25);  // residual scaled by 1/2
  EXPECT_DOUBLE_EQ(candidateInformation(25.0), 0.04);
  EXPECT_DOUBLE_EQ(candidateInformation(0.3), 1.0);  // floor: never above the static weight
  EXPECT_DOUBLE_EQ(candidateInformation(0.0), 1.0);
}

/// One frame of `n` tracked features under a random motion (seed 5, 0.3 px noise in both
/// frames), feature i moved off its epipolar line by `off_px(i)` pixels.
struct EpipolarScene {
  frontend::MotionPrior prior;
  std::vector<frontend::Feature> feats;
  std::vector<frontend::FilterItem> items;  ///< point into feats
  EpipolarScene(int n, const std::function<double(int)>& off_px) : feats(n), items(n) {
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    std::normal_distribution<double> noise(0.0, 0.3 / kF);
    const Motion m = randomMotion(rng);
    prior.valid = true;
    prior.q_prev_cur = Eigen::Quaterniond(m.R);
    prior.t_prev_cur = m.t;
    for (int i = 0; i < n; ++i) {
      const Vector3d p_prev(4 * u(rng), 3 * u(rng), 4 + 8 * (u(rng) + 1));
      Vector2d x1 = project(m.R.transpose() * (p_prev - m.t)) + Vector2d(noise(rng), noise(rng));
      const Vector2d x0 = project(p_prev);
      const Eigen::RowVector3d l = Vector3d(x0.x(), x0.y(), 1).transpose() * hat(m.t) * m.R;
      const Vector2d normal = Vector2d(l(0), l(1)).normalized();  // across the epipolar line
      feats[i].xy = x1 + normal * off_px(i) / kF;
      items[i].feature = &feats[i];
      items[i].tracked = true;
      items[i].prev_xy = x0 + Vector2d(noise(rng), noise(rng));
    }
  }
  EpipolarScene(const EpipolarScene&) = delete;
  EpipolarScene& operator=(const EpipolarScene&) = delete;
};

TEST(IdyFilter, EliminatesMovingAndMarksBorderlineFeatures) {
  // Moving features 8, 24, 72, 216 px off their epipolar lines. The greedy rule only
  // removes a value that dominates the rest: with k equal errors, or a geometric run
  // of similar ones, removing the largest does not lower the CV (third rule), and the
  // marking + BA weights are what handles them (DESIGN §4.4-4.5).
  EpipolarScene scene(150, [](int i) {
    if (i < 4) return 8.0 * std::pow(3.0, i);
    if (i >= 10 && i < 15) return 1.5 + 0.06 * (i - 10);  // slightly moving
    return 0.0;
  });
  const auto cam = pinholeCamera();
  frontend::MotionPrior& prior = scene.prior;
  std::vector<frontend::Feature>& feats = scene.feats;
  std::vector<frontend::FilterItem>& items = scene.items;
  IdyFilter filter(4.0, 1.0);
  frontend::FilterContext ctx{cam.get(), &prior, nullptr, 0, 50'000'000};
  filter.apply(ctx, items);
  for (int i = 0; i < 4; ++i) {
    EXPECT_TRUE(items[i].remove) << i;
    EXPECT_EQ(feats[i].label, frontend::FeatureLabel::kEliminated);
  }
  int candidates = 0;
  for (int i = 10; i < 15; ++i) candidates += feats[i].label == frontend::FeatureLabel::kCandidate;
  EXPECT_EQ(candidates, 5);
  EXPECT_EQ(filter.lastStats().eliminated, 4u);
  EXPECT_LE(filter.lastStats().candidates, 10u);  // the 5 + a few noise tails at most
  EXPECT_LT(filter.lastStats().cv_after, filter.lastStats().cv_before);
  // Without a prior, the frame passes unfiltered.
  frontend::MotionPrior none;
  for (auto& it : items) it.remove = false;
  frontend::FilterContext ctx2{cam.get(), &none, nullptr, 0, 50'000'000};
  filter.apply(ctx2, items);
  for (const auto& it : items) EXPECT_FALSE(it.remove);
  EXPECT_FALSE(filter.lastStats().prior_valid);
}

TEST(IdyFilter, DsScoredFromTheConfiguredObservationOn) {
  // Features 8, 24, 72 and 216 px off their epipolar lines among static ones; the 216 px
  // one is at its second observation, all others at their tenth. With ds_from_observation
  // 3 that one is not scored (d_s 0, static, kept), and the rest is judged exactly as if
  // it were absent.
  const int n = 150;
  EpipolarScene scene(n, [](int i) { return i < 4 ? 216.0 / std::pow(3.0, i) : 0.0; });
  const auto cam = pinholeCamera();
  const frontend::MotionPrior& prior = scene.prior;
  std::vector<frontend::Feature>& feats = scene.feats;
  std::vector<frontend::FilterItem>& items = scene.items;
  for (int i = 0; i < n; ++i) feats[i].track_length = i == 0 ? 2 : 10;
  frontend::FilterContext ctx{cam.get(), &prior, nullptr, 0, 50'000'000};
  const auto filterWith = [&](int from, std::vector<frontend::FilterItem>& its) {
    IdyOptions o;
    o.ds_from_observation = from;
    IdyFilter filter(o);
    for (auto& f : feats) f.label = frontend::FeatureLabel::kStatic;
    for (auto& it : its) it.remove = false;
    filter.apply(ctx, its);
    return filter.lastStats();
  };
  const FrameStats paper = filterWith(2, items);
  EXPECT_TRUE(items[0].remove);
  EXPECT_GT(feats[0].d_s_px2, 1000.0);
  EXPECT_EQ(paper.d_s.size(), static_cast<std::size_t>(n));
  std::vector<frontend::FilterItem> without(items.begin() + 1, items.end());
  filterWith(2, without);
  std::vector<bool> removed_without;
  std::vector<frontend::FeatureLabel> labels_without;
  for (const auto& it : without) {
    removed_without.push_back(it.remove);
    labels_without.push_back(it.feature->label);
  }
  const FrameStats third = filterWith(3, items);
  EXPECT_FALSE(items[0].remove);
  EXPECT_EQ(feats[0].d_s_px2, 0.0);
  EXPECT_EQ(feats[0].label, frontend::FeatureLabel::kStatic);
  EXPECT_EQ(third.d_s.size(), static_cast<std::size_t>(n - 1));
  EXPECT_EQ(third.tracked, static_cast<std::size_t>(n));
  int removed = 0;
  for (int i = 1; i < n; ++i) {
    EXPECT_EQ(items[i].remove, removed_without[i - 1]) << i;
    EXPECT_EQ(feats[i].label, labels_without[i - 1]) << i;
    removed += items[i].remove;
  }
  EXPECT_GE(removed, 1);  // the 72 px one at least
}

// Stereo motion test (extension of §4.3): a rig with the right camera 0.11 m to the
// right of the left one, like the simulator's.
Eigen::Isometry3d rightFromLeft() {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Vector3d(-0.11, 0, 0);
  return T;
}

/// A prior of pure forward motion, `step_m` per frame (P_prev = P_cur + t).
frontend::MotionPrior forwardPrior(double step_m, double position_var) {
  frontend::MotionPrior prior;
  prior.valid = true;
  prior.t_prev_cur = Vector3d(0, 0, step_m);
  prior.cov_p = Matrix3d::Identity() * position_var;
  return prior;
}

TEST(LostCornerTest, StaticPredictionFollowsThePriorWithItsTolerance) {
  // A static point seen in stereo at 8 m, moved by a forward prior of 0.5 m: predicted
  // where it projects now, within a tolerance of the base term plus the stereo depth
  // interval plus the prior's position sigmas; without translation depth does not matter.
  const auto cam = pinholeCamera();
  const auto T_r_l = rightFromLeft();
  const frontend::MotionPrior prior = forwardPrior(0.5, 1e-4);
  auto corner = [&](const Vector3d& p) {
    frontend::LostCorner c;
    c.xy = p.head<2>() / p.z();
    const Vector3d p_r = T_r_l * p;
    c.xy_right = p_r.head<2>() / p_r.z();
    return c;
  };
  const Vector3d near_prev(1.0, -0.5, 8.0);
  const auto near = predictStaticPoint(corner(near_prev), prior, *cam, T_r_l, 0.25, 2.0);
  ASSERT_TRUE(near);
  const Vector3d near_cur = near_prev - prior.t_prev_cur;  // P_prev = P_cur + t
  Vector2d uv_true;
  ASSERT_TRUE(cam->project(near_cur, uv_true));
  EXPECT_NEAR((near->uv_pred - uv_true).norm(), 0.0, 1e-6);
  EXPECT_NEAR((near->p_pred - near_cur).norm(), 0.0, 1e-9);
  // Base 2 px + 3 prior sigmas (3 f sqrt(3e-4) / z) + the depth interval (> 0).
  const double prior_term = 3.0 * kF * std::sqrt(3e-4) / near_prev.z();
  EXPECT_GT(near->tol_px, 2.0 + prior_term);
  EXPECT_LT(near->tol_px, 2.0 + prior_term + 1.0);
  const auto still = predictStaticPoint(corner(near_prev), forwardPrior(0.0, 1e-4), *cam, T_r_l, 0.25, 2.0);
  ASSERT_TRUE(still);
  EXPECT_NEAR(still->tol_px, 2.0 + prior_term, 1e-9);
  frontend::MotionPrior invalid = prior;
  invalid.valid = false;
  EXPECT_FALSE(predictStaticPoint(corner(near_prev), invalid, *cam, T_r_l, 0.25, 2.0));
  const Vector3d behind_after(0.1, 0.0, 0.4);  // 0.4 m ahead, 0.5 m forward: behind the camera now
  EXPECT_FALSE(predictStaticPoint(corner(behind_after), prior, *cam, T_r_l, 0.25, 2.0));
}

struct StereoPair {
  Vector2d l, r;
};
StereoPair observe(const Vector3d& p_left, const Eigen::Isometry3d& T_r_l) {
  return {project(p_left), project(T_r_l * p_left)};
}

/// Feature `id`, tracked with a right match in both frames: `prev` before, `cur` now.
void trackedStereo(std::size_t id, const StereoPair& prev, const StereoPair& cur, frontend::Feature& feat,
                   frontend::FilterItem& item) {
  feat = {};
  feat.id = id;
  feat.xy = cur.l;
  feat.has_right = true;
  feat.xy_right = cur.r;
  item = {};
  item.feature = &feat;
  item.tracked = true;
  item.prev_xy = prev.l;
  item.prev_has_right = true;
  item.prev_xy_right = prev.r;
}

TEST(StereoMotionTest, StaticPointsGiveZeroAndNoiseGivesFourDof) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const double sigma_px = 0.25;
  std::normal_distribution<double> noise(0.0, sigma_px / kF);
  const auto T_r_l = rightFromLeft();
  double sum = 0;
  int n = 0, above = 0;
  for (int i = 0; i < 2000; ++i) {
    const Motion m = randomMotion(rng);
    const Vector3d p_prev(3 * u(rng), 2 * u(rng), 3 + 6 * (u(rng) + 1));
    const Vector3d p_cur = m.R.transpose() * (p_prev - m.t);
    const StereoPair a = observe(p_prev, T_r_l), b = observe(p_cur, T_r_l);
    const StereoMotionError exact = stereoMotionError(a.l, a.r, b.l, b.r, T_r_l, m.R, m.t, 0.0, kF, sigma_px);
    ASSERT_TRUE(exact.valid);
    EXPECT_LT(exact.chi2, 1e-6);
    EXPECT_NEAR(exact.depth, p_prev.z(), 1e-6 * p_prev.z());
    auto nz = [&](const Vector2d& x) { return Vector2d(x + Vector2d(noise(rng), noise(rng))); };
    const StereoMotionError e =
        stereoMotionError(nz(a.l), nz(a.r), nz(b.l), nz(b.r), T_r_l, m.R, m.t, 0.0, kF, sigma_px);
    if (!e.valid) continue;
    sum += e.chi2;
    above += e.chi2 > 18.47;
    ++n;
  }
  ASSERT_GT(n, 1900);
  // The covariance is slightly conservative (2σ² for the previous left observation, which
  // moves the prediction by about σ): the mean stays at or below the 4 of χ²₄.
  EXPECT_GT(sum / n, 1.5);
  EXPECT_LT(sum / n, 4.5);
  EXPECT_LT(above, n / 200);  // χ²₄ 99.9 % quantile: well under 0.5 % above
}

TEST(StereoMotionTest, ShapedNoiseGivesFourDofAndAnEdgeSlidingAlongItselfPasses) {
  // Matches on a horizontal edge (a roofline against the sky): KLT and the stereo match
  // slide along u. Noise drawn with covariance σ² S, S = diag(25, 1), stays χ²₄ under the
  // shaped test, while the isotropic test takes it for motion far more often.
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const double sigma_px = 0.25;
  Matrix2d shape = Matrix2d::Zero();
  shape.diagonal() << 25.0, 1.0;
  std::normal_distribution<double> nu(0.0, 5.0 * sigma_px / kF), nv(0.0, sigma_px / kF);
  const auto T_r_l = rightFromLeft();
  double sum = 0;
  int n = 0, above_shaped = 0, above_isotropic = 0;
  for (int i = 0; i < 2000; ++i) {
    const Motion m = randomMotion(rng);
    const Vector3d p_prev(3 * u(rng), 2 * u(rng), 3 + 6 * (u(rng) + 1));
    const StereoPair a = observe(p_prev, T_r_l), b = observe(m.R.transpose() * (p_prev - m.t), T_r_l);
    // With the identity the shaped test is the isotropic one.
    const auto same = stereoMotionError(a.l, a.r, b.l, b.r, T_r_l, m.R, m.t, 0.0, kF, sigma_px, Matrix2d::Identity());
    const auto plain = stereoMotionError(a.l, a.r, b.l, b.r, T_r_l, m.R, m.t, 0.0, kF, sigma_px);
    ASSERT_EQ(same.chi2, plain.chi2);
    auto nz = [&](const Vector2d& x) { return Vector2d(x + Vector2d(nu(rng), nv(rng))); };
    const Vector2d al = nz(a.l), ar = nz(a.r), bl = nz(b.l), br = nz(b.r);
    const auto e = stereoMotionError(al, ar, bl, br, T_r_l, m.R, m.t, 0.0, kF, sigma_px, shape);
    const auto iso = stereoMotionError(al, ar, bl, br, T_r_l, m.R, m.t, 0.0, kF, sigma_px);
    if (!e.valid || !iso.valid) continue;
    sum += e.chi2;
    above_shaped += e.chi2 > 18.47;
    above_isotropic += iso.chi2 > 18.47;
    ++n;
  }
  ASSERT_GT(n, 1800);
  EXPECT_GT(sum / n, 1.5);
  EXPECT_LT(sum / n, 4.5);
  EXPECT_LT(above_shaped, n / 200);
  EXPECT_GT(above_isotropic, 20 * std::max(above_shaped, 1));
}

TEST(StereoMotionTest, AShapeAcrossTheMotionDoesNotHideTheCar) {
  // The camera moves forward; a point 8 m ahead, 2 m to the side, rises by 0.1 m (4.75 px
  // along v in both images) on a horizontal edge (the shape stretched along u): the motion
  // is across the edge, so the shaped test fails it about as clearly as the isotropic one.
  const auto T_r_l = rightFromLeft();
  const Matrix3d R = Matrix3d::Identity();
  const Vector3d t(0, 0, 0.5);
  const Vector3d p_prev(2.0, 0.0, 8.0);
  const StereoPair a = observe(p_prev, T_r_l),
                   moved = observe(R.transpose() * (p_prev + Vector3d(0, 0.1, 0) - t), T_r_l);
  Matrix2d horizontal = Matrix2d::Zero();
  horizontal.diagonal() << 100.0, 1.0;
  const double sigma_p2 = 1e-4;
  const auto shaped = stereoMotionError(a.l, a.r, moved.l, moved.r, T_r_l, R, t, sigma_p2, kF, 0.25, horizontal);
  const auto isotropic = stereoMotionError(a.l, a.r, moved.l, moved.r, T_r_l, R, t, sigma_p2, kF, 0.25);
  ASSERT_TRUE(shaped.valid);
  EXPECT_GT(shaped.chi2, 18.47);
  EXPECT_GT(shaped.chi2, 0.5 * isotropic.chi2);
}

TEST(StereoMotionTest, SeesMotionAlongTheEpipolarLineThatDsCannot) {
  // The camera moves forward 0.5 m; a car 8 m ahead, 2 m to the side, drives away at
  // 0.4 m per frame: parallel to the camera's motion, so it stays on its epipolar line.
  const auto T_r_l = rightFromLeft();
  const Matrix3d R = Matrix3d::Identity();
  const Vector3d t(0, 0, 0.5);  // p_prev = R p_cur + t: the current camera is 0.5 m ahead
  const Vector3d p_prev(2.0, 0.5, 8.0);
  const Vector3d p_static_cur = R.transpose() * (p_prev - t);
  const Vector3d p_moving_cur = R.transpose() * (p_prev + Vector3d(0, 0, 0.4) - t);
  const StereoPair a = observe(p_prev, T_r_l), s = observe(p_static_cur, T_r_l), mv = observe(p_moving_cur, T_r_l);
  EXPECT_LT(epipolarErrorPx2(a.l, mv.l, R, t, kF, kF), 1e-9);  // d_s: indistinguishable from static
  const double sigma_p2 = 0.01 * 0.01;
  const auto e_static = stereoMotionError(a.l, a.r, s.l, s.r, T_r_l, R, t, sigma_p2, kF, 0.25);
  const auto e_moving = stereoMotionError(a.l, a.r, mv.l, mv.r, T_r_l, R, t, sigma_p2, kF, 0.25);
  ASSERT_TRUE(e_moving.valid);
  EXPECT_LT(e_static.chi2, 1e-6);
  // Most of the 5 % depth change hides in the stereo depth noise (σ_ρ/ρ ≈ 7 % at 8 m);
  // the rest is still far above the 99.9 % threshold of 18.47.
  EXPECT_GT(e_moving.chi2, 50.0);
  // The 0.4 m shift moves the image point by f ‖(x, y)‖ (1/z' - 1/z) = 380·√4.25·(1/7.5 - 1/7.9) px.
  const double expected_px = kF * std::sqrt(4.25) * std::abs(1.0 / 7.9 - 1.0 / 7.5);
  EXPECT_NEAR((mv.l - s.l).norm() * kF, expected_px, 1e-9);
  EXPECT_GT(e_moving.residual_px2, expected_px * expected_px);  // left and right residuals
  // A looser prior (σ_P = 0.5 m) explains part of it: χ² drops.
  const auto e_loose = stereoMotionError(a.l, a.r, mv.l, mv.r, T_r_l, R, t, 0.25, kF, 0.25);
  EXPECT_LT(e_loose.chi2, 0.1 * e_moving.chi2);
  // Not triangulable (parallel rays with no baseline) → invalid, never flagged.
  EXPECT_FALSE(stereoMotionError(a.l, a.r, s.l, s.r, Eigen::Isometry3d::Identity(), R, t, 0, kF, 0.25).valid);
}

TEST(StereoMotionTest, LeftResidualAloneSeparatesABadRightMatchFromMotion) {
  // Same rig and car as above. A static point whose current right match is 3 px off (the
  // true one hidden behind a vehicle, KLT settling on the silhouette) fails the 4-dof test
  // like the moving car, but only the car's left-image residual disagrees with the prior.
  const auto T_r_l = rightFromLeft();
  const Matrix3d R = Matrix3d::Identity();
  const Vector3d t(0, 0, 0.5);
  const Vector3d p_prev(2.0, 0.5, 8.0);
  const StereoPair a = observe(p_prev, T_r_l), s = observe(R.transpose() * (p_prev - t), T_r_l),
                   mv = observe(R.transpose() * (p_prev + Vector3d(0, 0, 0.4) - t), T_r_l);
  const double sigma_p2 = 0.01 * 0.01, left_gate = 13.82;  // χ²₂ 99.9 %
  const auto bad_right = stereoMotionError(a.l, a.r, s.l, s.r + Vector2d(3.0 / kF, 0), T_r_l, R, t, sigma_p2, kF, 0.25);
  const auto moving = stereoMotionError(a.l, a.r, mv.l, mv.r, T_r_l, R, t, sigma_p2, kF, 0.25);
  std::printf("bad right match: chi2 %.1f, left %.3f; moving car: chi2 %.1f, left %.1f\n", bad_right.chi2,
              bad_right.chi2_left, moving.chi2, moving.chi2_left);
  EXPECT_GT(bad_right.chi2, 18.47);
  EXPECT_LT(bad_right.chi2_left, 1e-6);
  EXPECT_GT(moving.chi2_left, left_gate);
}

TEST(IdyFilter, StereoTestMarksOnFirstFailureAndRemovesOnSecond) {
  const auto cam = pinholeCamera();
  const auto T_r_l = rightFromLeft();
  const frontend::MotionPrior prior = forwardPrior(0.5, 1e-6);
  IdyOptions o;
  o.stereo.enabled = true;
  o.stereo.sigma_px = 0.25;
  o.stereo.remove_chi2 = 0;  // = chi2: every repeated failure removes
  o.T_r_l = T_r_l;
  IdyFilter filter(o);
  IdyOptions high_bar = o;  // a repeated failure below remove_chi2 stays a candidate
  high_bar.stereo.remove_chi2 = 1e9;
  IdyFilter keeps(high_bar);
  IdyOptions off = o;
  off.stereo.enabled = false;
  IdyFilter paper_only(off);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  // 60 static points and one car driving away along the view (feature id 0).
  std::vector<Vector3d> points(61);
  for (auto& p : points) p = Vector3d(4 * u(rng), 2 * u(rng), 6 + 4 * (u(rng) + 1));
  points[0] = Vector3d(2.0, 0.5, 8.0);
  auto frameItems = [&](std::vector<frontend::Feature>& feats, std::vector<frontend::FilterItem>& items) {
    feats.assign(points.size(), {});
    items.assign(points.size(), {});
    for (std::size_t i = 0; i < points.size(); ++i) {
      const Vector3d p_prev = points[i];
      const Vector3d p_cur = p_prev + Vector3d(0, 0, i == 0 ? 0.4 : 0.0) - prior.t_prev_cur;
      trackedStereo(i, observe(p_prev, T_r_l), observe(p_cur, T_r_l), feats[i], items[i]);
    }
    for (auto& p : points) p = p - prior.t_prev_cur + (&p == &points[0] ? Vector3d(0, 0, 0.4) : Vector3d::Zero());
  };
  frontend::FilterContext ctx{cam.get(), &prior, nullptr, 0, 50'000'000};
  std::vector<frontend::Feature> feats;
  std::vector<frontend::FilterItem> items;
  const auto start = points;
  frameItems(feats, items);
  auto copy_items = items;
  auto copy_feats = feats;
  for (std::size_t i = 0; i < copy_items.size(); ++i) copy_items[i].feature = &copy_feats[i];
  paper_only.apply(ctx, copy_items);  // the paper's test alone: the car passes as static
  EXPECT_FALSE(copy_items[0].remove);
  EXPECT_EQ(copy_feats[0].label, frontend::FeatureLabel::kStatic);
  const auto run_copy = [&](IdyFilter& f) {
    copy_items = items;
    copy_feats = feats;
    for (std::size_t i = 0; i < copy_items.size(); ++i) copy_items[i].feature = &copy_feats[i];
    f.apply(ctx, copy_items);
  };
  run_copy(keeps);
  filter.apply(ctx, items);  // first failure: marked only
  EXPECT_FALSE(items[0].remove);
  EXPECT_EQ(feats[0].label, frontend::FeatureLabel::kCandidate);
  EXPECT_GT(feats[0].stereo_chi2, o.stereo.chi2);
  EXPECT_EQ(filter.lastStats().stereo_tested, points.size());
  frameItems(feats, items);
  run_copy(keeps);  // second failure, but below remove_chi2: still only a candidate
  EXPECT_FALSE(copy_items[0].remove);
  EXPECT_EQ(copy_feats[0].label, frontend::FeatureLabel::kCandidate);
  EXPECT_EQ(keeps.lastStats().stereo_eliminated, 0u);
  filter.apply(ctx, items);  // second consecutive failure: removed
  EXPECT_TRUE(items[0].remove);
  EXPECT_EQ(feats[0].label, frontend::FeatureLabel::kEliminated);
  EXPECT_EQ(filter.lastStats().stereo_eliminated, 1u);
  EXPECT_GT(feats[0].stereo_chi2, 80.0);  // clear: removed at its second failure even with remove_chi2 80
  frameItems(feats, items);
  run_copy(keeps);                                   // a third consecutive failure persists: removed whatever its χ²
  ASSERT_EQ(high_bar.stereo.persistent_strikes, 3);  // the default
  EXPECT_TRUE(copy_items[0].remove);
  EXPECT_EQ(keeps.lastStats().stereo_eliminated, 1u);
  for (std::size_t i = 1; i < items.size(); ++i) {
    EXPECT_FALSE(items[i].remove) << i;
    EXPECT_LT(feats[i].stereo_chi2, 1e-3) << i;
  }
  // Without a right match in the previous frame the feature is not tested.
  points = start;
  frameItems(feats, items);
  items[0].prev_has_right = false;
  IdyFilter fresh(o);
  fresh.apply(ctx, items);
  EXPECT_EQ(feats[0].stereo_chi2, -1);
  EXPECT_EQ(fresh.lastStats().stereo_tested, points.size() - 1);
}

TEST(IdyFilter, LeftGateSparesStaticPointsWhoseRightMatchAloneIsOff) {
  // 40 static points, 10 of them (ids 1–10) with a right match 3 px off in every new frame
  // (the true one hidden, KLT on a silhouette), and the car of the test above (id 0).
  const auto cam = pinholeCamera();
  const auto T_r_l = rightFromLeft();
  const frontend::MotionPrior prior = forwardPrior(0.5, 1e-6);
  IdyOptions gated;
  gated.stereo.enabled = true;
  gated.stereo.remove_chi2 = 0;  // every repeated failure removes: the gate alone decides
  gated.T_r_l = T_r_l;
  ASSERT_DOUBLE_EQ(gated.stereo.left_chi2, 5.99);  // the default
  IdyOptions ungated = gated;
  ungated.stereo.left_chi2 = 0;  // 0 = off
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<Vector3d> start(41);
  for (auto& p : start) p = Vector3d(4 * u(rng), 2 * u(rng), 6 + 4 * (u(rng) + 1));
  start[0] = Vector3d(2.0, 0.5, 8.0);
  const frontend::FilterContext ctx{cam.get(), &prior, nullptr, 0, 50'000'000};
  auto run = [&](const IdyOptions& o) {
    IdyFilter filter(o);
    std::vector<Vector3d> points = start;
    std::vector<frontend::Feature> feats(points.size());
    std::vector<frontend::FilterItem> items(points.size());
    std::vector<frontend::FeatureLabel> labels(points.size());
    std::vector<bool> removed(points.size(), false);
    for (int frame = 0; frame < 2; ++frame) {
      for (std::size_t i = 0; i < points.size(); ++i) {
        const Vector3d p_cur = points[i] + Vector3d(0, 0, i == 0 ? 0.4 : 0.0) - prior.t_prev_cur;
        StereoPair b = observe(p_cur, T_r_l);
        if (i >= 1 && i <= 10) b.r += Vector2d(3.0 / kF, 0);
        trackedStereo(i, observe(points[i], T_r_l), b, feats[i], items[i]);
        points[i] = p_cur;
      }
      filter.apply(ctx, items);
      for (std::size_t i = 0; i < points.size(); ++i) removed[i] = removed[i] || items[i].remove;
    }
    for (std::size_t i = 0; i < points.size(); ++i) labels[i] = feats[i].label;
    return std::make_pair(removed, labels);
  };
  const auto [removed_gated, labels_gated] = run(gated);
  const auto [removed_ungated, labels_ungated] = run(ungated);
  EXPECT_TRUE(removed_gated[0]);  // the car: its left residual disagrees too
  EXPECT_TRUE(removed_ungated[0]);
  int bad_removed_ungated = 0;
  for (std::size_t i = 1; i < start.size(); ++i) {
    EXPECT_FALSE(removed_gated[i]) << i;
    EXPECT_EQ(labels_gated[i], frontend::FeatureLabel::kStatic) << i;
    if (i > 10) {
      EXPECT_FALSE(removed_ungated[i]) << i;
    }
    bad_removed_ungated += (i <= 10 && removed_ungated[i]) ? 1 : 0;
  }
  EXPECT_EQ(bad_removed_ungated, 10);  // without the gate two bad right matches remove a static point
}

/// A truck driving along the camera's line of sight among static points, all tracked in
/// stereo with Gaussian noise through an IdyFilter with the stereo motion test.
struct LineOfSightScene {
  Vector3d truck;            ///< the truck's feature in the first frame (left camera, m)
  double truck_step = 0;     ///< m per frame, away from the camera
  double camera_step = 0;    ///< m per frame, forward
  double near = 0, far = 0;  ///< depth range of the 80 static points (m)
  int frames = 0;
};
struct LineOfSightResult {
  int truck_removed_at = -1;  ///< frame of the truck's removal, -1: never
  int static_removed = 0;
};

LineOfSightResult runLineOfSight(const LineOfSightScene& scene, int anchor_frames, double noise_ref, double noise_px) {
  const auto cam = pinholeCamera();
  const auto T_r_l = rightFromLeft();
  const frontend::MotionPrior prior = forwardPrior(scene.camera_step, 1e-8);
  IdyOptions o;
  o.stereo.enabled = true;
  o.T_r_l = T_r_l;
  o.stereo.anchor_frames = anchor_frames;
  o.stereo.noise_ref = noise_ref;
  IdyFilter filter(o);
  std::mt19937 rng(8);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::normal_distribution<double> noise(0.0, noise_px / kF);
  std::vector<Vector3d> points(81);
  const double half = 0.5 * (scene.far - scene.near);
  for (auto& p : points) p = Vector3d(6 * u(rng), 2 * u(rng), scene.near + half * (u(rng) + 1));
  points[0] = scene.truck;
  std::vector<frontend::Feature> feats(points.size());
  std::vector<bool> gone(points.size(), false);
  std::vector<StereoPair> prev(points.size());
  auto nz = [&](const Vector2d& x) { return Vector2d(x + Vector2d(noise(rng), noise(rng))); };
  for (std::size_t i = 0; i < points.size(); ++i) {
    const StereoPair o0 = observe(points[i], T_r_l);
    prev[i] = {nz(o0.l), nz(o0.r)};
  }
  LineOfSightResult out;
  frontend::FilterContext ctx{cam.get(), &prior, nullptr, 0, 50'000'000};
  for (int frame = 1; frame <= scene.frames; ++frame) {
    std::vector<frontend::FilterItem> live;
    std::vector<std::size_t> ids;
    for (std::size_t i = 0; i < points.size(); ++i) {
      points[i] += Vector3d(0, 0, i == 0 ? scene.truck_step : 0.0) - prior.t_prev_cur;
      if (gone[i]) continue;
      const StereoPair ob = observe(points[i], T_r_l);
      frontend::FilterItem it;
      trackedStereo(i, prev[i], StereoPair{nz(ob.l), nz(ob.r)}, feats[i], it);  // braces: left noise first
      live.push_back(it);
      ids.push_back(i);
      prev[i] = {feats[i].xy, feats[i].xy_right};
    }
    filter.apply(ctx, live);
    for (std::size_t k = 0; k < live.size(); ++k) {
      if (!live[k].remove) continue;
      gone[ids[k]] = true;
      if (ids[k] == 0)
        out.truck_removed_at = frame;
      else
        ++out.static_removed;
    }
  }
  return out;
}

TEST(IdyFilter, AnchoredStereoTestSeesSlowMotionAlongTheLineOfSight) {
  // A truck 25 m ahead drives away 0.15 m per frame while the camera moves 0.1 m per
  // frame forward: per frame its image motion stays within the stereo depth noise, but
  // against an anchor up to 10 frames back it does not. 80 static points with 0.2 px
  // noise must survive 30 frames either way. With a fixed σ (noise_ref 0): 0.2 px of
  // Gaussian noise puts the frame's 25 % χ² quantile near 1, which the default noise scale
  // would read as a noisy tracker (see StereoNoiseScale below); at the bulk noise of the
  // tracker on clean renders (0.05 px) the default scale stays 1 and the truck goes the same.
  const LineOfSightScene scene{Vector3d(2.5, 0.3, 25.0), 0.15, 0.1, 12, 28, 30};
  const LineOfSightResult one = runLineOfSight(scene, 1, 0.0, 0.2);
  const LineOfSightResult ten = runLineOfSight(scene, 10, 0.0, 0.2);
  const LineOfSightResult scaled = runLineOfSight(scene, 10, StereoMotionOptions{}.noise_ref, 0.05);
  EXPECT_EQ(one.truck_removed_at, -1);  // consecutive frames only: never removed in 30 frames
  EXPECT_GT(ten.truck_removed_at, 2);   // anchored: removed after a few frames of accumulated motion
  EXPECT_LE(ten.truck_removed_at, 12);
  EXPECT_LE(one.static_removed, 1);
  EXPECT_LE(ten.static_removed, 1);
  EXPECT_GT(scaled.truck_removed_at, 2);
  EXPECT_LE(scaled.truck_removed_at, 12);
  EXPECT_EQ(scaled.static_removed, 0);
}

TEST(IdyFilter, AFarTruckAlongTheLineOfSightNeedsTheLongAnchor) {
  // A walking camera (0.07 m per frame) and a car 80 m ahead, 14 px from the focus of
  // expansion, driving away at 8 m/s (0.4 m per frame): its disparity (0.5 px) cannot tell
  // its depth change, and over 10 frames it moves about 0.6 px toward the focus of
  // expansion, within what a static point at some depth inside the stereo noise does. Over
  // the default anchor (40 frames, 2 s) it moves about 2 px and is removed; static points
  // 40-120 m away are not, at the default noise scale and 0.05 px of tracking noise.
  const LineOfSightScene scene{Vector3d(3.0, 0.3, 80.0), 0.4, 0.07, 40, 120, 80};
  const double noise_ref = StereoMotionOptions{}.noise_ref;
  const LineOfSightResult ten = runLineOfSight(scene, 10, noise_ref, 0.05);
  const LineOfSightResult def = runLineOfSight(scene, StereoMotionOptions{}.anchor_frames, noise_ref, 0.05);
  EXPECT_EQ(ten.truck_removed_at, -1);
  EXPECT_GT(def.truck_removed_at, 10);  // after more motion than the 10-frame anchor spans
  EXPECT_LE(def.truck_removed_at, 40);
  EXPECT_EQ(ten.static_removed, 0);
  EXPECT_EQ(def.static_removed, 0);
}

TEST(StereoNoiseScale, QuantileOverTheReferenceNeverBelowOne) {
  std::vector<double> chi2(101);
  for (std::size_t i = 0; i < chi2.size(); ++i) chi2[100 - i] = 0.01 * static_cast<double>(i);  // 0 … 1, reversed
  EXPECT_NEAR(stereoNoiseScale(chi2, 0.25, 0.1), 2.5, 1e-12);                                   // 25 % quantile 0.25
  EXPECT_NEAR(stereoNoiseScale(chi2, 0.5, 0.1), 5.0, 1e-12);
  EXPECT_DOUBLE_EQ(stereoNoiseScale(chi2, 0.25, 0.5), 1.0);  // quiet frame: never below 1
  EXPECT_DOUBLE_EQ(stereoNoiseScale(chi2, 0.25, 0.0), 1.0);  // 0 = off
  EXPECT_DOUBLE_EQ(stereoNoiseScale({}, 0.25, 0.1), 1.0);
  // Robust: 70 % of the values replaced by huge ones (moving points) leave the 25 % quantile.
  std::vector<double> contaminated(100, 0.3);
  for (std::size_t i = 0; i < 70; ++i) contaminated[i * 100 / 70] = 500.0;
  EXPECT_NEAR(stereoNoiseScale(contaminated, 0.25, 0.1), 3.0, 1e-12);
}

TEST(IdyFilter, NoiseScaleHoldsTheFalseAlarmRateOnHeavyTailedTracks) {
  // 200 static points tracked with the heavy-tailed errors of a real tracker: 0.12 px of
  // Gaussian noise and, on 4 % of the observations, a 1.2 px slip; and one car driving
  // away along the view at 1 m per frame. With a fixed σ the slips remove static points;
  // the frame's noise scale (25 % χ² quantile over the reference) keeps them, and the car
  // still goes.
  const auto cam = pinholeCamera();
  const auto T_r_l = rightFromLeft();
  const frontend::MotionPrior prior = forwardPrior(0.3, 1e-8);
  auto runFrames = [&](double noise_ref, int& car_removed_at, int& static_removed, double& mean_scale) {
    IdyOptions o;
    o.stereo.enabled = true;
    o.stereo.remove_chi2 = 0;  // every repeated failure removes: the noise scale alone decides
    o.T_r_l = T_r_l;
    o.stereo.noise_ref = noise_ref;
    IdyFilter filter(o);
    std::mt19937 rng(21);
    std::uniform_real_distribution<double> u(-1.0, 1.0), unit(0.0, 1.0);
    std::normal_distribution<double> noise(0.0, 0.12 / kF);
    auto nz = [&](const Vector2d& x) {
      Vector2d e(noise(rng), noise(rng));
      if (unit(rng) < 0.04) e += Vector2d(u(rng), u(rng)).normalized() * (1.2 / kF);
      return Vector2d(x + e);
    };
    std::vector<Vector3d> points(201);
    for (auto& p : points) p = Vector3d(6 * u(rng), 2 * u(rng), 6 + 6 * (u(rng) + 1));
    points[0] = Vector3d(2.0, 0.5, 10.0);
    std::vector<frontend::Feature> feats(points.size());
    std::vector<bool> gone(points.size(), false);
    std::vector<StereoPair> prev(points.size());
    for (std::size_t i = 0; i < points.size(); ++i) {
      const StereoPair o0 = observe(points[i], T_r_l);
      prev[i] = {nz(o0.l), nz(o0.r)};
    }
    car_removed_at = -1;
    static_removed = 0;
    mean_scale = 0;
    const int frames = 20;
    frontend::FilterContext ctx{cam.get(), &prior, nullptr, 0, 50'000'000};
    for (int frame = 1; frame <= frames; ++frame) {
      std::vector<frontend::FilterItem> live;
      std::vector<std::size_t> ids;
      for (std::size_t i = 0; i < points.size(); ++i) {
        points[i] += Vector3d(0, 0, i == 0 ? 1.0 : 0.0) - prior.t_prev_cur;
        if (gone[i]) continue;
        const StereoPair ob = observe(points[i], T_r_l);
        frontend::FilterItem it;
        const Vector2d l = nz(ob.l), r = nz(ob.r);
        trackedStereo(i, prev[i], StereoPair{l, r}, feats[i], it);
        live.push_back(it);
        ids.push_back(i);
        prev[i] = {l, r};
      }
      filter.apply(ctx, live);
      mean_scale += filter.lastStats().stereo_noise_scale / frames;
      for (std::size_t k = 0; k < live.size(); ++k) {
        if (!live[k].remove) continue;
        gone[ids[k]] = true;
        if (ids[k] == 0)
          car_removed_at = frame;
        else
          ++static_removed;
      }
    }
  };
  int car_fixed = 0, static_fixed = 0, car_scaled = 0, static_scaled = 0;
  double scale_fixed = 0, scale_scaled = 0;
  runFrames(0.0, car_fixed, static_fixed, scale_fixed);
  runFrames(StereoMotionOptions{}.noise_ref, car_scaled, static_scaled, scale_scaled);
  std::printf(
      "fixed sigma: %d static removed, car at frame %d; noise scale (mean %.2f): %d static removed, car at %d\n",
      static_fixed, car_fixed, scale_scaled, static_scaled, car_scaled);
  EXPECT_DOUBLE_EQ(scale_fixed, 1.0);
  EXPECT_GT(scale_scaled, 1.5);
  EXPECT_GE(static_fixed, 5);
  EXPECT_LE(static_scaled, static_fixed / 3);
  EXPECT_GT(car_fixed, 0);
  EXPECT_GT(car_scaled, 0);
  EXPECT_LE(car_scaled, 4);
}

}  // namespace
}  // namespace idyvins::dynamic

namespace idyvins::dynamic {
namespace {

TEST(IdyFilter, PointsBeyondTheMinimumDisparityAreNotJudged) {
  // Two cars driving away along the view at 2 m per frame, one 10 m ahead (disparity
  // 380 · 0.11 / 10 = 4.2 px) and one 40 m ahead (1.0 px), among 60 static points at
  // 6–14 m. The test sees both; with stereo_motion_min_disparity_px 1.5 the far one is
  // left alone (its χ² is still reported), the near one goes as before.
  const auto cam = pinholeCamera();
  const auto T_r_l = rightFromLeft();
  const frontend::MotionPrior prior = forwardPrior(0.3, 1e-8);
  auto run = [&](double min_disparity_px, std::vector<bool>& removed, std::vector<double>& chi2) {
    IdyOptions o;
    o.stereo.enabled = true;
    o.T_r_l = T_r_l;
    o.stereo.min_disparity_px = min_disparity_px;
    IdyFilter filter(o);
    std::mt19937 rng(4);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    std::vector<Vector3d> points(62);
    for (auto& p : points) p = Vector3d(4 * u(rng), 2 * u(rng), 10 + 4 * u(rng));
    points[0] = Vector3d(1.0, 0.3, 10.0);
    points[1] = Vector3d(3.0, 0.5, 40.0);
    std::vector<frontend::Feature> feats(points.size());
    std::vector<frontend::FilterItem> items(points.size());
    removed.assign(points.size(), false);
    chi2.assign(points.size(), -1);
    const frontend::FilterContext ctx{cam.get(), &prior, nullptr, 0, 50'000'000};
    for (int frame = 0; frame < 3; ++frame) {
      for (std::size_t i = 0; i < points.size(); ++i) {
        const Vector3d p_cur = points[i] + Vector3d(0, 0, i <= 1 ? 2.0 : 0.0) - prior.t_prev_cur;
        trackedStereo(i, observe(points[i], T_r_l), observe(p_cur, T_r_l), feats[i], items[i]);
        points[i] = p_cur;
      }
      filter.apply(ctx, items);
      for (std::size_t i = 0; i < points.size(); ++i) {
        removed[i] = removed[i] || items[i].remove;
        chi2[i] = std::max(chi2[i], feats[i].stereo_chi2);
      }
    }
  };
  std::vector<bool> all, gated;
  std::vector<double> chi2_all, chi2_gated;
  run(0.0, all, chi2_all);
  run(1.5, gated, chi2_gated);
  EXPECT_TRUE(all[0]);
  EXPECT_TRUE(all[1]);  // judged: the far car fails too
  EXPECT_TRUE(gated[0]);
  EXPECT_FALSE(gated[1]);                                // beyond the minimum disparity: not judged
  EXPECT_GT(chi2_gated[1], StereoMotionOptions{}.chi2);  // but its χ² is reported
  for (std::size_t i = 2; i < all.size(); ++i) {
    EXPECT_FALSE(all[i]) << i;
    EXPECT_FALSE(gated[i]) << i;
  }
}

}  // namespace
}  // namespace idyvins::dynamic

TEST(DepthSign, StaticPointsHaveAPositiveInverseDepthOvertakingOnesANegativeOne) {
  using idyvins::dynamic::depthSign;
  using idyvins::dynamic::DepthSign;
  // The camera moves 0.1 m forward (z) and turns 2° about y; P_a = R P_c + t.
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.035, Eigen::Vector3d::UnitY()).toRotationMatrix();
  const Eigen::Vector3d t(0.01, 0.0, 0.1);
  const double focal = 380, sigma_px = 0.25;
  const auto observe = [&](const Eigen::Vector3d& P_a, const Eigen::Vector3d& P_a_moved) {
    const Eigen::Vector3d P_c = R.transpose() * (P_a_moved - t);
    return depthSign(P_a.head<2>() / P_a.z(), P_c.head<2>() / P_c.z(), R, t, 1e-6, focal, sigma_px);
  };
  const Eigen::Vector3d near(1.5, 0.5, 4.0), far(-20, 5, 200);
  const DepthSign s = observe(near, near);
  ASSERT_TRUE(s.valid);
  EXPECT_NEAR(s.rho, 1.0 / 4.0, 1e-9);
  EXPECT_GT(s.z, 5.0);  // measured 8.0
  const DepthSign f = observe(far, far);
  ASSERT_TRUE(f.valid);
  EXPECT_NEAR(f.rho, 1.0 / 200.0, 1e-9);
  EXPECT_GT(f.z, 0.0);
  // A vehicle beside the camera overtaking it: 0.4 m forward in the same 0.05 s.
  const DepthSign o = observe(near, near + Eigen::Vector3d(0, 0, 0.4));
  ASSERT_TRUE(o.valid);
  EXPECT_LT(o.rho, 0.0);
  EXPECT_LT(o.z, -3.29);
  // No translation: nothing can be said.
  const Eigen::Vector3d P_c = R.transpose() * near;
  EXPECT_FALSE(
      depthSign(near.head<2>() / near.z(), P_c.head<2>() / P_c.z(), R, Eigen::Vector3d::Zero(), 0, focal, sigma_px)
          .valid);
}
