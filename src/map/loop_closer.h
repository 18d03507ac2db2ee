#pragma once
// Loop closure (DESIGN §7): keyframes that left the odometry window go into the keyframe
// database; each new one is looked up among the older ones (appearance), checked by PnP
// on the candidate's static landmarks (geometry) and, when it holds, joined to it by a
// loop edge in the 4-DoF pose graph, which is then solved. Runs on its own thread (or on
// the caller's); keyframes are handled in the order given, so every result is the same
// whatever the thread timing (the corrected trajectory is read after finish()).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <condition_variable>
#include <deque>
#include <memory>
#include <mutex>
#include <opencv2/core.hpp>
#include <thread>
#include <vector>

#include "camera/camera_model.h"
#include "core/time.h"
#include "map/keyframe_database.h"
#include "map/map_io.h"
#include "map/place_verifier.h"
#include "map/pose_graph.h"

namespace idyvins::map {

/// A landmark observed by the keyframe: static, or a dynamic candidate not yet cleared (the
/// caller passes no eliminated or confirmed-dynamic one). Candidates are kept apart: counted,
/// used only with LoopOptions::use_candidates.
struct LoopLandmark {
  std::uint64_t id = 0;
  Eigen::Vector3d p_w = Eigen::Vector3d::Zero();
  Eigen::Vector2d uv = Eigen::Vector2d::Zero(), xy = Eigen::Vector2d::Zero();
  bool candidate = false;
};

/// One keyframe handed to the loop closer.
struct LoopKeyframe {
  TimeNs t_ns = 0;
  Eigen::Vector3d p_w_b = Eigen::Vector3d::Zero();  ///< odometry pose
  Eigen::Quaterniond q_w_b = Eigen::Quaterniond::Identity();
  cv::Mat left;  ///< the left image (gray)
  std::vector<LoopLandmark> landmarks;
};

/// A loop that was closed.
struct LoopEvent {
  std::uint32_t old_keyframe = 0, new_keyframe = 0;  ///< pose-graph node indices
  TimeNs old_t_ns = 0, new_t_ns = 0;
  int votes = 0, matches = 0, inliers = 0;
  double sigma_position_m = 0;  ///< PnP position uncertainty (PlaceVerification)
  RelativePose4 relative;       ///< new keyframe in the old one's frame (from PnP)
  bool to_map = false;          ///< the old keyframe is from a loaded map (a relocalization)
};

struct LoopStats {
  std::size_t keyframes = 0, keyframes_skipped = 0, candidates_checked = 0, loops = 0, refused_by_consistency = 0;
  double sum_detect_ms = 0;  ///< descriptors, lookup, geometric check
  double sum_graph_ms = 0;   ///< pose-graph solves
  std::size_t graph_solves = 0;
  std::size_t landmarks = 0, candidates_kept_apart = 0;  ///< handed over with the keyframes taken
  // With a loaded map (loadMap):
  std::size_t map_keyframes = 0;                ///< keyframes loaded
  std::size_t map_loops = 0;                    ///< loops to the map's keyframes (relocalizations included)
  std::size_t relocalizations_unconfirmed = 0;  ///< map matches not confirmed by the next keyframes
  bool relocalized = false;
  TimeNs first_relocalization_t_ns = 0;  ///< the keyframe that confirmed the first relocalization
};

/// Whether a loop `rel` from the old keyframe (corrected pose p_old, q_old) puts the new keyframe
/// within the drift allowance of its corrected pose (p_now, q_now) after `path_m` metres of
/// odometry since the graph last fixed it: LoopOptions::max_loop_shift_m + max_loop_shift_per_m
/// * path_m in position, max_loop_yaw_rad + max_loop_yaw_per_m * path_m in yaw.
bool loopWithinDrift(const Eigen::Vector3d& p_old, const Eigen::Quaterniond& q_old, const Eigen::Vector3d& p_now,
                     const Eigen::Quaterniond& q_now, const RelativePose4& rel, double path_m,
                     const LoopOptions& options);

class LoopCloser {
 public:
  /// `left_camera` lifts the extra corners; T_b_c the left camera in the body. threaded: a worker thread.
  LoopCloser(const LoopOptions& options, std::unique_ptr<camera::CameraModel> left_camera,
             const Eigen::Isometry3d& T_b_c, bool threaded);
  ~LoopCloser();
  LoopCloser(const LoopCloser&) = delete;
  LoopCloser& operator=(const LoopCloser&) = delete;

