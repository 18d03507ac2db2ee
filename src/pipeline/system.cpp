#include "pipeline/system.h"

#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <functional>
#include <mutex>
#include <stdexcept>
#include <thread>
#include <utility>

#include "backend/estimator.h"
#include "config/modes.h"
#include "core/error.h"
#include "imu/preintegration.h"
#include "pipeline/front_end.h"

namespace idyvins::pipeline {

void checkRunnable(const Config& config) {
  if (config.T_b_c.size() != static_cast<std::size_t>(config.num_cam))
    throw InputError(config.path, "num_of_cam: " + std::to_string(config.num_cam) + " with " +
                                      std::to_string(config.T_b_c.size()) + " camera extrinsics");
  if (config.num_cam == 1 && !config.use_imu)
    throw InputError(config.path,
                     "num_of_cam: 1 with imu: 0: one camera needs the IMU for its scale (monocular "
                     "odometry without it is not supported)");
  if (!config.use_imu && config.estimator.estimate_td)
    throw InputError(config.path, "imu: 0 with estimate_td: 1: without an IMU there is no offset to estimate");
  checkMaskCamera(config);
}

void checkMaskCamera(const Config& config) {
  if (config.cam0_right && traitsOf(config.mode).needs_masks)
    throw InputError(config.path, std::string("mode ") + toString(config.mode) +
                                      " needs the left camera's masks, and this rig's cam0 (whose masks a dataset "
                                      "has) is its right camera");
}

namespace {

const Config& checkedConfig(const Config& config) {
  checkRunnable(config);
  return config;
}

/// Depth range (m, left camera) of the stereo points that enter the dynamic map: nearer is
/// a degenerate triangulation, farther than stereo depth can place.
constexpr double kDynamicMapMinDepthM = 0.1, kDynamicMapMaxDepthM = 80.0;

/// A stereo point triangulated in front of the left camera, within the dynamic map's range.
std::optional<Eigen::Vector3d> triangulateInRange(const Eigen::Isometry3d& T_w_c0, const Eigen::Isometry3d& T_w_c1,
                                                  const frontend::Feature& f) {
  const Eigen::Vector3d p_w = backend::triangulateTwoViews(T_w_c0, f.xy, T_w_c1, f.xy_right);
  const double z = (T_w_c0.inverse() * p_w).z();
  if (z > kDynamicMapMinDepthM && z < kDynamicMapMaxDepthM) return p_w;
  return std::nullopt;
}

}  // namespace

/// The back-end thread of a pipelined run: runs one job at a time, handed over by the caller.
class System::Worker {
 public:
  Worker() : thread_([this] { loop(); }) {}
  ~Worker() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stop_ = true;
    }
    cv_.notify_all();
    thread_.join();
  }
  void submit(std::function<void()> job) {
    std::lock_guard<std::mutex> lock(mutex_);
    job_ = std::move(job);
    busy_ = true;
    cv_.notify_all();
  }
  /// Waits until the submitted job has finished; rethrows what it threw.
  void wait() {
    std::unique_lock<std::mutex> lock(mutex_);
    cv_.wait(lock, [this] { return !busy_; });
    if (error_) std::rethrow_exception(std::exchange(error_, nullptr));
  }

 private:
  void loop() {
    std::unique_lock<std::mutex> lock(mutex_);
    while (true) {
      cv_.wait(lock, [this] { return stop_ || job_; });
      if (!job_) return;  // stopped
      auto job = std::move(job_);
      job_ = nullptr;
      lock.unlock();
      std::exception_ptr error;
      try {
        job();
      } catch (...) {
        error = std::current_exception();
      }
      lock.lock();
      error_ = error;
      busy_ = false;
      cv_.notify_all();
    }
  }
  std::mutex mutex_;
  std::condition_variable cv_;
  std::function<void()> job_;
  bool busy_ = false, stop_ = false;
  std::exception_ptr error_;
  std::thread thread_;
};

struct System::Parts {
  explicit Parts(const Config& config)
      : front_end(config), estimator(config.rig(), config.imu.noise, optionsFor(config).estimator) {}
  FrontEnd front_end;
  backend::Estimator estimator;
};

