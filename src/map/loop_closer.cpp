#include "map/loop_closer.h"

#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <set>
#include <stdexcept>

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

void LoopCloser::loadMap(const SavedMap& map, bool extend) {
  if (added_ || database_.size() > 0) throw std::logic_error("LoopCloser::loadMap after keyframes were added");
  if (map.keyframes.size() != map.nodes.size())
    throw std::invalid_argument("LoopCloser::loadMap: one node per keyframe");
  for (const Keyframe& k : map.keyframes) database_.add(k);
  graph_.loadMap(map.nodes, map.loops);
  loaded_ = map.keyframes.size();
  extend_ = extend;
  stats_.map_keyframes = loaded_;
  std::lock_guard<std::mutex> lock(correction_mutex_);
  correction_.in_map = false;
}

void LoopCloser::add(LoopKeyframe keyframe) {
  added_ = true;
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
  if (worker_.joinable()) {
    std::unique_lock<std::mutex> lock(mutex_);
    idle_.wait(lock, [this] { return queue_.empty() && !busy_; });
  }
  if (unsolved_loops_) solve(static_cast<std::uint32_t>(graph_.nodes().size() - 1));  // the worker is idle
}

void LoopCloser::solve(std::uint32_t newest) {
  const auto t0 = std::chrono::steady_clock::now();
  graph_.optimize();
  stats_.sum_graph_ms += msSince(t0);
  ++stats_.graph_solves;
  unsolved_loops_ = false;
  last_solve_node_ = newest;
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
  // Candidates stay out of the database unless asked for (LoopOptions::use_candidates).
  std::vector<LoopLandmark> used;
  for (const LoopLandmark& l : in.landmarks) {
    if (l.candidate && !options_.use_candidates) {
      ++stats_.candidates_kept_apart;
      continue;
    }
    ++stats_.landmarks;
    used.push_back(l);
  }
  in.landmarks = std::move(used);
  std::vector<cv::Point2f> corners;
  for (const LoopLandmark& l : in.landmarks)
    corners.emplace_back(static_cast<float>(l.uv.x()), static_cast<float>(l.uv.y()));
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
  // Node index = database id unless localizing only (then the database keeps the map alone).
  const auto node = static_cast<std::uint32_t>(graph_.addKeyframe(in.t_ns, in.p_w_b, in.q_w_b));
  const bool relocalized_before = stats_.relocalized;
  const bool closed = tryLoop(kf, query, node);
  if (extend_) database_.add(std::move(kf));
  ++stats_.keyframes;
  stats_.sum_detect_ms += msSince(t0);
  // Solve at the first loop and a relocalization at once, otherwise at most every
  // graph_solve_interval keyframes while loops come (and at finish()): fixed points of the stream.
  unsolved_loops_ |= closed;
  if (unsolved_loops_ && (stats_.graph_solves == 0 || stats_.relocalized != relocalized_before ||
                          node >= last_solve_node_ + static_cast<std::uint32_t>(options_.graph_solve_interval)))
    solve(node);
  const PoseGraphNode& newest = graph_.nodes()[node];
  std::lock_guard<std::mutex> lock(correction_mutex_);
  correction_ = {loaded_ == 0 || stats_.relocalized, newest};
}

bool LoopCloser::correctNow(const Eigen::Vector3d& p_odom, const Eigen::Quaterniond& q_odom, Eigen::Vector3d& p_w_b,
                            Eigen::Quaterniond& q_w_b) const {
  Correction c;
  {
    std::lock_guard<std::mutex> lock(correction_mutex_);
    c = correction_;
  }
  p_w_b = p_odom;
  q_w_b = q_odom;
  if (loaded_ > 0 && !c.in_map) return false;
  applyCorrection(c.newest, p_odom, q_odom, p_w_b, q_w_b);
  return true;
}

