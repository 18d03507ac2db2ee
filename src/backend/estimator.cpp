#include "backend/estimator.h"

#include <ceres/ceres.h>

#include <chrono>
#include <deque>
#include <functional>
#include <optional>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>
#include <unordered_map>
#include <utility>

#include "backend/gauge.h"
#include "backend/imu_factor.h"
#include "backend/initializer.h"
#include "backend/parameter_blocks.h"
#include "core/so3.h"
#include "dynamic/dynamic.h"

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

/// One projection factor of a landmark; its blocks are (pose of the anchor frame, pose of
/// `frame`, inverse depth) or, for the stereo factor within the anchor frame (frame −1),
/// the inverse depth alone; a factor with the time offset adds the td block last.
struct LandmarkFactor {
  std::shared_ptr<ceres::CostFunction> cost;
  int frame;  ///< -1 for the one-frame stereo factor
};

/// How a landmark's factors treat the time offset.
struct TdUse {
  bool block = false;  ///< each factor carries the td block
  /// Without the block: observations moved to this offset (the current estimate) when
  /// estimating, so the factors hold no information on td; nullopt: observations as they are.
  std::optional<double> moved_to;
};

/// The factors of a landmark whose anchor ray is estimated (block: ray x, y, inverse depth):
/// the anchor observation is a residual like the others.
std::vector<LandmarkFactor> rayLandmarkFactors(const Landmark& lm, const Rig& rig, const ProjectionWeight& w_static,
                                               const std::map<int, const double*>& scale_of_frame) {
  std::vector<LandmarkFactor> out{{std::make_shared<AnchorRayObservation>(lm.obs.front().xy, w_static), -1}};
  for (std::size_t k = 0; k < lm.obs.size(); ++k) {
    const Observation& o = lm.obs[k];
    const int frame = lm.start_frame + static_cast<int>(k);
    ProjectionWeight w = w_static;
    const auto it = scale_of_frame.find(frame);
    if (it != scale_of_frame.end()) w.info_scale = it->second;
    if (k > 0) out.push_back({std::make_shared<ProjectionTwoFrameRay>(o.xy, rig.T_b_c0, rig.T_b_c0, w), frame});
    if (!rig.stereo || !o.has_right) continue;
    if (k > 0)
      out.push_back({std::make_shared<ProjectionTwoFrameRay>(o.xy_right, rig.T_b_c0, rig.T_b_c1, w), frame});
    else
      out.push_back({std::make_shared<ProjectionOneFrameTwoCamRay>(o.xy_right, rig.T_b_c0, rig.T_b_c1, w_static), -1});
  }
  return out;
}

/// The projection factors of one landmark; with `ray`, those of its estimated-ray form.
std::vector<LandmarkFactor> landmarkFactors(const Landmark& lm, const Rig& rig, const ProjectionWeight& w_static,
                                            const TdUse& td, const std::map<int, const double*>& scale_of_frame = {},
                                            bool ray = false) {
  if (ray) return rayLandmarkFactors(lm, rig, w_static, scale_of_frame);
  std::vector<LandmarkFactor> out;
  const Observation& a = lm.obs.front();
  auto at = [&](const TimedObservation& o) -> Vector2d {
    return td.moved_to ? Vector2d(o.xy - (*td.moved_to - o.td_obs) * o.velocity) : o.xy;
  };
  const TimedObservation a_left = TimedObservation{a.xy, a.velocity, a.td_s};
  auto twoFrame = [&](const TimedObservation& target, const Extrinsic& cam, const ProjectionWeight& w)
      -> std::shared_ptr<ceres::CostFunction> {
    if (td.block) return std::make_shared<ProjectionTwoFrameTd>(a_left, target, rig.T_b_c0, cam, w);
    return std::make_shared<ProjectionTwoFrame>(at(a_left), at(target), rig.T_b_c0, cam, w);
  };
  for (std::size_t k = 0; k < lm.obs.size(); ++k) {
    const Observation& o = lm.obs[k];
    const int frame = lm.start_frame + static_cast<int>(k);
    ProjectionWeight w = w_static;  // stereo factors within one frame keep the static weight
    const auto it = scale_of_frame.find(frame);
    if (it != scale_of_frame.end()) w.info_scale = it->second;
    if (k > 0) out.push_back({twoFrame(TimedObservation{o.xy, o.velocity, o.td_s}, rig.T_b_c0, w), frame});
    if (!rig.stereo || !o.has_right) continue;
    const TimedObservation right = TimedObservation{o.xy_right, o.velocity_right, o.td_s};
    if (k > 0) {
      out.push_back({twoFrame(right, rig.T_b_c1, w), frame});
    } else if (td.block) {
      out.push_back({std::make_shared<ProjectionOneFrameTwoCamTd>(a_left, right, rig.T_b_c0, rig.T_b_c1, w_static), -1});
    } else {
      out.push_back(
          {std::make_shared<ProjectionOneFrameTwoCam>(at(a_left), at(right), rig.T_b_c0, rig.T_b_c1, w_static), -1});
    }
  }
  return out;
}

/// A landmark the window's solve uses (addProjections; storeRays reads back the same set).
bool inSolve(const Landmark& lm) { return lm.usable() && std::isfinite(lm.inv_depth); }

