// The estimator's frame step: a new frame into the window (integration from the previous one,
// the feature manager's landmarks), initialization or triangulation, the solve, post-processing
// and the failure test, the slide. The other rooms: estimator_init.cpp (initialization),
// estimator_solve.cpp (the window's solve), estimator_post.cpp (post-processing, outliers,
// static map), estimator_reset.cpp (resets and re-anchoring), estimator_marginalize.cpp.

#include "backend/estimator.h"

#include <algorithm>
#include <chrono>
#include <utility>

#include "backend/parameter_blocks.h"

namespace idyvins::backend {

using Eigen::Isometry3d;
using Eigen::Quaterniond;
using Eigen::Vector2d;
using Eigen::Vector3d;

namespace {
Extrinsic toExtrinsic(const Isometry3d& T) {
  Extrinsic e;
  e.q_b_c = Quaterniond(T.linear()).normalized();
  e.t_b_c = T.translation();
  return e;
}
}  // namespace

Estimator::Estimator(const camera::Rig& cameras, const ImuNoise& noise, const EstimatorOptions& options)
    : options_(options) {
  rig_.T_b_c0 = toExtrinsic(cameras.T_b_c[0]);
  rig_.stereo = cameras.stereo();
  if (rig_.stereo) rig_.T_b_c1 = toExtrinsic(cameras.T_b_c[1]);
  const auto f = camera::pixelsPerNormalized(cameras.cams[0]);
  rig_.focal_px = 0.5 * (f[0] + f[1]);
  rig_.fx = f[0];
  rig_.fy = f[1];
  noise_ = noise;
  w_.td_s = options.td_s;
  ex_.start = rig_.T_b_c0;
  if (rig_.stereo) ex_.T_c0_c1 = relative(rig_.T_b_c0, rig_.T_b_c1);
  ex_.rotation_known = options.estimate_extrinsic != 2;
  setPose(rig_.T_b_c0.t_b_c, rig_.T_b_c0.q_b_c, ex_.block.data());
}

void Estimator::addImu(const ImuSample& s) {
  if (!w_.imu.empty() && s.t_ns <= w_.imu.back().t_ns) return;
  w_.imu.push_back(s);
}

LatestState Estimator::latest() const {
  LatestState l;
  if (!w_.initialized || w_.count < 0) return l;
  l.valid = true;
  l.t_ns = w_.frames[w_.count].t_ns;
  l.state = w_.frames[w_.count].nav();
  l.td_s = w_.td_s;
  return l;
}

std::string Estimator::bridgeProblem(TimeNs t1, bool& imu_only) const {
  const TimeNs t0 = w_.frames[w_.count].t_ns;
  char text[120];
  imu_only = false;
  if (t1 - t0 > static_cast<TimeNs>(options_.max_frame_gap_s * 1e9)) {
    std::snprintf(text, sizeof(text), "no frame for %.3f s (max_frame_gap %.3f s)", 1e-9 * (t1 - t0),
                  options_.max_frame_gap_s);
    return text;
  }
  imu_only = true;
  if (!options_.use_imu) return "";  // stereo alone: only the frame gap matters
  if (w_.imu.empty() || w_.imu.front().t_ns > t0 || w_.imu.back().t_ns < t1) return "no IMU data between frames";
  // The samples the integration uses: the last one at or before t0 to the first at or after t1.
  auto it = std::upper_bound(w_.imu.begin(), w_.imu.end(), t0, [](TimeNs t, const ImuSample& s) { return t < s.t_ns; });
  if (it != w_.imu.begin()) --it;
  TimeNs largest = 0;
  for (; it + 1 != w_.imu.end() && it->t_ns < t1; ++it) largest = std::max(largest, (it + 1)->t_ns - it->t_ns);
  if (largest > static_cast<TimeNs>(options_.max_imu_gap_s * 1e9)) {
    std::snprintf(text, sizeof(text), "IMU gap of %.3f s (max_imu_gap %.3f s)", 1e-9 * largest, options_.max_imu_gap_s);
    return text;
  }
  return "";
}

std::unique_ptr<imu::Preintegration> Estimator::integrate(TimeNs t0, TimeNs t1, const imu::NavState& from) const {
  if (w_.imu.empty() || w_.imu.front().t_ns > t0 || w_.imu.back().t_ns < t1) return nullptr;
  return std::make_unique<imu::Preintegration>(imu::integrateBetween(w_.imu, t0, t1, from.ba, from.bg, noise_));
}

bool Estimator::pushFrame(const frontend::FeatureFrame& ff, bool without_imu) {
  const int n = w_.count + 1;
  WindowFrame& f = w_.frames[n];
  f.t_ns = ff.t_ns;
  if (n == 0) {
    f.setNav(imu::NavState{});
    f.pre.reset();
  } else if (without_imu) {  // no IMU factor: at constant velocity from the previous frame
    imu::NavState s = w_.frames[n - 1].nav();
    s.p_w_b += s.v_w * (1e-9 * static_cast<double>(ff.t_ns - w_.frames[n - 1].t_ns));
    f.pre.reset();
    f.setNav(s);
  } else {
    const imu::NavState prev = w_.frames[n - 1].nav();
    f.pre = integrate(w_.frames[n - 1].t_ns, ff.t_ns, prev);
    f.setNav(f.pre->predict(prev));
  }
  w_.count = n;
  return w_.fm.addFrame(n, ff, options_.keyframe_parallax_px, rig_.focal_px, map_.dynamic_ids);
}

void Estimator::startFromPnp() {
  // imu: 0: the new frame starts from PnP against the window's landmarks, unless PnP lands far
  // from the constant-velocity prediction (a few bad landmarks, a moving object): then from it.
  const int n = w_.count;
  const imu::NavState predicted = w_.frames[n].nav();
  if (!pnp(n)) return;
  const double dt = 1e-9 * static_cast<double>(w_.frames[n].t_ns - w_.frames[n - 1].t_ns);
  const double allowed = std::max(0.5, 3.0 * predicted.v_w.norm() * dt);
  if ((w_.frames[n].nav().p_w_b - predicted.p_w_b).norm() > allowed) w_.frames[n].setNav(predicted);
}

FrameResult Estimator::addFrame(const frontend::FeatureFrame& ff) {
  FrameResult r;
  r.t_ns = ff.t_ns;
  r.td_s = w_.td_s;
  if (w_.count >= 0 && ff.t_ns <= w_.frames[w_.count].t_ns) {
    r.status = "skipped: time stamp not after the previous frame";
    return r;
  }
  // A gap the integration cannot bridge ends the segment: this frame starts a new window; an IMU
  // gap on an initialized stereo rig is carried by the stereo factors (bridge_imu_gaps).
  bool imu_only = false, without_imu = !options_.use_imu && w_.count >= 0;
  if (const std::string why = w_.count >= 0 ? bridgeProblem(ff.t_ns, imu_only) : std::string(); !why.empty()) {
    if (imu_only && w_.initialized && rig_.stereo && options_.bridge_imu_gaps) {
      without_imu = true;
      r.stereo_only = why;
    } else {
      r.reset = w_.initialized;
      r.reset_why = why;
      if (w_.initialized)
        resetAfterFailure();
      else
        resetWindow();
    }
  }
  r.keyframe = pushFrame(ff, without_imu);
  if (without_imu && !options_.use_imu && w_.initialized) startFromPnp();

  if (!w_.initialized) {
    if (!initStep(r)) return r;
  } else {
    w_.fm.triangulate(w_.poses(), rig_);
  }
  optimize(r);
  if (options_.post_process) postProcess(r);
  removeOutliers(r);
  w_.fm.removeFailures();
  std::string why;
  if (failureDetected(why)) {
    r.reset = true;
    r.reset_why = why;
    r.status = "reset: " + why;
    resetAfterFailure();
    return r;
  }
  r.initialized = true;
  if (r.status.empty())
    r.status = r.stereo_only.empty() || !options_.use_imu ? "tracking" : "tracking on stereo alone: " + r.stereo_only;
  r.state = w_.frames[w_.count].nav();
  r.td_s = w_.td_s;
  if (options_.estimate_extrinsic != 0) r.extrinsic = extrinsicEstimate();
  seg_.last_good = r.state;
  seg_.last_good_t_ns = ff.t_ns;
  seg_.last_good_settled = ++seg_.frames >= kSettledFrames;
  const auto slide_start = std::chrono::steady_clock::now();
  slide(r.keyframe);
  r.left_window = std::exchange(leaving_, std::nullopt);
  r.marginalization_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - slide_start).count();
  return r;
}

bool Estimator::failureDetected(std::string& why) const {
  const imu::NavState s = w_.frames[w_.count].nav();
  if (s.ba.norm() > 2.5) {
    why = "accelerometer bias estimate too large (" + std::to_string(s.ba.norm()) + " m/s^2)";
    return true;
  }
  if (s.bg.norm() > 1.0) {
    why = "gyroscope bias estimate too large";
    return true;
  }
  if (w_.count > 0) {
    const imu::NavState p = w_.frames[w_.count - 1].nav();
    if ((s.p_w_b - p.p_w_b).norm() > 5.0) {
      why = "position jump between frames";
      return true;
    }
    if (s.q_w_b.angularDistance(p.q_w_b) > 50.0 * M_PI / 180) {
      why = "rotation jump between frames";
      return true;
    }
  }
  if (w_.fm.trackedIn(w_.count) < 2) {
    why = "too few tracked landmarks";
    return true;
  }
  return false;
}
}  // namespace idyvins::backend