System::System(const Config& config, const RunOptions& run)
    : config_(leftFirst(checkedConfig(config))),
      cam0_right_(config.cam0_right),
      mode_(config.mode),
      run_(run),
      parts_(std::make_unique<Parts>(config_)),
      spike_gate_(config_.imu.spike) {
  if (run_.feedback_delay != 0 && run_.feedback_delay != 1)
    throw std::invalid_argument("RunOptions::feedback_delay must be 0 or 1");
  if (run_.pipelined && run_.feedback_delay != 1)
    throw std::invalid_argument("a pipelined run needs RunOptions::feedback_delay 1");
  if (run_.pipelined) worker_ = std::make_unique<Worker>();
  td_s_ = config_.estimator.td_s;
  T_b_c0_ = config_.T_b_c.at(0);
  if (config_.loop.enabled) {
    map::LoopOptions loop = config_.loop;
    if (config_.T_b_c.size() > 1)  // the stored landmarks' depth uncertainty
      loop.verify.stereo_baseline_m = (config_.T_b_c[1].translation() - config_.T_b_c[0].translation()).norm();
    loop_ = std::make_unique<map::LoopCloser>(loop, camera::makeCamera(config_.cams.at(0)), config_.T_b_c.at(0),
                                              /*threaded=*/true);
  }
}

System::~System() = default;

std::string rigFingerprint(const Config& config) {
  const camera::CameraParams& c = config.cams.at(0);
  const Eigen::Isometry3d& T = config.T_b_c.at(0);
  const Eigen::Quaterniond q(T.rotation());
  char text[320];
  std::snprintf(text, sizeof(text),
                "%s %dx%d f %.2f %.2f c %.2f %.2f d %.4f %.4f %.4f %.4f T_b_c0 %.3f %.3f %.3f q %.4f %.4f %.4f %.4f",
                camera::toString(c.type), c.width, c.height, c.fx, c.fy, c.cx, c.cy, c.dist[0], c.dist[1], c.dist[2],
                c.dist[3], T.translation().x(), T.translation().y(), T.translation().z(), q.w(), q.x(), q.y(), q.z());
  return text;
}

void System::loadMap(const map::SavedMap& m, bool extend, const std::string& source) {
  if (!loop_) throw std::logic_error("System::loadMap needs the config's loop_closure");
  const std::string rig = rigFingerprint(config_);
  if (!m.rig.empty() && m.rig != rig)
    throw InputError(source, "map built with another left camera (" + m.rig + ") than the config's (" + rig + ")");
  loop_->loadMap(m, extend);
}

void System::addImu(const ImuSample& sample) {
  if (!config_.use_imu) return;                            // imu: 0: the samples a dataset has are not used
  if (last_imu_t_ns_ && sample.t_ns <= *last_imu_t_ns_) {  // as the estimator: strictly increasing
    ++summary_.imu_out_of_order;
    return;
  }
  if (!sample.acc_b.allFinite() || !sample.gyr_b.allFinite() || sample.acc_b.norm() > config_.imu.max_acc_mps2 ||
      sample.gyr_b.norm() > config_.imu.max_gyr_radps) {
    ++summary_.imu_out_of_range;
    return;
  }
  last_imu_t_ns_ = sample.t_ns;
  spike_gate_.push(sample, imu_);  // short spikes held back, then dropped
  summary_.imu_spikes = spike_gate_.spikes();
  summary_.imu_spike_samples = spike_gate_.droppedSamples();
}

frontend::MotionPrior System::priorFor(TimeNs t_prev, TimeNs t_cur) const {
  const backend::LatestState& s = snapshot_;
  if (!usesIdyFilter(mode_) || !s.valid) return {};
  if (!config_.use_imu) {  // imu: 0: the window's constant-velocity prediction
    if (trajectory_.size() < 2) return {};
    const StampedState& a = trajectory_[trajectory_.size() - 2];
    const StampedState& b = trajectory_.back();
    const auto pose = [](const StampedState& x) { return Eigen::Translation3d(x.state.p_w_b) * x.state.q_w_b; };
    return dynamic::cameraMotionPrior(dynamic::constantVelocityMotion(pose(a), a.t_ns, pose(b), b.t_ns, t_prev, t_cur,
                                                                      config_.idy.cv_prior_acc_sigma),
                                      T_b_c0_);
  }
  imu::NavState from = s.state;
  TimeNs t_from = s.t_ns;
  // The newest finished state is older than the previous frame (feedback_delay 1): predict
  // it to the previous frame's time with the IMU and its own biases.
  if (run_.feedback_delay == 1 && t_prev > t_from) {
    if (imu_.empty() || imu_.front().t_ns > t_from || imu_.back().t_ns < t_prev) return {};
    from = imu::integrateBetween(imu_, t_from, t_prev, from.ba, from.bg, config_.imu.noise).predict(from);
    t_from = t_prev;
  }
  return dynamic::motionPrior(from, t_from, t_cur, imu_, config_.imu.noise, T_b_c0_);
}