const PoseManifold kPoseManifold;
}  // namespace

Isometry3d Estimator::Frame::T_w_b() const {
  Isometry3d T = Isometry3d::Identity();
  T.linear() = Eigen::Map<const Quaterniond>(pose.data() + 3).normalized().toRotationMatrix();
  T.translation() = Eigen::Map<const Vector3d>(pose.data());
  return T;
}

imu::NavState Estimator::Frame::nav() const { return navStateFromBlocks(pose.data(), sb.data()); }

void Estimator::Frame::setNav(const imu::NavState& s) {
  setPose(s.p_w_b, s.q_w_b, pose.data());
  Eigen::Map<Eigen::Matrix<double, 9, 1>> v(sb.data());
  v << s.v_w, s.ba, s.bg;
}

Estimator::Estimator(const camera::Rig& cameras, const ImuNoise& noise, const EstimatorOptions& options)
    : options_(options) {
  rig_.T_b_c0 = toExtrinsic(cameras.T_b_c[0]);
  rig_.stereo = cameras.stereo();
  if (rig_.stereo) rig_.T_b_c1 = toExtrinsic(cameras.T_b_c[1]);
  rig_.focal_px = 0.5 * (cameras.cams[0].fx + cameras.cams[0].fy);
  const bool fisheye = cameras.cams[0].type == camera::ModelType::kKannalaBrandt;
  rig_.fx = fisheye ? rig_.focal_px : cameras.cams[0].fx;
  rig_.fy = fisheye ? rig_.focal_px : cameras.cams[0].fy;
  noise_ = noise;
  td_s_ = options.td_s;
}

void Estimator::addImu(const ImuSample& s) {
  if (!imu_.empty() && s.t_ns <= imu_.back().t_ns) return;
  imu_.push_back(s);
}

LatestState Estimator::latest() const {
  LatestState l;
  if (!initialized_ || count_ < 0) return l;
  l.valid = true;
  l.t_ns = frames_[count_].t_ns;
  l.state = frames_[count_].nav();
  l.td_s = td_s_;
  return l;
}

void Estimator::resetWindow() {
  count_ = -1;
  initialized_ = false;
  fm_.clear();
  prior_.reset();
  bias_anchor_.reset();
  segment_frames_ = 0;
  for (auto& f : frames_) f.pre.reset();
}

void Estimator::resetAfterFailure() {
  resetWindow();
  reanchor_pending_ = last_good_.has_value();
  td_s_ = options_.td_s;  // a failure may come from a wrong offset: start again from the config's
  td_restarted_ = false;
}

std::string Estimator::bridgeProblem(TimeNs t1) const {
  const TimeNs t0 = frames_[count_].t_ns;
  char text[120];
  if (t1 - t0 > static_cast<TimeNs>(options_.max_frame_gap_s * 1e9)) {
    std::snprintf(text, sizeof(text), "no frame for %.3f s (max_frame_gap %.3f s)", 1e-9 * (t1 - t0),
                  options_.max_frame_gap_s);
    return text;
  }
  if (imu_.empty() || imu_.front().t_ns > t0 || imu_.back().t_ns < t1) return "no IMU data between frames";
  // The samples the integration uses: the last one at or before t0 to the first at or after t1.
  auto it = std::upper_bound(imu_.begin(), imu_.end(), t0, [](TimeNs t, const ImuSample& s) { return t < s.t_ns; });
  if (it != imu_.begin()) --it;
  TimeNs largest = 0;
  for (; it + 1 != imu_.end() && it->t_ns < t1; ++it) largest = std::max(largest, (it + 1)->t_ns - it->t_ns);
  if (largest > static_cast<TimeNs>(options_.max_imu_gap_s * 1e9)) {
    std::snprintf(text, sizeof(text), "IMU gap of %.3f s (max_imu_gap %.3f s)", 1e-9 * largest, options_.max_imu_gap_s);
    return text;
  }
  return "";
}

std::unique_ptr<imu::Preintegration> Estimator::integrate(TimeNs t0, TimeNs t1, const imu::NavState& from) const {
  if (imu_.empty() || imu_.front().t_ns > t0 || imu_.back().t_ns < t1) return nullptr;
  return std::make_unique<imu::Preintegration>(imu::integrateBetween(imu_, t0, t1, from.ba, from.bg, noise_));
}

std::vector<Isometry3d> Estimator::windowPoses() const {
  std::vector<Isometry3d> T;
  for (int i = 0; i <= count_; ++i) T.push_back(frames_[i].T_w_b());
  return T;
}

