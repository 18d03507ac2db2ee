#include "pipeline/system.h"

#include "core/error.h"

namespace idyvins::pipeline {
namespace {

backend::EstimatorOptions estimatorOptionsFor(Mode mode, const Config& config) {
  backend::EstimatorOptions o;
  o.candidate_weights = o.post_process = mode == Mode::kIdy || mode == Mode::kIdyBa;  // DESIGN §4.5, §4.6
  o.confirm_outliers = o.post_process && config.dynamic.confirm_outliers;           // DESIGN §4.9
  return o;
}

const Config& checkedConfig(const Config& config) {
  if (!config.use_imu || config.num_cam != 2 || config.T_b_c.size() < 2)
    throw InputError(config.path, "idyvins runs stereo + IMU configs only (imu: 1, num_of_cam: 2)");
  return config;
}

/// A stereo point triangulated in front of the left camera, within the dynamic map's range.
std::optional<Eigen::Vector3d> triangulateInRange(const Eigen::Isometry3d& T_w_c0, const Eigen::Isometry3d& T_w_c1,
                                                  const frontend::Feature& f) {
  const Eigen::Vector3d p_w = backend::triangulateTwoViews(T_w_c0, f.xy, T_w_c1, f.xy_right);
  const double z = (T_w_c0.inverse() * p_w).z();
  if (z > 0.1 && z < 80.0) return p_w;
  return std::nullopt;
}

}  // namespace

System::System(const Config& config)
    : config_(checkedConfig(config)),
      mode_(config.dynamic.mode),
      front_end_(config_, mode_),
      estimator_(config_, estimatorOptionsFor(mode_, config_)) {}

System::~System() = default;

void System::addImu(const ImuSample& sample) { estimator_.addImu(sample); }

frontend::MotionPrior System::priorFor(TimeNs t_ns) const {
  const backend::LatestState latest = estimator_.latest();
  if (!usesIdyFilter(mode_) || !latest.valid) return {};
  return dynamic::motionPrior(latest.state, latest.t_ns, t_ns, estimator_.imuHistory(), config_.imu,
                              config_.T_b_c[0]);
}

const FrameOutput& System::addFrame(const StereoFrame& frame) {
  FrameOutput& out = last_;
  out = FrameOutput{};
  out.index = summary_.frames;
  out.t_ns = frame.t_ns;
  out.features = front_end_.track(frame, priorFor(frame.t_ns));
  out.idy = front_end_.idyStats();
  mapLostMoving(out.features, out);
  out.estimate = estimator_.addFrame(out.features);
  mapEliminated(out.features, out);
  if (out.estimate.reset) front_end_.reset();
  account(out);
  for (FrameObserver* o : observers_) o->onFrame(frame, out);
  return out;
}

void System::mapLostMoving(const frontend::FeatureFrame& ff, FrameOutput& out) {
  summary_.lost_tested += ff.lost_tested;
  summary_.lost_moving += ff.lost_moving.size();
  if (!prev_T_w_c_) return;  // triangulated with the cameras of the frame they were seen in
  for (const auto& f : ff.lost_moving)
    if (const auto p_w = triangulateInRange(prev_T_w_c_->first, prev_T_w_c_->second, f))
      out.eliminated_points.push_back({*p_w, 1, f.id});
}

void System::mapEliminated(const frontend::FeatureFrame& ff, FrameOutput& out) {
  prev_T_w_c_.reset();
  if (!usesIdyFilter(mode_) || !out.estimate.initialized) return;
  Eigen::Isometry3d T_w_b = Eigen::Isometry3d::Identity();
  T_w_b.linear() = out.estimate.state.q_w_b.toRotationMatrix();
  T_w_b.translation() = out.estimate.state.p_w_b;
  const Eigen::Isometry3d T_w_c0 = backend::cameraPose(T_w_b, estimator_.rig().T_b_c0);
  const Eigen::Isometry3d T_w_c1 = backend::cameraPose(T_w_b, estimator_.rig().T_b_c1);
  prev_T_w_c_.emplace(T_w_c0, T_w_c1);
  for (const auto& f : ff.removed)  // eliminated features with a stereo match: dynamic map
    if (f.has_right)
      if (const auto p_w = triangulateInRange(T_w_c0, T_w_c1, f)) out.eliminated_points.push_back({*p_w, 1, f.id});
}

void System::account(FrameOutput& out) {
  Summary& s = summary_;
  if (s.frames == 0) s.first_t_ns = out.t_ns;
  s.last_t_ns = out.t_ns;
  ++s.frames;
  const backend::FrameResult& r = out.estimate;
  if (r.initialized) {
    trajectory_.push_back({r.t_ns, r.state});
    if (s.init_t_ns < 0) s.init_t_ns = r.t_ns;
  }
  if (r.reset) s.resets.push_back({r.t_ns, out.index, r.status});
  if (out.idy && !out.idy->prior_valid) ++s.frames_without_prior;
  s.sum_tracking_ms += out.features.tracking_ms;
  s.sum_filter_ms += out.features.filter_ms;
  s.sum_optimization_ms += r.optimization_ms;
  s.sum_marginalization_ms += r.marginalization_ms;
  if (r.solve.iterations > 0) {
    backend::SolveProfile& t = s.solve_sum;
    ++s.solves;
    s.solves_converged += r.solve.converged;
    t.build_ms += r.solve.build_ms;
    t.preprocess_ms += r.solve.preprocess_ms;
    t.residual_ms += r.solve.residual_ms;
    t.jacobian_ms += r.solve.jacobian_ms;
    t.linear_solver_ms += r.solve.linear_solver_ms;
    t.minimizer_ms += r.solve.minimizer_ms;
    t.post_ms += r.solve.post_ms;
    t.iterations += r.solve.iterations;
  }
  s.last_status = r.status;
  eliminated_.insert(eliminated_.end(), out.eliminated_points.begin(), out.eliminated_points.end());
}

Result System::finish() {
  estimator_.flushMap();
  Result result;
  result.static_map = estimator_.staticMap();
  result.dynamic_map = eliminated_;
  for (const auto& p : estimator_.dynamicMap()) result.dynamic_map.push_back({p.p_w, 2, p.id});
  result.trajectory = trajectory_;
  result.summary = summary_;
  return result;
}

StampedPose toStampedPose(const StampedState& s) { return {s.t_ns, s.state.p_w_b, s.state.q_w_b}; }

}  // namespace idyvins::pipeline