const FrameOutput* System::addFrame(const StereoFrame& frame) {
  done_.reset();
  // Checked on arrival (the frame may wait for IMU samples before it is processed).
  if (traitsOf(mode_).needs_masks && frame.left_mask.empty())
    throw InputError("frame " + std::to_string(frame.t_ns),
                     std::string("mode ") + toString(mode_) + " needs the left image's ground-truth mask");
  pending_.push_back(cam0_right_ ? leftFirst(frame) : frame);  // images are reference-counted: no copy
  while (!pending_.empty() && (imuCovers(pending_.front()) || pending_.size() > kMaxPendingFrames)) {
    process(pending_.front());
    pending_.pop_front();
  }
  return done_ ? &done_->out : nullptr;
}

std::size_t System::poll() {
  std::size_t processed = 0;
  for (; !pending_.empty() && imuCovers(pending_.front()); ++processed) {
    process(pending_.front());
    pending_.pop_front();
  }
  return processed;
}

TimeNs System::imuTime(const StereoFrame& frame) const {
  return frame.t_ns + static_cast<TimeNs>(std::llround(td_s_ * 1e9));
}

bool System::imuCovers(const StereoFrame& frame) const {
  // The estimator integrates to the frame's time: a sample at or after it must be here
  // (a frame between two samples, or whose own-time sample was dropped, waits for the next).
  // Without the IMU (imu: 0) no frame waits.
  return !config_.use_imu || (!imu_.empty() && imu_.back().t_ns >= imuTime(frame));
}

void System::process(const StereoFrame& frame) {
  auto f = std::make_unique<InFlight>();
  f->input = frame;
  StereoFrame on_imu_clock = frame;
  on_imu_clock.t_ns = imuTime(frame);
  const TimeNs t = on_imu_clock.t_ns;
  FrameOutput& out = f->out;
  out.index = summary_.frames + (in_flight_ ? 1 : 0);
  out.t_ns = t;
  out.features = parts_->front_end.track(on_imu_clock, priorFor(last_frame_t_ns_, t));
  out.features.td_s = td_s_;
  out.idy = parts_->front_end.idyStats();
  last_frame_t_ns_ = t;
  // The estimator gets the IMU samples up to this frame's time, and the first one at or after
  // it (a frame between two samples is reached by interpolation), with the frame's back end.
  while (imu_to_estimator_ < imu_.size() && (imu_to_estimator_ == 0 || imu_[imu_to_estimator_ - 1].t_ns < t))
    f->imu.push_back(imu_[imu_to_estimator_++]);
  completeInFlight();  // feedback_delay 1: the previous frame's back end
  mapLostMoving(out.features, out);
  in_flight_ = std::move(f);
  if (run_.pipelined) {
    worker_->submit([this, job = in_flight_.get()] { backEnd(*job); });
  } else if (run_.feedback_delay == 0) {
    completeInFlight();
  }
}

void System::backEnd(InFlight& f) {
  for (const ImuSample& s : f.imu) parts_->estimator.addImu(s);
  const std::size_t static_before = parts_->estimator.staticMap().size();
  f.out.estimate = parts_->estimator.addFrame(f.out.features);
  const auto& static_map = parts_->estimator.staticMap();
  if (static_map.size() > static_before)
    f.out.new_static_points.assign(static_map.begin() + static_cast<std::ptrdiff_t>(static_before), static_map.end());
  mapEliminated(f.out.features, f.out);
}

void System::completeInFlight() {
  if (!in_flight_) return;
  if (run_.pipelined)
    worker_->wait();
  else
    backEnd(*in_flight_);
  done_ = std::move(in_flight_);
  finalize(*done_);
}