FrameResult Estimator::addFrame(const frontend::FeatureFrame& ff) {
  FrameResult r;
  r.t_ns = ff.t_ns;
  r.td_s = td_s_;
  if (count_ >= 0 && ff.t_ns <= frames_[count_].t_ns) {
    r.status = "skipped: time stamp not after the previous frame";
    return r;
  }
  // A gap the integration cannot bridge ends the segment: this frame starts a new window.
  if (const std::string why = count_ >= 0 ? bridgeProblem(ff.t_ns) : std::string(); !why.empty()) {
    r.reset = initialized_;
    r.reset_why = why;
    if (initialized_) resetAfterFailure(); else resetWindow();
  }
  const int n = count_ + 1;
  Frame& f = frames_[n];
  f.t_ns = ff.t_ns;
  if (n == 0) {
    f.setNav(imu::NavState{});
    f.pre.reset();
  } else {
    const imu::NavState prev = frames_[n - 1].nav();
    f.pre = integrate(frames_[n - 1].t_ns, ff.t_ns, prev);
    f.setNav(f.pre->predict(prev));
  }
  count_ = n;
  r.keyframe = fm_.addFrame(n, ff, options_.keyframe_parallax_px, rig_.focal_px, dynamic_ids_);

  if (!initialized_) {
    if (!initStep(r)) return r;
  } else {
    fm_.triangulate(windowPoses(), rig_);
  }
  optimize(r);
  if (options_.post_process) postProcess(r);
  removeOutliers(r);
  fm_.removeFailures();
  std::string why;
  if (failureDetected(why)) {
    r.reset = true;
    r.reset_why = why;
    r.status = "reset: " + why;
    resetAfterFailure();
    return r;
  }
  r.initialized = true;
  if (r.status.empty()) r.status = "tracking";
  r.state = frames_[count_].nav();
  r.td_s = td_s_;
  last_T_w_b_ = frames_[count_].T_w_b();
  last_good_ = r.state;
  last_good_t_ns_ = ff.t_ns;
  last_good_settled_ = ++segment_frames_ >= kSettledFrames;
  const auto slide_start = std::chrono::steady_clock::now();
  slide(r.keyframe);
  r.left_window = std::exchange(leaving_, std::nullopt);
  r.marginalization_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - slide_start).count();
  return r;
}

bool Estimator::initStep(FrameResult& r) {
  const int n = count_;
  if (n > 0) {
    if (!pnp(n)) {
      r.status = "initializing: PnP failed, restarting";
      resetWindow();
      return false;
    }
    // Check the visual rotation against the gyroscope before accepting the frame.
    const Quaterniond q_vis = Quaterniond(frames_[n - 1].T_w_b().linear()).conjugate() *
                              Quaterniond(frames_[n].T_w_b().linear());
    const double diff_deg = q_vis.angularDistance(frames_[n].pre->deltaQ()) * 180.0 / M_PI;
    if (diff_deg > options_.init_rotation_check_deg) {
      r.status = "initializing: PnP rotation disagrees with the gyroscope, restarting";
      resetWindow();
      return false;
    }
  }
  fm_.triangulate(windowPoses(), rig_);
  if (n < kWindowSize) {
    r.status = "initializing: " + std::to_string(n + 1) + "/" + std::to_string(kWindowSize + 1) + " frames";
    return false;
  }
  if (estimatesTd() && !td_restarted_ && alignTimeOffset(r)) return false;
  if (!alignAndStart()) {
    r.status = "initializing: gravity/velocity alignment failed, sliding";
    slide(true);
    return false;
  }
  r.status = "initialized";
  if (reanchor_pending_) {
    r.biases_from_last_good = biasesFromLastGood();  // as alignAndStart decided
    r.reanchored = reanchor();
  }
  return true;
}

