#include "map/loop_closer.h"

#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>

namespace idyvins::map {

namespace {
double msSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}
/// Roll and pitch (the tilt) of two rotations differ by this angle (rad).
double tiltDifference(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b) {
  return Eigen::AngleAxisd(tiltOf(a).transpose() * tiltOf(b)).angle();
}
}  // namespace

LoopCloser::LoopCloser(const LoopOptions& options, std::unique_ptr<camera::CameraModel> left_camera,
                       const Eigen::Isometry3d& T_b_c, bool threaded)
    : options_(options),
      camera_(std::move(left_camera)),
      T_b_c_(T_b_c),
      database_(options.recognition),
      graph_(options.graph) {
  options_.verify.focal_px = camera_->params().fx;
  if (threaded) worker_ = std::thread([this] { run(); });
}

LoopCloser::~LoopCloser() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  if (worker_.joinable()) worker_.join();
}

void LoopCloser::add(LoopKeyframe keyframe) {
  if (have_last_ && (keyframe.p_w_b - last_p_).norm() < options_.min_keyframe_distance_m &&
      keyframe.q_w_b.angularDistance(last_q_) < options_.min_keyframe_turn_rad) {
    std::lock_guard<std::mutex> lock(mutex_);
    ++stats_.keyframes_skipped;
    return;
  }
  have_last_ = true;
  last_p_ = keyframe.p_w_b;
  last_q_ = keyframe.q_w_b;
  if (!worker_.joinable()) {
    handle(keyframe);
    return;
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);
    queue_.push_back(std::move(keyframe));
  }
  wake_.notify_one();
}

void LoopCloser::finish() {
  if (!worker_.joinable()) return;
  std::unique_lock<std::mutex> lock(mutex_);
  idle_.wait(lock, [this] { return queue_.empty() && !busy_; });
}

void LoopCloser::run() {
  // Below the odometry's threads: on a busy machine loops wait, the odometry does not (Linux:
  // a thread's nice value is its own). Failing to lower it changes nothing but timing.
  (void)setpriority(PRIO_PROCESS, static_cast<id_t>(::syscall(SYS_gettid)), 10);
  for (;;) {
    LoopKeyframe k;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      wake_.wait(lock, [this] { return !queue_.empty() || stopping_; });
      if (queue_.empty()) return;
      k = std::move(queue_.front());
      queue_.pop_front();
      busy_ = true;
    }
    handle(k);
    {
      std::lock_guard<std::mutex> lock(mutex_);
      busy_ = false;
    }
    idle_.notify_all();
  }
}

void LoopCloser::handle(LoopKeyframe& in) {
  const auto t0 = std::chrono::steady_clock::now();
  // Corners: the landmarks' own, then extra ones for recognition.
  std::vector<cv::Point2f> corners;
  for (const LoopLandmark& l : in.landmarks) corners.emplace_back(static_cast<float>(l.uv.x()), static_cast<float>(l.uv.y()));
  const std::size_t n_landmarks = corners.size();
  for (const cv::Point2f& c : recognitionCorners(in.left, options_.extra_corners)) corners.push_back(c);
  std::vector<int> kept;
  const std::vector<Descriptor> desc = describeCorners(in.left, corners, &kept);
  Keyframe kf;
  kf.t_ns = in.t_ns;
  kf.p_w_b = in.p_w_b;
  kf.q_w_b = in.q_w_b;
  PlaceQuery query;
  for (std::size_t i = 0; i < kept.size(); ++i) {
    const auto src = static_cast<std::size_t>(kept[i]);
    Eigen::Vector2d xy;
    if (src < n_landmarks) {
      const LoopLandmark& l = in.landmarks[src];
      kf.landmarks.push_back({l.id, l.p_w, l.xy, desc[i]});
      xy = l.xy;
    } else if (!camera_->liftToNormalized({corners[i].x, corners[i].y}, xy)) {
      continue;
    }
    kf.descriptors.push_back(desc[i]);
    query.xy.push_back(xy);
    query.descriptors.push_back(desc[i]);
  }
  const std::uint32_t id = static_cast<std::uint32_t>(database_.size());
  graph_.addKeyframe(in.t_ns, in.p_w_b, in.q_w_b);
  const bool closed = tryLoop(kf, query, id);
  database_.add(std::move(kf));
  ++stats_.keyframes;
  stats_.sum_detect_ms += msSince(t0);
  if (closed) {
    const auto t1 = std::chrono::steady_clock::now();
    graph_.optimize();
    stats_.sum_graph_ms += msSince(t1);
    ++stats_.graph_solves;
  }
}

bool LoopCloser::tryLoop(const Keyframe& now, const PlaceQuery& query, std::uint32_t new_id) {
  const TimeNs before = now.t_ns - static_cast<TimeNs>(options_.min_age_s * 1e9);
  if (database_.size() == 0 || database_.keyframe(0).t_ns >= before) return false;  // nothing old enough yet
  for (const PlaceCandidate& c : database_.query(query.descriptors, before)) {
    ++stats_.candidates_checked;
    const Keyframe& old = database_.keyframe(c.keyframe);
    const PlaceVerification v = verifyPlace(old, query, T_b_c_, options_.verify);
    if (!v.accepted) continue;
    // The loop against the odometry's own guess: a wild jump or a tilt gravity rules out is no loop.
    const RelativePose4 rel = relativePose4(old.p_w_b, old.q_w_b, v.p_w_b, v.q_w_b);
    const RelativePose4 odo = relativePose4(old.p_w_b, old.q_w_b, now.p_w_b, now.q_w_b);
    if ((rel.t_from_to - odo.t_from_to).norm() > options_.max_loop_distance_m ||
        std::abs(wrapAngle(rel.dyaw - odo.dyaw)) > options_.max_loop_yaw_rad ||
        tiltDifference(v.q_w_b, now.q_w_b) > options_.max_tilt_rad) {
      ++stats_.refused_by_consistency;
      continue;
    }
    graph_.addLoop({c.keyframe, new_id, rel});
    loops_.push_back({c.keyframe, new_id, old.t_ns, now.t_ns, c.votes, v.matches, v.inliers, rel});
    ++stats_.loops;
    return true;
  }
  return false;
}

SavedMap LoopCloser::savedMap() const {
  SavedMap m;
  m.keyframes = database_.keyframes();
  m.nodes = graph_.nodes();
  m.loops = graph_.loops();
  return m;
}


}  // namespace idyvins::map