void System::finalize(InFlight& f) {
  if (f.out.estimate.reset) parts_->front_end.reset();
  snapshot_ = parts_->estimator.latest();
  td_s_ = parts_->estimator.timeOffset();
  if (f.out.estimate.extrinsic) {
    extrinsic_ = f.out.estimate.extrinsic;
    T_b_c0_ = Eigen::Translation3d(extrinsic_->t_b_c0) * extrinsic_->q_b_c0;
  }
  // The next priors start at the newest state (or, before there is one, at a frame not
  // older than this one): drop the samples before the last one at or before that time.
  const TimeNs from = snapshot_.valid ? std::min(snapshot_.t_ns, f.out.t_ns) : f.out.t_ns;
  std::size_t drop = 0;
  while (drop + 1 < imu_to_estimator_ && imu_[drop + 1].t_ns <= from) ++drop;
  if (drop > 0) {
    imu_.erase(imu_.begin(), imu_.begin() + static_cast<std::ptrdiff_t>(drop));
    imu_to_estimator_ -= drop;
  }
  account(f.out);
  if (loop_) feedLoopCloser(f);
  for (FrameObserver* o : observers_) o->onFrame(f.input, f.out);
}

void System::feedLoopCloser(const InFlight& f) {
  constexpr std::size_t kMaxImages = 400;  // frames in the window span far fewer; bounds a long failure
  window_images_.emplace_back(f.out.features.t_ns, f.input.left);
  if (window_images_.size() > kMaxImages) window_images_.pop_front();
  const auto& kf = f.out.estimate.left_window;
  if (!kf) return;
  while (!window_images_.empty() && window_images_.front().first < kf->t_ns) window_images_.pop_front();
  if (window_images_.empty() || window_images_.front().first != kf->t_ns) return;  // not seen (cannot happen)
  map::LoopKeyframe k;
  k.t_ns = kf->t_ns;
  k.p_w_b = kf->p_w_b;
  k.q_w_b = kf->q_w_b;
  k.left = window_images_.front().second;
  // Static landmarks, and candidates for the loop closer to keep apart; never an eliminated or
  // confirmed-dynamic one (DESIGN §7).
  for (const backend::KeyframeObservation& o : kf->observations)
    if ((o.label == FeatureLabel::kStatic || o.label == FeatureLabel::kCandidate) && o.has_position)
      k.landmarks.push_back({o.id, o.p_w, o.uv, o.xy, o.label == FeatureLabel::kCandidate});
  loop_->add(std::move(k));
}

void System::finishLoops(Result& result) {
  result.loop_enabled = loop_ != nullptr;
  if (!loop_) return;
  loop_->finish();
  for (const StampedState& s : trajectory_) {
    StampedPose p{s.t_ns, s.state.p_w_b, s.state.q_w_b};
    loop_->graph().correctedAt(s.t_ns, s.state.p_w_b, s.state.q_w_b, p.p_w_b, p.q_w_b);
    result.loop_trajectory.push_back(p);
  }
  result.loops = loop_->loops();
  result.loop_stats = loop_->stats();
  for (const auto& [id, p_w] : loop_->correctedLandmarks())
    result.loop_static_map.push_back({p_w, FeatureLabel::kStatic, id});
}

void System::mapLostMoving(const frontend::FeatureFrame& ff, FrameOutput& out) {
  summary_.lost_tested += ff.lost_tested;
  summary_.lost_moving += ff.lost_moving.size();
  if (!prev_T_w_c_) return;  // triangulated with the cameras of the frame they were seen in
  for (const auto& f : ff.lost_moving) {
    if (!f.has_right) continue;  // judged moving without a stereo point: labelled only
    if (const auto p_w = triangulateInRange(prev_T_w_c_->first, prev_T_w_c_->second, f))
      out.eliminated_points.push_back({*p_w, frontend::FeatureLabel::kEliminated, f.id});
  }
}