std::string Estimator::reanchor() {
  reanchor_pending_ = false;
  const TimeNs t_end = frames_[0].t_ns, max_gap = static_cast<TimeNs>(options_.max_imu_gap_s * 1e9);
  imu::NavState s = *last_good_;
  bool held = false, extrapolated = false;
  // Integrate over the runs of samples without a gap; across a gap the state is held.
  TimeNs t = last_good_t_ns_;
  const std::size_t n = imu_.size();
  std::size_t k = static_cast<std::size_t>(
      std::upper_bound(imu_.begin(), imu_.end(), t, [](TimeNs x, const ImuSample& a) { return x < a.t_ns; }) -
      imu_.begin());
  if (k == 0) {  // no sample at or before the last good state: held up to the first one
    held = true;
    if (n == 0) k = n;
    else t = std::min(t_end, imu_[0].t_ns);
  } else {
    --k;  // the last sample at or before t
  }
  while (t < t_end && k < n) {
    std::size_t j = k;  // the run of samples without a gap from k on
    while (j + 1 < n && imu_[j + 1].t_ns - imu_[j].t_ns <= max_gap && imu_[j].t_ns < t_end) ++j;
    const TimeNs to = std::min(t_end, imu_[j].t_ns);
    if (to > t) s = imu::integrateBetween(imu_, t, to, s.ba, s.bg, noise_).predict(s);
    t = to;
    if (t >= t_end) break;
    k = j + 1;  // a gap after sample j, or no samples after it
    if (k >= n) break;
    const TimeNs gap_end = std::min(t_end, imu_[k].t_ns);
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
  const Isometry3d T_corr = gaugeCorrection(T_pred, frames_[0].T_w_b());
  const Quaterniond q_corr(T_corr.linear());
  for (int k = 0; k <= count_; ++k) {
    imu::NavState f = frames_[k].nav();
    f.p_w_b = T_corr * f.p_w_b;
    f.q_w_b = (q_corr * f.q_w_b).normalized();
    f.v_w = q_corr * f.v_w;
    frames_[k].setNav(f);
  }
  return held ? "held" : extrapolated ? "extrapolated" : "imu";
}

bool Estimator::alignTimeOffset(FrameResult& r) {
  std::vector<Quaterniond> q;
  std::vector<TimeNs> t;
  for (int i = 0; i <= count_; ++i) {
    q.push_back(Quaterniond(frames_[i].T_w_b().linear()));
    t.push_back(frames_[i].t_ns);
  }
  const std::optional<double> shift = alignRotationTimes(q, t, imu_, kTdInitSearchS);
  if (!shift || std::abs(*shift) < kTdInitRestartS) return false;
  // Moving the window's observations by the shift starts its solve far from where PnP put
  // the poses (a shift of all poses along the motion is nearly free for the IMU factors and
  // the solver crawls along it): start again with frames stamped with the new offset.
  td_s_ += *shift;
  td_restarted_ = true;
  resetWindow();
  r.status = "initializing: time offset " + std::to_string(1e3 * td_s_) + " ms from the rotations, restarting";
  return true;
}

bool Estimator::pnp(int n) {
  std::vector<cv::Point3d> obj;
  std::vector<cv::Point2d> img;
  std::vector<std::uint64_t> ids;
  for (const auto& [id, lm] : fm_.landmarks()) {
    if (lm.inv_depth <= 0 || lm.start_frame >= n || lm.endFrame() != n) continue;
    const Vector3d p_w = cameraPose(frames_[lm.start_frame].T_w_b(), rig_.T_b_c0) * lm.anchorPoint();
    obj.emplace_back(p_w.x(), p_w.y(), p_w.z());
    img.emplace_back(lm.obs.back().xy.x(), lm.obs.back().xy.y());
    ids.push_back(id);
  }
  if (static_cast<int>(obj.size()) < options_.min_pnp_points) return false;
  // Initial guess: the previous camera pose.
  const Isometry3d T_c_w = cameraPose(frames_[n - 1].T_w_b(), rig_.T_b_c0).inverse();
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
  fm_.remove(outliers);
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
  imu::NavState s = frames_[n].nav();
  s.p_w_b = T_w_b.translation();
  s.q_w_b = Quaterniond(T_w_b.linear()).normalized();
  frames_[n].setNav(s);
  return true;
}

bool Estimator::alignAndStart() {
  std::vector<Quaterniond> q;
  std::vector<const imu::Preintegration*> pre;
  for (int i = 0; i <= count_; ++i) {
    q.push_back(Quaterniond(frames_[i].T_w_b().linear()));
    pre.push_back(frames_[i].pre.get());
  }
  const Vector3d bg = solveGyroBias(q, pre);
  for (int i = 1; i <= count_; ++i) frames_[i].pre->repropagate(Vector3d::Zero(), bg);
  const Alignment a = alignVelocityGravity(windowPoses(), pre, noise_.g_norm);
  if (!a.ok) return false;
  const Quaterniond R0 = Quaterniond::FromTwoVectors(a.g_w, Vector3d::UnitZ());
  const bool from_last_good = biasesFromLastGood();
  for (int i = 0; i <= count_; ++i) {
    imu::NavState s = frames_[i].nav();
    s.p_w_b = R0 * s.p_w_b;
    s.q_w_b = (R0 * s.q_w_b).normalized();
    s.v_w = R0 * a.v_w[i];
    s.bg = bg;
    s.ba = from_last_good ? last_good_->ba : Vector3d::Zero();
    frames_[i].setNav(s);
  }
  if (from_last_good && (options_.reset_bias_prior_acc > 0 || options_.reset_bias_prior_gyr > 0)) {
    bias_anchor_.emplace();
    *bias_anchor_ << last_good_->ba, last_good_->bg;
  }
  initialized_ = true;
  return true;
}

bool Estimator::biasesFromLastGood() const { return reanchor_pending_ && last_good_ && last_good_settled_; }

void Estimator::optimize(FrameResult& r) {
  const auto start = std::chrono::steady_clock::now();
  ceres::Problem problem(borrowingProblemOptions());
  std::vector<std::shared_ptr<ceres::CostFunction>> costs;  // owned here, borrowed by the problem
  ceres::HuberLoss huber(options_.huber_px);
  r.skipped_blocks = addStateAndImu(problem, costs);
  // Candidate weights 1/m_j (DESIGN §4.5): one value per (landmark, frame), owned here,
  // pointed to by the factors and refreshed by the iteration callback below.
  std::deque<CandidateWeight> weights;
  r.landmarks = addProjections(problem, costs, huber, weights, r.candidates);
  // The offset is observable only in motion: held while the oldest frame is slow (as VINS-Fusion).
  if (estimatesTd() && problem.HasParameterBlock(&td_s_) && frames_[0].nav().v_w.norm() < kMinSpeedForTd)
    problem.SetParameterBlockConstant(&td_s_);
  refreshWeights(weights);
  struct Refresh : ceres::IterationCallback {
    std::function<void()> f;
    ceres::CallbackReturnType operator()(const ceres::IterationSummary&) override {
      f();
      return ceres::SOLVER_CONTINUE;
    }
  } callback;
  callback.f = [&] { refreshWeights(weights); };
  ceres::Solver::Options o;
  if (!weights.empty()) {
    o.callbacks.push_back(&callback);
    o.update_state_every_iteration = true;  // the callback reads the current poses
  }
  o.linear_solver_type = ceres::DENSE_SCHUR;
  o.trust_region_strategy_type = ceres::DOGLEG;
  o.max_num_iterations = options_.max_num_iterations;
  o.function_tolerance = options_.function_tolerance;
  if (options_.time_limited) o.max_solver_time_in_seconds = options_.max_solver_time_s;  // live only
  o.num_threads = 1;  // deterministic
  const Isometry3d T_w_b0_before = frames_[0].T_w_b();
  const auto solve_start = std::chrono::steady_clock::now();
  ceres::Solver::Summary summary;
  ceres::Solve(o, &problem, &summary);
  const auto post_start = std::chrono::steady_clock::now();
  if (estimatesRays()) storeRays();
  if (options_.fix_gauge) restoreGauge(T_w_b0_before);
  for (int i = 1; i <= count_; ++i) {
    const imu::NavState s = frames_[i - 1].nav();
    if (frames_[i].pre->needsRepropagation(s.ba, s.bg)) frames_[i].pre->repropagate(s.ba, s.bg);
  }
  const auto end = std::chrono::steady_clock::now();
  using Ms = std::chrono::duration<double, std::milli>;
  r.optimization_ms = Ms(end - start).count();
  SolveProfile& p = r.solve;
  p.build_ms = Ms(solve_start - start).count();
  p.post_ms = Ms(end - post_start).count();
  p.preprocess_ms = 1e3 * summary.preprocessor_time_in_seconds;
  p.residual_ms = 1e3 * summary.residual_evaluation_time_in_seconds;
  p.jacobian_ms = 1e3 * summary.jacobian_evaluation_time_in_seconds;
  p.linear_solver_ms = 1e3 * summary.linear_solver_time_in_seconds;
  p.minimizer_ms = 1e3 * summary.minimizer_time_in_seconds;
  p.iterations = summary.num_successful_steps + summary.num_unsuccessful_steps;
  p.converged = summary.termination_type == ceres::CONVERGENCE;
}

bool Estimator::finiteAt(const ceres::CostFunction& cost, const std::vector<double*>& blocks) {
  std::vector<double> residuals(static_cast<std::size_t>(cost.num_residuals()));
  if (!cost.Evaluate(blocks.data(), residuals.data(), nullptr)) return false;
  for (double x : residuals)
    if (!std::isfinite(x)) return false;
  return true;
}

int Estimator::addStateAndImu(ceres::Problem& problem, std::vector<std::shared_ptr<ceres::CostFunction>>& costs) {
  int skipped = 0;
  for (int i = 0; i <= count_; ++i) {
    problem.AddParameterBlock(frames_[i].pose.data(), 7, const_cast<PoseManifold*>(&kPoseManifold));
    problem.AddParameterBlock(frames_[i].sb.data(), 9);
  }
  // Every block is evaluated once before it enters the problem: one that is not finite at
  // the start values (a degenerate integration, a prior gone bad) is left out and counted.
  if (prior_) {
    costs.push_back(std::make_shared<MarginalizationFactor>(prior_));
    if (finiteAt(*costs.back(), prior_->blocks))
      problem.AddResidualBlock(costs.back().get(), nullptr, prior_->blocks);
    else
      ++skipped;
  }
  addBiasAnchor(problem, costs);
  for (int i = 1; i <= count_; ++i) {
    if (frames_[i].pre->sumDt() > 10.0) continue;
    costs.push_back(std::make_shared<ImuFactor>(frames_[i].pre.get()));
    const std::vector<double*> blocks{frames_[i - 1].pose.data(), frames_[i - 1].sb.data(), frames_[i].pose.data(),
                                      frames_[i].sb.data()};
    if (finiteAt(*costs.back(), blocks))
      problem.AddResidualBlock(costs.back().get(), nullptr, blocks);
    else
      ++skipped;
  }
  return skipped;
}

void Estimator::addBiasAnchor(ceres::Problem& problem, std::vector<std::shared_ptr<ceres::CostFunction>>& costs) {
  if (prior_) bias_anchor_.reset();  // the window has its own prior now
  if (!bias_anchor_) return;
  costs.push_back(std::make_shared<BiasPriorFactor>(bias_anchor_->head<3>(), bias_anchor_->tail<3>(),
                                                    options_.reset_bias_prior_acc, options_.reset_bias_prior_gyr));
  problem.AddResidualBlock(costs.back().get(), nullptr, frames_[0].sb.data());
}

std::vector<double*> Estimator::factorBlocks(Landmark& lm, int frame, bool with_td) {
  std::vector<double*> blocks;
  if (frame >= 0) blocks = {frames_[lm.start_frame].pose.data(), frames_[frame].pose.data()};
  if (estimatesRays()) {
    lm.ray_block = {lm.anchorRay().x(), lm.anchorRay().y(), lm.inv_depth};
    blocks.push_back(lm.ray_block.data());
  } else {
    blocks.push_back(&lm.inv_depth);
  }
  if (with_td) blocks.push_back(&td_s_);
  return blocks;
}

int Estimator::addProjections(ceres::Problem& problem, std::vector<std::shared_ptr<ceres::CostFunction>>& costs,
                              ceres::LossFunction& huber, std::deque<CandidateWeight>& weights,
                              int& candidates) {
  const ProjectionWeight w{rig_.focal_px, options_.sigma_px, nullptr};
  int used = 0;
  for (auto& [id, lm] : fm_.landmarks()) {
    if (!inSolve(lm)) continue;
    ++used;
    const bool candidate = options_.candidate_weights && lm.label == FeatureLabel::kCandidate;
    candidates += candidate;
    std::map<int, const double*> scale_of_frame;
    if (candidate) {
      for (std::size_t k = 1; k < lm.obs.size(); ++k) {
        weights.push_back({&lm, lm.start_frame + static_cast<int>(k), 1.0});
        scale_of_frame[weights.back().frame] = &weights.back().info;
      }
    }
    for (const auto& lf :
         landmarkFactors(lm, rig_, w, TdUse{estimatesTd(), std::nullopt}, scale_of_frame, estimatesRays())) {
      costs.push_back(lf.cost);
      problem.AddResidualBlock(lf.cost.get(), &huber, factorBlocks(lm, lf.frame, estimatesTd()));
    }
  }
  return used;
}

void Estimator::storeRays() {
  for (auto& [id, lm] : fm_.landmarks()) {
    if (!inSolve(lm)) continue;
    lm.ray_estimated = true;
    lm.ray_xy = Vector2d(lm.ray_block[0], lm.ray_block[1]);
    lm.inv_depth = lm.ray_block[2];
  }
}

void Estimator::refreshWeights(std::deque<CandidateWeight>& weights) const {
  for (auto& wt : weights) {
    const Isometry3d T_ci = cameraPose(frames_[wt.lm->start_frame].T_w_b(), rig_.T_b_c0);
    const Isometry3d T_cj = cameraPose(frames_[wt.frame].T_w_b(), rig_.T_b_c0);
    const Isometry3d T_ci_cj = T_ci.inverse() * T_cj;
    const double m = dynamic::epipolarErrorPx2(wt.lm->obs.front().xy, wt.lm->obs[wt.frame - wt.lm->start_frame].xy,
                                               T_ci_cj.linear(), T_ci_cj.translation(), rig_.fx, rig_.fy);
    wt.info = dynamic::candidateInformation(m);
  }
}

void Estimator::restoreGauge(const Isometry3d& T_w_b0_before) {
  const Isometry3d G = gaugeCorrection(T_w_b0_before, frames_[0].T_w_b());
  const Quaterniond q_G(G.linear());
  for (int i = 0; i <= count_; ++i) {
    imu::NavState s = frames_[i].nav();
    s.p_w_b = G * s.p_w_b;
    s.q_w_b = (q_G * s.q_w_b).normalized();
    s.v_w = q_G * s.v_w;
    frames_[i].setNav(s);
  }
}

Vector3d Estimator::landmarkWorld(const Landmark& lm) const {
  return cameraPose(frames_[lm.start_frame].T_w_b(), rig_.T_b_c0) * lm.anchorPoint();
}

LeavingKeyframe Estimator::leavingKeyframe() const {
  LeavingKeyframe k;
  const Isometry3d T = frames_[0].T_w_b();
  k.t_ns = frames_[0].t_ns;
  k.p_w_b = T.translation();
  k.q_w_b = Quaterniond(T.linear()).normalized();
  for (const auto& [id, lm] : fm_.landmarks()) {
    if (lm.start_frame != 0) continue;  // frame 0 is the oldest: its landmarks start there
    KeyframeObservation o;
    o.id = id;
    o.label = lm.label;
    o.has_position = lm.usable();
    if (o.has_position) o.p_w = landmarkWorld(lm);
    o.uv = lm.obs.front().uv;
    o.xy = lm.obs.front().xy;
    k.observations.push_back(o);
  }
  return k;
}

void Estimator::addToStaticMap(const Landmark& lm) {
  if (!initialized_ || !lm.usable() || lm.label != FeatureLabel::kStatic || lm.obs.size() < 3) return;
  if (!mapped_.insert(lm.id).second) return;
  static_map_.push_back({landmarkWorld(lm), FeatureLabel::kStatic, lm.id});
}

void Estimator::flushMap() {
  if (!initialized_) return;
  for (const auto& [id, lm] : fm_.landmarks()) addToStaticMap(lm);
}

double Estimator::meanReprojectionErrorPx(const Landmark& lm, int last_n) const {
  const Vector3d pts_i(lm.anchorRay().x(), lm.anchorRay().y(), 1.0);
  const imu::NavState si = frames_[lm.start_frame].nav();
  const std::size_t first =
      last_n > 0 ? std::max<std::size_t>(1, lm.obs.size() - std::min<std::size_t>(last_n, lm.obs.size())) : 1;
  double sum = 0;
  for (std::size_t k = first; k < lm.obs.size(); ++k) {
    const imu::NavState sj = frames_[lm.start_frame + k].nav();
    const Vector3d p = transferPoint(pts_i, lm.inv_depth, si.p_w_b, si.q_w_b, sj.p_w_b, sj.q_w_b, rig_.T_b_c0, rig_.T_b_c0);
    sum += (p.head<2>() / p.z() - lm.obs[k].xy).norm() * rig_.focal_px;
  }
  return lm.obs.size() > first ? sum / static_cast<double>(lm.obs.size() - first) : 0.0;
}

void Estimator::postProcess(FrameResult& r) {
  std::vector<std::uint64_t> confirmed;
  for (auto& [id, lm] : fm_.landmarks()) {
    if (lm.label != FeatureLabel::kCandidate || !lm.usable() || lm.obs.size() < 2) continue;
    // The error of the observations made since the landmark was marked: a long static
    // history must not dilute an object that has just started to move.
    if (meanReprojectionErrorPx(lm, lm.candidate_obs) > options_.outlier_px) {
      confirmed.push_back(id);
      dynamic_ids_.insert(id);
      if (mapped_.insert(id).second)
        r.confirmed_points.push_back({landmarkWorld(lm), FeatureLabel::kConfirmedDynamic, id});
    } else if (lm.candidate_obs >= options_.clear_after_observations) {
      lm.label = FeatureLabel::kStatic;
      lm.candidate_obs = 0;
      ++r.cleared;
    }
  }
  r.confirmed_dynamic = static_cast<int>(confirmed.size());
  fm_.remove(confirmed);
}

void Estimator::removeOutliers(FrameResult& r) {
  std::vector<std::uint64_t>& bad = r.outlier_ids;
  for (const auto& [id, lm] : fm_.landmarks())
    if (lm.usable() && lm.obs.size() > 1 && meanReprojectionErrorPx(lm) > options_.outlier_px) bad.push_back(id);
  if (options_.confirm_outliers) {
    for (std::uint64_t id : bad) {
      if (!dynamic_ids_.insert(id).second) continue;
      ++r.outliers_confirmed;
      if (mapped_.insert(id).second)
        r.confirmed_points.push_back({landmarkWorld(fm_.landmarks().at(id)), FeatureLabel::kConfirmedDynamic, id});
    }
  }
  fm_.remove(bad);
  // Not while estimating td: with it, the PipelineTimeOffset test's run is 1.18x the run with
  // td known (0.0032 / 0.0027 m; bound 1.10x), also with the observations moved to the
  // estimated offset as the factors move them. Why is not settled.
  if (options_.stereo_outlier_px > 0 && !estimatesTd()) r.right_outliers = dropRightOutliers();
}

int Estimator::dropRightOutliers() {
  int dropped = 0;
  for (auto& [id, lm] : fm_.landmarks()) {
    if (!inSolve(lm)) continue;
    const Vector3d pts_i(lm.anchorRay().x(), lm.anchorRay().y(), 1.0);
    const imu::NavState si = frames_[lm.start_frame].nav();
    for (std::size_t k = 0; k < lm.obs.size(); ++k) {
      Observation& o = lm.obs[k];
      if (!o.has_right) continue;
      const imu::NavState sj = frames_[lm.start_frame + static_cast<int>(k)].nav();
      const Vector3d p = transferPoint(pts_i, lm.inv_depth, si.p_w_b, si.q_w_b, sj.p_w_b, sj.q_w_b, rig_.T_b_c0, rig_.T_b_c1);
      if (p.z() > 0 && (p.head<2>() / p.z() - o.xy_right).norm() * rig_.focal_px <= options_.stereo_outlier_px) continue;
      o.has_right = false;
      ++dropped;
    }
  }
  return dropped;
}

bool Estimator::failureDetected(std::string& why) const {
  const imu::NavState s = frames_[count_].nav();
  if (s.ba.norm() > 2.5) {
    why = "accelerometer bias estimate too large (" + std::to_string(s.ba.norm()) + " m/s^2)";
    return true;
  }
  if (s.bg.norm() > 1.0) {
    why = "gyroscope bias estimate too large";
    return true;
  }
  if (count_ > 0) {
    const imu::NavState p = frames_[count_ - 1].nav();
    if ((s.p_w_b - p.p_w_b).norm() > 5.0) {
      why = "position jump between frames";
      return true;
    }
    if (s.q_w_b.angularDistance(p.q_w_b) > 50.0 * M_PI / 180) {
      why = "rotation jump between frames";
      return true;
    }
  }
  if (fm_.trackedIn(count_) < 2) {
    why = "too few tracked landmarks";
    return true;
  }
  return false;
}

void Estimator::slide(bool keyframe) {
  if (count_ < kWindowSize) return;
  if (keyframe || !initialized_)
    marginalizeOldest();
  else
    dropSecondNewest();
  // Keep the IMU samples still needed (from the oldest window frame on, and from the last
  // good state while a new segment must continue from it).
  const TimeNs keep_from = reanchor_pending_ ? std::min(frames_[0].t_ns, last_good_t_ns_) : frames_[0].t_ns;
  std::size_t first = 0;
  while (first + 1 < imu_.size() && imu_[first + 1].t_ns <= keep_from) ++first;
  if (first > 0) imu_.erase(imu_.begin(), imu_.begin() + static_cast<std::ptrdiff_t>(first));
}

void Estimator::marginalizeOldest() {
  if (initialized_) {
    Marginalizer m;
    double* pose0 = frames_[0].pose.data();
    double* sb0 = frames_[0].sb.data();
    if (prior_) {
      std::vector<int> drop;
      for (std::size_t k = 0; k < prior_->blocks.size(); ++k)
        if (prior_->blocks[k] == pose0 || prior_->blocks[k] == sb0) drop.push_back(static_cast<int>(k));
      // Carried into the new prior even when it does not touch frame 0.
      m.add({std::make_shared<MarginalizationFactor>(prior_), nullptr, prior_->blocks, drop});
    }
    if (frames_[1].pre && frames_[1].pre->sumDt() <= 10.0)
      m.add({std::make_shared<ImuFactor>(frames_[1].pre.get()), nullptr,
             {pose0, sb0, frames_[1].pose.data(), frames_[1].sb.data()}, {0, 1}});
    auto huber = std::make_shared<ceres::HuberLoss>(options_.huber_px);
    const ProjectionWeight w{rig_.focal_px, options_.sigma_px, nullptr};
    std::deque<double> shares;  // the projection weights point at them until marginalize()
    for (auto& [id, lm] : fm_.landmarks()) {
      if (lm.start_frame != 0 || !lm.usable()) continue;
      std::map<int, const double*> share_of_frame;
      if (options_.prior_landmark_share && lm.priorShare() < 1.0) {
        shares.push_back(lm.priorShare());
        for (int j = 0; j <= lm.endFrame(); ++j) share_of_frame[j] = &shares.back();
      }
      // The prior keeps no information on the time offset: the marginalized observations are
      // moved to the current estimate (measured: a prior that kept it held td near its first values).
      const TdUse td = estimatesTd() ? TdUse{false, td_s_} : TdUse{};
      for (const auto& lf : landmarkFactors(lm, rig_, w, td, share_of_frame, estimatesRays()))
        m.add({lf.cost, huber, factorBlocks(lm, lf.frame, false), lf.frame < 0 ? std::vector<int>{0} : std::vector<int>{0, 2}});
    }
    prior_ = std::make_shared<MarginalizationPrior>(m.marginalize());
    if (options_.prior_fading < 1.0) prior_->scaleInformation(options_.prior_fading);
    if (prior_->blocks.empty()) prior_.reset();
  }
  if (initialized_) leaving_ = leavingKeyframe();
  for (const auto& [id, lm] : fm_.landmarks())
    if (lm.start_frame == 0 && lm.endFrame() < count_) addToStaticMap(lm);  // leaves the window
  std::vector<Isometry3d> T_w_b;  // before the slide
  for (int i = 0; i <= kWindowSize; ++i) T_w_b.push_back(frames_[i].T_w_b());
  std::unordered_map<double*, double*> remap;
  for (int i = 0; i < kWindowSize; ++i) {
    frames_[i].t_ns = frames_[i + 1].t_ns;
    frames_[i].pose = frames_[i + 1].pose;
    frames_[i].sb = frames_[i + 1].sb;
    frames_[i].pre = std::move(frames_[i + 1].pre);
    remap[frames_[i + 1].pose.data()] = frames_[i].pose.data();
    remap[frames_[i + 1].sb.data()] = frames_[i].sb.data();
  }
  frames_[0].pre.reset();
  fm_.removeOldest(T_w_b, rig_, options_.reanchor_triangulate, estimatesRays());
  if (prior_) prior_->remap(remap);
  count_ = kWindowSize - 1;
}

void Estimator::dropSecondNewest() {
  const int k = kWindowSize - 1, newest = kWindowSize;
  if (prior_) {
    std::vector<int> drop;
    for (std::size_t i = 0; i < prior_->blocks.size(); ++i)
      if (prior_->blocks[i] == frames_[k].pose.data() || prior_->blocks[i] == frames_[k].sb.data())
        drop.push_back(static_cast<int>(i));
    if (!drop.empty()) {
      Marginalizer m;
      m.add({std::make_shared<MarginalizationFactor>(prior_), nullptr, prior_->blocks, drop});
      prior_ = std::make_shared<MarginalizationPrior>(m.marginalize());
      if (prior_->blocks.empty()) prior_.reset();
    }
  }
  // One preintegration from frame k-1 to the newest frame.
  auto merged = integrate(frames_[k - 1].t_ns, frames_[newest].t_ns, frames_[k - 1].nav());
  frames_[k].t_ns = frames_[newest].t_ns;
  frames_[k].pose = frames_[newest].pose;
  frames_[k].sb = frames_[newest].sb;
  frames_[k].pre = merged ? std::move(merged) : std::move(frames_[newest].pre);
  frames_[newest].pre.reset();
  fm_.removeFrame(k);
  if (prior_) prior_->remap({{frames_[newest].pose.data(), frames_[k].pose.data()},
                             {frames_[newest].sb.data(), frames_[k].sb.data()}});
  count_ = kWindowSize - 1;
}

}  // namespace idyvins::backend
