#include "map/pose_graph.h"

#include <ceres/ceres.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/so3.h"
#include "map/four_dof_edge.h"

namespace idyvins::map {

double yawOf(const Eigen::Quaterniond& q_w_b) {
  const Eigen::Matrix3d R = q_w_b.toRotationMatrix();
  return std::atan2(R(1, 0), R(0, 0));
}

Eigen::Matrix3d rotZ(double yaw) { return Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix(); }

double wrapAngle(double angle) {
  const double a = std::remainder(angle, 2.0 * M_PI);  // [-pi, pi]
  return a <= -M_PI ? a + 2.0 * M_PI : a;
}

Eigen::Matrix3d tiltOf(const Eigen::Quaterniond& q_w_b) {
  return rotZ(yawOf(q_w_b)).transpose() * q_w_b.toRotationMatrix();
}

void applyCorrection(const PoseGraphNode& n, const Eigen::Vector3d& p_odom, const Eigen::Quaterniond& q_odom,
                     Eigen::Vector3d& p_w_b, Eigen::Quaterniond& q_w_b) {
  const Eigen::Matrix3d R = rotZ(wrapAngle(n.yaw - yawOf(n.q_odom)));
  p_w_b = R * (p_odom - n.p_odom) + n.p;
  q_w_b = Eigen::Quaterniond(R * q_odom.toRotationMatrix()).normalized();
}

RelativePose4 relativePose4(const Eigen::Vector3d& p_w_from, const Eigen::Quaterniond& q_w_from,
                            const Eigen::Vector3d& p_w_to, const Eigen::Quaterniond& q_w_to) {
  RelativePose4 r;
  r.t_from_to = q_w_from.conjugate() * (p_w_to - p_w_from);
  r.dyaw = wrapAngle(yawOf(q_w_to) - yawOf(q_w_from));
  return r;
}

FourDofEdgeCost::FourDofEdgeCost(const RelativePose4& measured, const Eigen::Matrix3d& tilt_i, double sigma_t,
                                 double sigma_yaw)
    : measured_(measured), tilt_i_(tilt_i), w_t_(1.0 / sigma_t), w_yaw_(1.0 / sigma_yaw) {}

bool FourDofEdgeCost::Evaluate(double const* const* parameters, double* residuals, double** jacobians) const {
  const Eigen::Map<const Eigen::Vector3d> p_i(parameters[0]), p_j(parameters[2]);
  const double yaw_i = parameters[1][0], yaw_j = parameters[3][0];
  const Eigen::Matrix3d Rz_t = rotZ(yaw_i).transpose();
  const Eigen::Matrix3d A = tilt_i_.transpose() * Rz_t;  // R_i^T
  const Eigen::Vector3d d = p_j - p_i;
  Eigen::Map<Eigen::Vector4d> r(residuals);
  r.head<3>() = w_t_ * (A * d - measured_.t_from_to);
  r(3) = w_yaw_ * wrapAngle(yaw_j - yaw_i - measured_.dyaw);
  if (!jacobians) return true;
  if (jacobians[0]) {  // d r / d p_i
    Eigen::Map<Eigen::Matrix<double, 4, 3, Eigen::RowMajor>> J(jacobians[0]);
    J.setZero();
    J.topRows<3>() = -w_t_ * A;
  }
  if (jacobians[1]) {  // d r / d yaw_i: d(Rz^T)/dyaw = -[e_z]x Rz^T
    Eigen::Map<Eigen::Vector4d> J(jacobians[1]);
    J.head<3>() = -w_t_ * tilt_i_.transpose() * hat(Eigen::Vector3d::UnitZ()) * Rz_t * d;
    J(3) = -w_yaw_;
  }
  if (jacobians[2]) {  // d r / d p_j
    Eigen::Map<Eigen::Matrix<double, 4, 3, Eigen::RowMajor>> J(jacobians[2]);
    J.setZero();
    J.topRows<3>() = w_t_ * A;
  }
  if (jacobians[3]) {  // d r / d yaw_j
    Eigen::Map<Eigen::Vector4d> J(jacobians[3]);
    J.setZero();
    J(3) = w_yaw_;
  }
  return true;
}

PoseGraph::PoseGraph(const PoseGraphOptions& options) : options_(options) {}

std::size_t PoseGraph::addKeyframe(TimeNs t_ns, const Eigen::Vector3d& p_odom, const Eigen::Quaterniond& q_odom) {
  PoseGraphNode n;
  n.t_ns = t_ns;
  n.p_odom = p_odom;
  n.q_odom = q_odom.normalized();
  n.p = p_odom;
  n.yaw = yawOf(n.q_odom);
  const bool first = nodes_.size() == session_start_;
  if (!first) {  // the newest node's correction (every node added since the last solve has it too)
    Eigen::Quaterniond q;
    applyCorrection(nodes_.back(), p_odom, n.q_odom, n.p, q);
    n.yaw = yawOf(q);
  }
  n.fixed = first;
  nodes_.push_back(n);
  return nodes_.size() - 1;
}

void PoseGraph::addLoop(const LoopEdge& loop) { loops_.push_back(loop); }

void PoseGraph::loadMap(const std::vector<PoseGraphNode>& nodes, const std::vector<LoopEdge>& loops) {
  if (!nodes_.empty()) throw std::logic_error("PoseGraph::loadMap after keyframes were added");
  nodes_ = nodes;
  for (PoseGraphNode& n : nodes_) n.fixed = true;
  loops_ = loops;
  session_start_ = nodes_.size();
}

void PoseGraph::relocalize(double yaw, const Eigen::Vector3d& t) {
  const Eigen::Matrix3d R = rotZ(yaw);
  for (std::size_t i = session_start_; i < nodes_.size(); ++i) {
    nodes_[i].p = R * nodes_[i].p + t;
    nodes_[i].yaw = wrapAngle(nodes_[i].yaw + yaw);
  }
  if (session_start_ < nodes_.size()) nodes_[session_start_].fixed = false;
}

PoseGraphSolve PoseGraph::optimize() {
  PoseGraphSolve out;
  if (nodes_.size() < 2) return out;
  ceres::Problem problem;
  const int k = options_.odometry_neighbours;
  for (std::size_t j = 1; j < nodes_.size(); ++j) {
    // Odometry edges within a session only; the loaded map's nodes are fixed (no edges among them).
    if (j < session_start_) continue;
    const std::size_t first =
        j == session_start_ ? j : std::max(session_start_, j > static_cast<std::size_t>(k) ? j - k : 0);
    for (std::size_t i = first; i < j; ++i) {
      const PoseGraphNode &a = nodes_[i], &b = nodes_[j];
      problem.AddResidualBlock(
          new FourDofEdgeCost(relativePose4(a.p_odom, a.q_odom, b.p_odom, b.q_odom), tiltOf(a.q_odom),
                              options_.odometry_sigma_t, options_.odometry_sigma_yaw),
          nullptr, nodes_[i].p.data(), &nodes_[i].yaw, nodes_[j].p.data(), &nodes_[j].yaw);
    }
  }
  for (const LoopEdge& l : loops_) {
    if (nodes_[l.from].fixed && nodes_[l.to].fixed) continue;  // the loaded map's own loops
    problem.AddResidualBlock(
        new FourDofEdgeCost(l.measured, tiltOf(nodes_[l.from].q_odom), options_.loop_sigma_t, options_.loop_sigma_yaw),
        new ceres::HuberLoss(options_.loop_huber), nodes_[l.from].p.data(), &nodes_[l.from].yaw, nodes_[l.to].p.data(),
        &nodes_[l.to].yaw);
  }
  for (PoseGraphNode& n : nodes_) {
    if (!n.fixed || !problem.HasParameterBlock(n.p.data())) continue;  // a map node no edge reaches
    problem.SetParameterBlockConstant(n.p.data());
    problem.SetParameterBlockConstant(&n.yaw);
  }
  ceres::Solver::Options o;
  o.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  o.max_num_iterations = options_.max_iterations;
  o.num_threads = 1;
  o.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(o, &problem, &summary);
  for (PoseGraphNode& n : nodes_) n.yaw = wrapAngle(n.yaw);
  out.iterations = static_cast<int>(summary.iterations.size());
  out.initial_cost = summary.initial_cost;
  out.final_cost = summary.final_cost;
  out.converged = summary.termination_type == ceres::CONVERGENCE;
  return out;
}

Eigen::Vector3d PoseGraph::correctedPoint(std::size_t i, const Eigen::Vector3d& p_odom) const {
  const PoseGraphNode& n = nodes_.at(i);
  return rotZ(wrapAngle(n.yaw - yawOf(n.q_odom))) * (p_odom - n.p_odom) + n.p;
}

void PoseGraph::correctedPose(std::size_t i, Eigen::Vector3d& p_w_b, Eigen::Quaterniond& q_w_b) const {
  const PoseGraphNode& n = nodes_.at(i);
  p_w_b = n.p;
  q_w_b = Eigen::Quaterniond(rotZ(n.yaw) * tiltOf(n.q_odom)).normalized();
}

void PoseGraph::correctedAt(TimeNs t_ns, const Eigen::Vector3d& p_odom, const Eigen::Quaterniond& q_odom,
                            Eigen::Vector3d& p_w_b, Eigen::Quaterniond& q_w_b) const {
  p_w_b = p_odom;
  q_w_b = q_odom;
  if (nodes_.size() <= session_start_) return;
  const auto begin = nodes_.begin() + static_cast<std::ptrdiff_t>(session_start_);
  const auto it =
      std::upper_bound(begin, nodes_.end(), t_ns, [](TimeNs t, const PoseGraphNode& n) { return t < n.t_ns; });
  applyCorrection(it == begin ? *begin : *std::prev(it), p_odom, q_odom, p_w_b, q_w_b);
}

}  // namespace idyvins::map