bool LoopCloser::tryLoop(const Keyframe& now, const PlaceQuery& query, std::uint32_t new_node) {
  const TimeNs before = now.t_ns - static_cast<TimeNs>(options_.min_age_s * 1e9);
  if (database_.size() == 0) return false;
  if (loaded_ == 0 && database_.keyframe(0).t_ns >= before) return false;  // nothing old enough yet
  const auto map_ids = static_cast<std::uint32_t>(loaded_);
  for (const PlaceCandidate& c : database_.query(query.descriptors, before, map_ids)) {
    ++stats_.candidates_checked;
    const Keyframe& old = database_.keyframe(c.keyframe);
    const PlaceVerification v = verifyPlace(old, query, T_b_c_, options_.verify);
    if (!v.accepted) continue;
    // The loop against what gravity observes: PnP's roll and pitch must be the odometry's.
    if (tiltDifference(v.q_w_b, now.q_w_b) > options_.max_tilt_rad) {
      ++stats_.refused_by_consistency;
      continue;
    }
    const RelativePose4 rel = relativePose4(old.p_w_b, old.q_w_b, v.p_w_b, v.q_w_b);
    if (c.keyframe < map_ids) {
      if (mapMatch(now, c.keyframe, new_node, rel, c, v)) return true;
      continue;
    }
    // Within the run: against the corrected estimate, a jump beyond the drift is no loop.
    if (!consistent(c.keyframe, new_node, rel, std::max(c.keyframe, solvedNode()))) {
      ++stats_.refused_by_consistency;
      continue;
    }
    graph_.addLoop({c.keyframe, new_node, rel});
    loops_.push_back(
        {c.keyframe, new_node, old.t_ns, now.t_ns, c.votes, v.matches, v.inliers, v.sigma_position_m, rel, false});
    ++stats_.loops;
    return true;
  }
  return false;
}

bool loopWithinDrift(const Eigen::Vector3d& p_old, const Eigen::Quaterniond& q_old, const Eigen::Vector3d& p_now,
                     const Eigen::Quaterniond& q_now, const RelativePose4& rel, double path_m,
                     const LoopOptions& options) {
  const double shift = (p_old + q_old * rel.t_from_to - p_now).norm();
  const double turn = std::abs(wrapAngle(yawOf(q_old) + rel.dyaw - yawOf(q_now)));
  return shift <= options.max_loop_shift_m + options.max_loop_shift_per_m * path_m &&
         turn <= options.max_loop_yaw_rad + options.max_loop_yaw_per_m * path_m;
}

std::uint32_t LoopCloser::solvedNode() const {
  return stats_.graph_solves > 0 ? last_solve_node_ : static_cast<std::uint32_t>(graph_.sessionStart());
}

double LoopCloser::pathLength(std::uint32_t from, std::uint32_t to) const {
  const std::vector<PoseGraphNode>& nodes = graph_.nodes();
  double length = 0;
  for (std::size_t i = std::max<std::size_t>(from, graph_.sessionStart()) + 1; i <= to; ++i)
    length += (nodes[i].p_odom - nodes[i - 1].p_odom).norm();
  return length;
}

bool LoopCloser::consistent(std::uint32_t old_id, std::uint32_t new_node, const RelativePose4& rel,
                            std::uint32_t anchor) const {
  // Where the loop puts the new keyframe: the old keyframe's corrected pose, then `rel`.
  Eigen::Vector3d p_old, p_now;
  Eigen::Quaterniond q_old, q_now;
  graph_.correctedPose(old_id, p_old, q_old);
  graph_.correctedPose(new_node, p_now, q_now);
  return loopWithinDrift(p_old, q_old, p_now, q_now, rel, pathLength(anchor, new_node), options_);
}