void System::mapEliminated(const frontend::FeatureFrame& ff, FrameOutput& out) {
  prev_T_w_c_.reset();
  if (!usesIdyFilter(mode_) || !out.estimate.initialized) return;
  Eigen::Isometry3d T_w_b = Eigen::Isometry3d::Identity();
  T_w_b.linear() = out.estimate.state.q_w_b.toRotationMatrix();
  T_w_b.translation() = out.estimate.state.p_w_b;
  const Eigen::Isometry3d T_w_c0 = backend::cameraPose(T_w_b, parts_->estimator.rig().T_b_c0);
  const Eigen::Isometry3d T_w_c1 = backend::cameraPose(T_w_b, parts_->estimator.rig().T_b_c1);
  prev_T_w_c_.emplace(T_w_c0, T_w_c1);
  for (const auto& f : ff.removed)  // eliminated features with a stereo match: dynamic map
    if (f.has_right)
      if (const auto p_w = triangulateInRange(T_w_c0, T_w_c1, f))
        out.eliminated_points.push_back({*p_w, frontend::FeatureLabel::kEliminated, f.id});
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
  if (r.reset) s.resets.push_back({r.t_ns, out.index, r.reset_why.empty() ? r.status : r.reset_why, -1, ""});
  if (r.initialized && !s.resets.empty() && s.resets.back().resumed_t_ns < 0) {
    s.resets.back().resumed_t_ns = r.t_ns;
    s.resets.back().continued_by = r.reanchored;
  }
  if (out.idy && !out.idy->prior_valid) ++s.frames_without_prior;
  if (!r.stereo_only.empty()) ++s.frames_stereo_only;
  s.sum_tracking_ms += out.features.tracking_ms;
  s.lost_tracks += out.features.lost_tracks;
  s.lost_new += out.features.lost_new;
  s.sum_filter_ms += out.features.filter_ms;
  s.sum_optimization_ms += r.optimization_ms;
  s.sum_marginalization_ms += r.marginalization_ms;
  if (r.solve.iterations > 0) {
    ++s.solves;
    s.solves_converged += r.solve.converged;
    s.solve_sum += r.solve;
  }
  s.last_status = r.status;
  if (!r.initialized && r.status.rfind("initializing: ", 0) == 0 && r.status.find(" frames") == std::string::npos)
    ++s.init_failures[r.status];
  s.sum_features += out.features.features.size();
  eliminated_.insert(eliminated_.end(), out.eliminated_points.begin(), out.eliminated_points.end());
  confirmed_.insert(confirmed_.end(), r.confirmed_points.begin(), r.confirmed_points.end());
}

Result System::finish() {
  spike_gate_.flush(imu_);  // the end of the stream: a run still held is released as it is
  // Frames whose time on the IMU clock is past the last IMU sample cannot be integrated to.
  for (; !pending_.empty(); pending_.pop_front()) {
    if (imuCovers(pending_.front()))
      process(pending_.front());
    else
      ++summary_.frames_beyond_imu;
  }
  completeInFlight();
  summary_.td_s = td_s_;
  summary_.td_estimated = config_.estimator.estimate_td;
  if (config_.estimator.estimate_extrinsic != 0) summary_.extrinsic = extrinsicSummary();
  parts_->estimator.flushMap();
  Result result;
  result.static_map = parts_->estimator.staticMap();
  result.dynamic_map = eliminated_;  // the one dynamic map: eliminated points, then confirmed ones
  result.dynamic_map.insert(result.dynamic_map.end(), confirmed_.begin(), confirmed_.end());
  result.trajectory = trajectory_;
  result.summary = summary_;
  finishLoops(result);
  return result;
}

ExtrinsicSummary System::extrinsicSummary() const {
  ExtrinsicSummary e;
  e.mode = config_.estimator.estimate_extrinsic;
  e.estimate = extrinsic_.value_or(backend::ExtrinsicEstimate{});
  if (!extrinsic_) {  // never initialized: the config's
    e.estimate.t_b_c0 = config_.T_b_c[0].translation();
    e.estimate.q_b_c0 = Eigen::Quaterniond(config_.T_b_c[0].linear());
  }
  const Eigen::Isometry3d T_b_left = Eigen::Translation3d(e.estimate.t_b_c0) * e.estimate.q_b_c0;
  for (const Eigen::Isometry3d& T_b_c : config_.T_b_c)  // the pair rigid: each camera as in the config
    e.T_b_c.push_back(T_b_left * config_.T_b_c[0].inverse() * T_b_c);
  const Eigen::Isometry3d* written = &config_.T_b_c[0];
  if (cam0_right_) {  // named as the config names them: cam0 is the right camera
    std::swap(e.T_b_c[0], e.T_b_c[1]);
    written = &config_.T_b_c[1];
    e.estimate.t_b_c0 = e.T_b_c[0].translation();
    e.estimate.q_b_c0 = Eigen::Quaterniond(e.T_b_c[0].linear());
  }
  e.rotation_change_deg = Eigen::Quaterniond(written->linear()).angularDistance(e.estimate.q_b_c0) * 180.0 / M_PI;
  e.translation_change_m = (written->translation() - e.estimate.t_b_c0).norm();
  return e;
}

StampedPose toStampedPose(const StampedState& s) { return {s.t_ns, s.state.p_w_b, s.state.q_w_b}; }

}  // namespace idyvins::pipeline
