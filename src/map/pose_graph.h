#pragma once
// The 4-DoF pose graph of loop closure (DESIGN §7): keyframe positions and yaws are free,
// roll and pitch stay as the odometry estimated them (observable from gravity). Odometry
// edges tie each keyframe to its predecessors, loop edges to the keyframe a place was
// recognised in; loop edges carry a robust loss so one wrong loop cannot bend the graph.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstddef>
#include <vector>

#include "core/time.h"
#include "map/loop_options.h"

namespace idyvins::map {

/// Yaw (rad, about world z) of a body-to-world rotation, ZYX convention: q = Rz(yaw) Ry(pitch) Rx(roll).
double yawOf(const Eigen::Quaterniond& q_w_b);
/// Rotation about z by `yaw` rad.
Eigen::Matrix3d rotZ(double yaw);
/// `angle` wrapped to (-pi, pi].
double wrapAngle(double angle);
/// Ry(pitch) Rx(roll) of a body-to-world rotation: Rz(yaw)^T R (what gravity observes).
Eigen::Matrix3d tiltOf(const Eigen::Quaterniond& q_w_b);

/// A relative pose in 4-DoF: translation of `to` in `from`'s body frame, yaw(to) - yaw(from).
struct RelativePose4 {
  Eigen::Vector3d t_from_to = Eigen::Vector3d::Zero();
  double dyaw = 0;
};
/// The 4-DoF relative pose between two full poses (roll and pitch of `from` kept in the translation).
RelativePose4 relativePose4(const Eigen::Vector3d& p_w_from, const Eigen::Quaterniond& q_w_from,
                            const Eigen::Vector3d& p_w_to, const Eigen::Quaterniond& q_w_to);

/// One keyframe in the graph: its odometry pose and its corrected pose.
struct PoseGraphNode {
  TimeNs t_ns = 0;
  Eigen::Vector3d p_odom = Eigen::Vector3d::Zero();
  Eigen::Quaterniond q_odom = Eigen::Quaterniond::Identity();
  Eigen::Vector3d p = Eigen::Vector3d::Zero();  ///< corrected position
  double yaw = 0;                               ///< corrected yaw
  bool fixed = false;                           ///< held during optimization (the first node, a loaded map)
};

/// An odometry pose moved by node n's correction: yaw turned by n's yaw change about n,
/// position kept at the same offset from n.
void applyCorrection(const PoseGraphNode& n, const Eigen::Vector3d& p_odom, const Eigen::Quaterniond& q_odom,
                     Eigen::Vector3d& p_w_b, Eigen::Quaterniond& q_w_b);

struct LoopEdge {
  std::size_t from = 0, to = 0;  ///< node indices, from the older keyframe to the newer
  RelativePose4 measured;
};

struct PoseGraphSolve {
  int iterations = 0;
  double initial_cost = 0, final_cost = 0;
  bool converged = false;
};

/// The graph. Not thread-safe; the system solves it on its own thread from a copy.
class PoseGraph {
 public:
  explicit PoseGraph(const PoseGraphOptions& options = {});

  /// Appends a keyframe with its odometry pose; its corrected pose starts as the odometry
  /// pose moved by the correction of the session's newest node (none for the session's first
  /// node, which is held fixed: the gauge until the session is tied to a map). Returns its index.
  std::size_t addKeyframe(TimeNs t_ns, const Eigen::Vector3d& p_odom, const Eigen::Quaterniond& q_odom);
  void addLoop(const LoopEdge& loop);

  /// A loaded map: appends its nodes (held fixed) and loop edges before any keyframe of this run,
  /// and starts a new session: the run's keyframes (in their own odometry frame, unrelated to the
  /// map's) follow. Throws std::logic_error after addKeyframe.
  void loadMap(const std::vector<PoseGraphNode>& nodes, const std::vector<LoopEdge>& loops);
  /// Ties the session to the map: every session node's corrected pose moved by the 4-DoF
  /// transform map <- odometry (yaw about z, then translation); the session's first node is freed.
  void relocalize(double yaw, const Eigen::Vector3d& t);
  /// First node of the current session (0 without a loaded map).
  std::size_t sessionStart() const { return session_start_; }

  /// Optimizes positions and yaws (deterministic: one thread, fixed iteration limit).
  PoseGraphSolve optimize();

  const std::vector<PoseGraphNode>& nodes() const { return nodes_; }
  const std::vector<LoopEdge>& loops() const { return loops_; }
  /// A point of node i's odometry frame moved by node i's correction (landmarks it anchors).
  Eigen::Vector3d correctedPoint(std::size_t i, const Eigen::Vector3d& p_odom) const;
  /// Corrected full pose of node i (its odometry roll and pitch, corrected yaw and position).
  void correctedPose(std::size_t i, Eigen::Vector3d& p_w_b, Eigen::Quaterniond& q_w_b) const;
  /// An odometry pose at t_ns moved by the correction of the current session's newest node at or
  /// before t_ns (the session's first node's for earlier times): yaw turned by the node's yaw
  /// change, position kept at the same offset from the node (unchanged without nodes). Poses newer
  /// than the newest node get its correction, as new keyframes do.
  void correctedAt(TimeNs t_ns, const Eigen::Vector3d& p_odom, const Eigen::Quaterniond& q_odom, Eigen::Vector3d& p_w_b,
                   Eigen::Quaterniond& q_w_b) const;

 private:
  PoseGraphOptions options_;
  std::vector<PoseGraphNode> nodes_;
  std::vector<LoopEdge> loops_;
  std::size_t session_start_ = 0;
};

}  // namespace idyvins::map