bool LoopCloser::mapMatch(const Keyframe& now, std::uint32_t old_id, std::uint32_t new_node, const RelativePose4& rel,
                          const PlaceCandidate& c, const PlaceVerification& v) {
  // Where the match puts the new keyframe in the map: the old keyframe's map pose, then `rel`.
  Eigen::Vector3d p_old, p_now;
  Eigen::Quaterniond q_old, q_now;
  graph_.correctedPose(old_id, p_old, q_old);
  graph_.correctedPose(new_node, p_now, q_now);
  const Eigen::Vector3d p_map = p_old + q_old * rel.t_from_to;
  const double yaw_map = wrapAngle(yawOf(q_old) + rel.dyaw);
  const LoopEvent event{
      old_id, new_node, database_.keyframe(old_id).t_ns, now.t_ns, c.votes, v.matches, v.inliers, v.sigma_position_m,
      rel,    true};
  if (stats_.relocalized) {  // tied to the map already: against the current map pose
    if (!consistent(old_id, new_node, rel, solvedNode())) {
      ++stats_.refused_by_consistency;
      return false;
    }
    graph_.addLoop({old_id, new_node, rel});
    loops_.push_back(event);
    ++stats_.loops;
    ++stats_.map_loops;
    return true;
  }
  // Not yet: the transform map <- odometry this match implies, confirmed by a later keyframe's.
  const double yaw = wrapAngle(yaw_map - yawOf(q_now));
  const Eigen::Vector3d t = p_map - rotZ(yaw) * p_now;
  if (pending_.valid && pending_.node == new_node) return false;  // one hypothesis per keyframe (the best)
  const bool confirms = pending_.valid &&
                        new_node - pending_.node <= static_cast<std::uint32_t>(options_.relocalization_window) &&
                        std::abs(wrapAngle(yaw - pending_.yaw)) < options_.relocalization_tolerance_rad &&
                        (t - pending_.t).norm() < options_.relocalization_tolerance_m;
  if (!confirms) {
    if (pending_.valid) ++stats_.relocalizations_unconfirmed;
    pending_ = {true, yaw, t, new_node, event};
    return false;
  }
  graph_.relocalize(yaw, t);
  for (const LoopEvent& e : {pending_.event, event}) {
    graph_.addLoop({e.old_keyframe, e.new_keyframe, e.relative});
    loops_.push_back(e);
    ++stats_.loops;
    ++stats_.map_loops;
  }
  pending_.valid = false;
  stats_.relocalized = true;
  stats_.first_relocalization_t_ns = now.t_ns;
  return true;
}

std::vector<std::pair<std::uint64_t, Eigen::Vector3d>> LoopCloser::correctedLandmarks() const {
  const std::size_t n = loaded_ > 0 && !stats_.relocalized ? loaded_ : database_.size();
  std::vector<std::pair<std::uint64_t, Eigen::Vector3d>> out;
  std::set<std::pair<bool, std::uint64_t>> seen;  // landmark ids restart with each session
  for (std::size_t i = 0; i < n; ++i)
    for (const KeyframeLandmark& l : database_.keyframe(static_cast<std::uint32_t>(i)).landmarks)
      if (seen.insert({i < loaded_, l.id}).second) out.emplace_back(l.id, graph_.correctedPoint(i, l.p_w));
  return out;
}

SavedMap LoopCloser::savedMap() const {
  // A run that loaded a map but never tied itself to it has its keyframes in another frame: the
  // map is saved as loaded. Localizing only, the database holds the map alone.
  const std::size_t n = loaded_ > 0 && !stats_.relocalized ? loaded_ : database_.size();
  SavedMap m;
  m.keyframes.assign(database_.keyframes().begin(), database_.keyframes().begin() + static_cast<std::ptrdiff_t>(n));
  m.nodes.assign(graph_.nodes().begin(), graph_.nodes().begin() + static_cast<std::ptrdiff_t>(n));
  for (const LoopEdge& l : graph_.loops())
    if (l.from < n && l.to < n) m.loops.push_back(l);
  for (PoseGraphNode& node : m.nodes) node.fixed = false;
  if (!m.nodes.empty()) m.nodes.front().fixed = true;
  return m;
}

}  // namespace idyvins::map
