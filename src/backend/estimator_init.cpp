// Initialization of the window (DESIGN §2): PnP of each new frame against the window's stereo
// landmarks checked against the gyroscope, the time offset from the rotations (estimate_td),
// gyroscope bias, gravity and velocities from the IMU.

#include <Eigen/Core>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>

#include "backend/estimator.h"
#include "backend/initializer.h"
#include "backend/mono_init.h"

namespace idyvins::backend {

using Eigen::Isometry3d;
using Eigen::Quaterniond;
using Eigen::Vector2d;
using Eigen::Vector3d;

bool Estimator::initStepStereo(FrameResult& r) {
  // imu: 0: the first frame is the world (its body frame, or the last good pose after a failure),
  // started as soon as its stereo landmarks are enough for the next frame's PnP.
  if (seg_.reanchor_pending && seg_.last_good) {
    imu::NavState s = *seg_.last_good;
    s.v_w.setZero();
    w_.frames[w_.count].setNav(s);
    seg_.reanchor_pending = false;
    r.reanchored = "held";
  }
  w_.fm.triangulate(w_.poses(), rig_);
  if (w_.fm.trackedIn(w_.count) < kStereoInitLandmarks) {
    r.status = "initializing: too few stereo landmarks, waiting";
    resetWindow();
    return false;
  }
  w_.initialized = true;
  r.status = "initialized (stereo, no IMU)";
  return true;
}

bool Estimator::initStep(FrameResult& r) {
  if (!options_.use_imu) return initStepStereo(r);
  if (!ex_.rotation_known && !calibrateRotation(r)) return false;
  if (!rig_.stereo) return initStepMono(r);
  const int n = w_.count;
  if (n > 0) {
    if (!pnp(n)) {
      r.status = "initializing: PnP failed, restarting";
      resetWindow();
      return false;
    }
    // Check the visual rotation against the gyroscope before accepting the frame.
    const Quaterniond q_vis =
        Quaterniond(w_.frames[n - 1].T_w_b().linear()).conjugate() * Quaterniond(w_.frames[n].T_w_b().linear());
    const double diff_deg = q_vis.angularDistance(w_.frames[n].pre->deltaQ()) * 180.0 / M_PI;
    if (diff_deg > options_.init_rotation_check_deg) {
      r.status = "initializing: PnP rotation disagrees with the gyroscope, restarting";
      resetWindow();
      return false;
    }
  }
  w_.fm.triangulate(w_.poses(), rig_);
  if (n < kWindowSize) {
    r.status = "initializing: " + std::to_string(n + 1) + "/" + std::to_string(kWindowSize + 1) + " frames";
    return false;
  }
  if (estimatesTd() && !seg_.td_restarted && alignTimeOffset(r)) return false;
  if (!alignAndStart()) {
    r.status = "initializing: gravity/velocity alignment failed, sliding";
    slide(true);
    return false;
  }
  r.status = "initialized";
  if (seg_.reanchor_pending) {
    r.biases_from_last_good = biasesFromLastGood();  // as alignAndStart decided
    r.reanchored = reanchor();
  }
  return true;
}

bool Estimator::alignTimeOffset(FrameResult& r) {
  // Collect the PnP poses while the window slides, then search the offset over all of them:
  // over one window (0.5 s) the streets' slow turns left the search 10-30 ms off, over 2 s
  // within 2.4 ms (docs/results.md, "A time offset from any start").
  if (seg_.td_times.empty())
    for (int i = 0; i < w_.count; ++i) {
      seg_.td_poses.push_back(w_.frames[i].T_w_b());
      seg_.td_times.push_back(w_.frames[i].t_ns);
    }
  seg_.td_poses.push_back(w_.frames[w_.count].T_w_b());
  seg_.td_times.push_back(w_.frames[w_.count].t_ns);
  const double span_s = 1e-9 * static_cast<double>(seg_.td_times.back() - seg_.td_times.front());
  const auto collecting = [&](const std::string& why) {
    r.status = "initializing: " + why + " (" + std::to_string(std::lround(10 * span_s) / 10.0).substr(0, 3) +
               " s of poses), searching the time offset";
    slide(true);
    return true;
  };
  if (span_s < kTdSearchSpanS) return collecting("collecting poses");
  std::vector<Quaterniond> q;
  for (const auto& T : seg_.td_poses) q.emplace_back(T.linear());
  double contrast = 0;
  const std::optional<double> shift = alignRotationTimes(q, seg_.td_times, w_.imu, kTdInitSearchS, 0.001, &contrast);
  // How far kContrastShiftS off the best raises the rotations' misfit, in units of its noise
  // (an F statistic of one parameter), and how fast the rig turns: a rig at rest or moving
  // straight does not tell the offset, and a flat misfit's minimum is noise.
  const double significance = (contrast - 1.0) * static_cast<double>(q.size() - 4);
  double angle = 0;
  for (std::size_t i = 1; i < q.size(); ++i) angle += q[i - 1].angularDistance(q[i]);
  const bool tells = shift && significance >= kTdSignificance && angle / span_s >= kTdSearchMinRate;
  if (!tells && span_s < kTdSearchMaxSpanS) return collecting("the rotations do not tell the offset yet");
  seg_.td_poses.clear();
  seg_.td_times.clear();
  seg_.td_restarted = true;
  // Not telling after kTdSearchMaxSpanS, or a shift below kTdInitRestartS: the window starts
  // with the current offset and estimates it.
  if (!tells || std::abs(*shift) < kTdInitRestartS) return false;
  // Moving the window's observations by the shift starts its solve far from where PnP put
  // the poses (a shift of all poses along the motion is nearly free for the IMU factors and
  // the solver crawls along it): start again with frames stamped with the new offset.
  w_.td_s += *shift;
  resetWindow();
  r.status = "initializing: time offset " + std::to_string(1e3 * w_.td_s) + " ms from the rotations of " +
             std::to_string(q.size()) + " frames (significance " + std::to_string(std::lround(significance)) +
             "), restarting";
  return true;
}

bool Estimator::pnp(int n) {
  std::vector<cv::Point3d> obj;
  std::vector<cv::Point2d> img;
  std::vector<std::uint64_t> ids;
  for (const auto& [id, lm] : w_.fm.landmarks()) {
    if (lm.inv_depth <= 0 || lm.start_frame >= n || lm.endFrame() != n) continue;
    const Vector3d p_w = cameraPose(w_.frames[lm.start_frame].T_w_b(), rig_.T_b_c0) * lm.anchorPoint();
    obj.emplace_back(p_w.x(), p_w.y(), p_w.z());
    img.emplace_back(lm.obs.back().xy.x(), lm.obs.back().xy.y());
    ids.push_back(id);
  }
  if (static_cast<int>(obj.size()) < options_.min_pnp_points) return false;
  // Initial guess: the previous camera pose.
  const Isometry3d T_c_w = cameraPose(w_.frames[n - 1].T_w_b(), rig_.T_b_c0).inverse();
  cv::Mat rvec, tvec;
  cv::Mat R_cv;
  cv::eigen2cv(Eigen::Matrix3d(T_c_w.linear()), R_cv);
  cv::Rodrigues(R_cv, rvec);
  cv::eigen2cv(Vector3d(T_c_w.translation()), tvec);
  std::vector<int> inliers;
  const bool ok = cv::solvePnPRansac(obj, img, cv::Mat::eye(3, 3, CV_64F), cv::Mat(), rvec, tvec, true, 100,
                                     2.0 / rig_.focal_px, 0.99, inliers, cv::SOLVEPNP_ITERATIVE);
  if (!ok || static_cast<int>(inliers.size()) < options_.min_pnp_points) return false;
  // Drop the landmarks PnP found inconsistent (moving objects, bad tracks).
  std::vector<bool> is_inlier(ids.size(), false);
  for (int i : inliers) is_inlier[i] = true;
  std::vector<std::uint64_t> outliers;
  for (std::size_t i = 0; i < ids.size(); ++i)
    if (!is_inlier[i]) outliers.push_back(ids[i]);
  w_.fm.remove(outliers);
  cv::Rodrigues(rvec, R_cv);
  Eigen::Matrix3d R;
  Vector3d t;
  cv::cv2eigen(R_cv, R);
  cv::cv2eigen(tvec, t);
  Isometry3d T_c_w_new = Isometry3d::Identity();
  T_c_w_new.linear() = R;
  T_c_w_new.translation() = t;
  Isometry3d T_b_c = Isometry3d::Identity();
  T_b_c.linear() = rig_.T_b_c0.q_b_c.toRotationMatrix();
  T_b_c.translation() = rig_.T_b_c0.t_b_c;
  const Isometry3d T_w_b = T_c_w_new.inverse() * T_b_c.inverse();
  imu::NavState s = w_.frames[n].nav();
  s.p_w_b = T_w_b.translation();
  s.q_w_b = Quaterniond(T_w_b.linear()).normalized();
  w_.frames[n].setNav(s);
  return true;
}

bool Estimator::alignAndStart() {
  std::vector<Quaterniond> q;
  std::vector<const imu::Preintegration*> pre;
  for (int i = 0; i <= w_.count; ++i) {
    q.push_back(Quaterniond(w_.frames[i].T_w_b().linear()));
    pre.push_back(w_.frames[i].pre.get());
  }
  const Vector3d bg = solveGyroBias(q, pre);
  for (int i = 1; i <= w_.count; ++i) w_.frames[i].pre->repropagate(Vector3d::Zero(), bg);
  const Alignment a = alignVelocityGravity(w_.poses(), pre, noise_.g_norm);
  if (!a.ok) return false;
  std::vector<Vector3d> p;
  for (int i = 0; i <= w_.count; ++i) p.push_back(w_.frames[i].nav().p_w_b);
  startAligned(p, q, a, bg);
  return true;
}

void Estimator::startAligned(const std::vector<Vector3d>& p_w_b, const std::vector<Quaterniond>& q_w_b,
                             const Alignment& a, const Vector3d& bg) {
  const Quaterniond R0 = Quaterniond::FromTwoVectors(a.g_w, Vector3d::UnitZ());
  const bool from_last_good = biasesFromLastGood();
  for (int i = 0; i <= w_.count; ++i) {
    imu::NavState s = w_.frames[i].nav();
    s.p_w_b = R0 * p_w_b[i];
    s.q_w_b = (R0 * q_w_b[i]).normalized();
    s.v_w = R0 * a.v_w[i];
    s.bg = bg;
    s.ba = from_last_good ? seg_.last_good->ba : Vector3d::Zero();
    w_.frames[i].setNav(s);
  }
  if (from_last_good && (options_.reset_bias_prior_acc > 0 || options_.reset_bias_prior_gyr > 0)) {
    seg_.bias_anchor.emplace();
    *seg_.bias_anchor << seg_.last_good->ba, seg_.last_good->bg;
  }
  w_.initialized = true;
}

bool Estimator::initStepMono(FrameResult& r) {
  const int n = w_.count;
  // Until the structure is known the frames hold their IMU-predicted orientation only (an
  // unaligned prediction's position runs away).
  imu::NavState s = w_.frames[n].nav();
  s.p_w_b.setZero();
  s.v_w.setZero();
  w_.frames[n].setNav(s);
  if (n < kWindowSize) {
    r.status =
        "initializing (one camera): " + std::to_string(n + 1) + "/" + std::to_string(kWindowSize + 1) + " frames";
    return false;
  }
  std::vector<MonoTrack> tracks;
  for (const auto& [id, lm] : w_.fm.landmarks()) {
    if (lm.obs.size() < 2) continue;
    MonoTrack& t = tracks.emplace_back();
    t.start_frame = lm.start_frame;
    for (const auto& o : lm.obs) t.xy.push_back(o.xy);
  }
  std::string why;
  std::optional<MonoStructure> sfm = monocularStructure(tracks, n + 1, rig_.focal_px, MonoSfmOptions{}, why);
  if (sfm) {
    // Again with the rotations held to the gyroscope's (its bias from the first structure).
    const MonoRotationPrior prior = gyroRotations(*sfm);
    if (auto held = monocularStructure(tracks, n + 1, rig_.focal_px, MonoSfmOptions{}, why, &prior)) sfm = held;
  }
  if (!sfm || !alignMonoAndStart(*sfm)) {
    r.status = "initializing (one camera): " + (sfm ? std::string("IMU alignment failed") : why) + ", sliding";
    slide(r.keyframe);
    return false;
  }
  r.status = "initialized (one camera)";
  if (seg_.reanchor_pending) {
    r.biases_from_last_good = biasesFromLastGood();
    r.reanchored = reanchor();
  }
  return true;
}

bool Estimator::monoWindow(const MonoStructure& sfm, std::vector<Quaterniond>& q, std::vector<Vector3d>& p_c,
                           std::vector<const imu::Preintegration*>& pre) const {
  const Quaterniond q_c_b = rig_.T_b_c0.q_b_c.conjugate();
  for (int i = 0; i <= w_.count; ++i) {
    if (i > 0 && !w_.frames[i].pre) return false;
    q.push_back((Quaterniond(sfm.T_w_c[i].linear()) * q_c_b).normalized());
    p_c.push_back(sfm.T_w_c[i].translation());
    pre.push_back(w_.frames[i].pre.get());
  }
  return true;
}

MonoRotationPrior Estimator::gyroRotations(const MonoStructure& sfm) const {
  const Quaterniond q_c_b = rig_.T_b_c0.q_b_c.conjugate();
  std::vector<Quaterniond> q;
  std::vector<Vector3d> p_c;
  std::vector<const imu::Preintegration*> pre;
  if (!monoWindow(sfm, q, p_c, pre)) return {};
  const Vector3d bg = solveGyroBias(q, pre);
  MonoRotationPrior prior;
  prior.q_prev_c.resize(q.size(), Quaterniond::Identity());
  double var = 0;
  for (int i = 1; i <= w_.count; ++i) {
    prior.q_prev_c[i] = (q_c_b * pre[i]->correctedDeltaQ(bg) * rig_.T_b_c0.q_b_c).normalized();
    var = std::max(var, pre[i]->covariance().block<3, 3>(imu::kR, imu::kR).diagonal().maxCoeff());
  }
  prior.sigma_rad = std::sqrt(var);
  return prior;
}

bool Estimator::alignMonoAndStart(const MonoStructure& sfm) {
  std::vector<Quaterniond> q;
  std::vector<Vector3d> p_c;
  std::vector<const imu::Preintegration*> pre;
  if (!monoWindow(sfm, q, p_c, pre)) return false;
  const Vector3d bg = solveGyroBias(q, pre);
  for (int i = 1; i <= w_.count; ++i) w_.frames[i].pre->repropagate(Vector3d::Zero(), bg);
  const ScaledAlignment a = alignWithScale(q, p_c, rig_.T_b_c0.t_b_c, pre, noise_.g_norm);
  if (!a.ok || a.scale_sigma > kMonoMaxScaleSigma) return false;
  std::vector<Vector3d> p;
  for (int i = 0; i <= w_.count; ++i) p.push_back(a.scale * p_c[i] - q[i] * rig_.T_b_c0.t_b_c);
  startAligned(p, q, a, bg);
  // The landmarks from the metric poses.
  for (auto& [id, lm] : w_.fm.landmarks()) {
    lm.inv_depth = -1.0;
    lm.ray_estimated = false;
  }
  w_.fm.triangulate(w_.poses(), rig_);
  return true;
}

bool Estimator::calibrateRotation(FrameResult& r) {
  const int n = w_.count;
  if (n > 0 && w_.frames[n].pre) {
    std::vector<Vector2d> xy_a, xy_b;
    for (const auto& [id, lm] : w_.fm.landmarks()) {
      if (lm.start_frame > n - 1 || lm.endFrame() < n) continue;
      xy_a.push_back(lm.obs[static_cast<std::size_t>(n - 1 - lm.start_frame)].xy);
      xy_b.push_back(lm.obs[static_cast<std::size_t>(n - lm.start_frame)].xy);
    }
    if (const auto q_cam = relativeCameraRotation(xy_a, xy_b, rig_.focal_px))
      ex_.pairs.push_back({w_.frames[n].pre->deltaQ(), *q_cam});
  }
  const auto q_b_c = static_cast<int>(ex_.pairs.size()) >= kWindowSize ? handEyeRotation(ex_.pairs) : std::nullopt;
  if (!q_b_c) {
    r.status = "initializing: calibrating the camera-IMU rotation (" + std::to_string(ex_.pairs.size()) +
               " frame pairs; rotate the rig)";
    if (n >= kWindowSize) slide(true);
    return false;
  }
  // The hand–eye rotation replaces the config's; the window starts again with it.
  rig_.T_b_c0.q_b_c = *q_b_c;
  if (rig_.stereo) rig_.T_b_c1 = compose(rig_.T_b_c0, ex_.T_c0_c1);
  ex_.start = rig_.T_b_c0;
  setPose(rig_.T_b_c0.t_b_c, rig_.T_b_c0.q_b_c, ex_.block.data());
  ex_.rotation_known = true;
  ex_.pairs.clear();
  r.status = "initializing: camera-IMU rotation calibrated from the tracks, restarting";
  resetWindow();
  return false;
}

}  // namespace idyvins::backend