  /// Starts in a saved map's frame (before the first add()): its keyframes join the database and
  /// the pose graph (fixed); the run's keyframes are matched against them whatever their age. The
  /// first match to the map that the next keyframes confirm (the same map <- odometry transform
  /// within LoopOptions' relocalization tolerances) ties the run to the map (relocalization);
  /// later ones are loops. `extend` false: localization only, the run's keyframes are not added
  /// to the database (the map stays as loaded). Throws std::logic_error after add().
  void loadMap(const SavedMap& map, bool extend);

  /// Takes a keyframe (skipped when it is too near the last one taken: LoopOptions).
  void add(LoopKeyframe keyframe);
  /// Waits until every keyframe given has been handled (call before reading results).
  void finish();

  /// Live use (any thread, while keyframes are handled): an odometry pose moved by the newest
  /// correction the loop closer has finished (that of its newest pose-graph node). False, pose
  /// unchanged, while a loaded map has not been relocalized in (the pose is in no map frame yet).
  /// Offline results read the final graph instead (PoseGraph::correctedAt after finish()).
  bool correctNow(const Eigen::Vector3d& p_odom, const Eigen::Quaterniond& q_odom, Eigen::Vector3d& p_w_b,
                  Eigen::Quaterniond& q_w_b) const;

  const std::vector<LoopEvent>& loops() const { return loops_; }
  const PoseGraph& graph() const { return graph_; }
  const KeyframeDatabase& database() const { return database_; }
  const LoopStats& stats() const { return stats_; }
  /// The keyframe database and pose graph, as saveMap writes them (after finish()).
  SavedMap savedMap() const;
  /// The database's static landmarks moved by the correction of the keyframe that first saw
  /// each (the static map re-anchored to the corrected poses; one point per landmark id and
  /// session), in database order. Without a relocalization, a loaded map's only.
  std::vector<std::pair<std::uint64_t, Eigen::Vector3d>> correctedLandmarks() const;

 private:
  void run();
  void handle(LoopKeyframe& keyframe);
  bool tryLoop(const Keyframe& now, const PlaceQuery& query, std::uint32_t new_node);
  void solve(std::uint32_t newest);  ///< optimizes the pose graph (newest: the node handled last)
  /// The newest node the last solve saw (the session's first before any solve).
  std::uint32_t solvedNode() const;
  /// Odometry path length (m) from node `from` to node `to` within the session.
  double pathLength(std::uint32_t from, std::uint32_t to) const;
  /// Whether a loop old_id -> new_node moves the new node's corrected pose by no more than the
  /// drift allowed for the path since `anchor` (LoopOptions::max_loop_shift_m and siblings).
  bool consistent(std::uint32_t old_id, std::uint32_t new_node, const RelativePose4& rel, std::uint32_t anchor) const;
  /// A verified match of the new node to a map keyframe (PnP pose p_w_b/q_w_b in the old
  /// keyframe's odometry frame): relocalizes once confirmed, else a loop checked against the
  /// current map pose. True when it became a loop edge.
  bool mapMatch(const Keyframe& now, std::uint32_t old_id, std::uint32_t new_node, const RelativePose4& rel,
                const PlaceCandidate& c, const PlaceVerification& v);

  LoopOptions options_;
  std::unique_ptr<camera::CameraModel> camera_;
  Eigen::Isometry3d T_b_c_;
  KeyframeDatabase database_;
  PoseGraph graph_;
  std::vector<LoopEvent> loops_;
  LoopStats stats_;
  std::size_t loaded_ = 0;       ///< keyframes from a loaded map (database ids below it)
  bool unsolved_loops_ = false;  ///< loop edges added since the last solve
  std::uint32_t last_solve_node_ = 0;
  bool extend_ = true;
  bool added_ = false;
  /// An unconfirmed relocalization: the map <- odometry transform one keyframe's match implied.
  struct Hypothesis {
    bool valid = false;
    double yaw = 0;
    Eigen::Vector3d t = Eigen::Vector3d::Zero();
    std::uint32_t node = 0;
    LoopEvent event;
  } pending_;
  bool have_last_ = false;  ///< the last keyframe taken (add(), caller's thread)
  Eigen::Vector3d last_p_ = Eigen::Vector3d::Zero();
  Eigen::Quaterniond last_q_ = Eigen::Quaterniond::Identity();
  /// The newest node's correction, published after each keyframe for correctNow().
  struct Correction {
    bool in_map = true;
    PoseGraphNode newest;  ///< identity correction until a keyframe is handled
  };
  mutable std::mutex correction_mutex_;
  Correction correction_;
  std::mutex mutex_;
  std::condition_variable wake_, idle_;
  std::deque<LoopKeyframe> queue_;
  bool busy_ = false, stopping_ = false;
  std::thread worker_;
};

}  // namespace idyvins::map
