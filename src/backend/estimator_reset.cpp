// Resets and re-anchoring (DESIGN §4.11): a failure empties the window; the next segment starts
// from the last good state (its biases when they had settled), moved onto it across the gap.

#include "backend/estimator.h"
#include "backend/gauge.h"

namespace idyvins::backend {

using Eigen::Isometry3d;
using Eigen::Quaterniond;
using Eigen::Vector2d;
using Eigen::Vector3d;

void Estimator::resetWindow() {
  w_.count = -1;
  w_.initialized = false;
  w_.fm.clear();
  w_.prior.reset();
  seg_.bias_anchor.reset();
  seg_.frames = 0;
  seg_.td_poses.clear();
  seg_.td_times.clear();
  for (auto& f : w_.frames) f.pre.reset();
}

void Estimator::resetAfterFailure() {
  resetWindow();
  seg_.reanchor_pending = seg_.last_good.has_value();
  w_.td_s = options_.td_s;  // a failure may come from a wrong offset: start again from the config's
  seg_.td_restarted = false;
}

bool Estimator::biasesFromLastGood() const { return seg_.reanchor_pending && seg_.last_good && seg_.last_good_settled; }

std::string Estimator::reanchor() {
  seg_.reanchor_pending = false;
  const TimeNs t_end = w_.frames[0].t_ns, max_gap = static_cast<TimeNs>(options_.max_imu_gap_s * 1e9);
  imu::NavState s = *seg_.last_good;
  bool held = false, extrapolated = false;
  // Integrate over the runs of samples without a gap; across a gap the state is held.
  TimeNs t = seg_.last_good_t_ns;
  const std::size_t n = w_.imu.size();
  std::size_t k = static_cast<std::size_t>(
      std::upper_bound(w_.imu.begin(), w_.imu.end(), t, [](TimeNs x, const ImuSample& a) { return x < a.t_ns; }) -
      w_.imu.begin());
  if (k == 0) {  // no sample at or before the last good state: held up to the first one
    held = true;
    if (n == 0)
      k = n;
    else
      t = std::min(t_end, w_.imu[0].t_ns);
  } else {
    --k;  // the last sample at or before t
  }
  while (t < t_end && k < n) {
    std::size_t j = k;  // the run of samples without a gap from k on
    while (j + 1 < n && w_.imu[j + 1].t_ns - w_.imu[j].t_ns <= max_gap && w_.imu[j].t_ns < t_end) ++j;
    const TimeNs to = std::min(t_end, w_.imu[j].t_ns);
    if (to > t) s = imu::integrateBetween(w_.imu, t, to, s.ba, s.bg, noise_).predict(s);
    t = to;
    if (t >= t_end) break;
    k = j + 1;  // a gap after sample j, or no samples after it
    if (k >= n) break;
    const TimeNs gap_end = std::min(t_end, w_.imu[k].t_ns);
    // A dropout no longer than max_frame_gap: the body went on at its velocity. Longer (a time
    // jump, a stop): held.
    if (gap_end - t <= static_cast<TimeNs>(options_.max_frame_gap_s * 1e9)) {
      s.p_w_b += s.v_w * (1e-9 * static_cast<double>(gap_end - t));
      extrapolated = true;
    } else {
      held = true;
    }
    t = gap_end;
  }
  if (t < t_end) held = true;
  Isometry3d T_pred = Isometry3d::Identity();
  T_pred.linear() = s.q_w_b.toRotationMatrix();
  T_pred.translation() = s.p_w_b;
  restoreGauge(T_pred);  // the window moved (yaw and position) so that its oldest frame is there
  return held ? "held" : extrapolated ? "extrapolated" : "imu";
}
}  // namespace idyvins::backend
