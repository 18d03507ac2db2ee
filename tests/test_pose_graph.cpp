// The 4-DoF pose graph of loop closure: its edge Jacobians against numerical ones, a drifted
// loop corrected by one loop edge, one wrong loop among right ones held off by the robust loss;
// the drift allowance a loop must fall within.

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "jacobian_check.h"
#include "map/four_dof_edge.h"
#include "map/loop_closer.h"
#include "map/pose_graph.h"

namespace idyvins::map {
namespace {

Eigen::Quaterniond ypr(double yaw, double pitch, double roll) {
  return Eigen::Quaterniond(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
                            Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                            Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()));
}

TEST(PoseGraph, YawAndWrapConventions) {
  EXPECT_NEAR(yawOf(ypr(0.7, 0.2, -0.1)), 0.7, 1e-12);
  EXPECT_NEAR(yawOf(ypr(-3.0, -0.3, 0.4)), -3.0, 1e-12);
  EXPECT_NEAR(wrapAngle(3 * M_PI / 2), -M_PI / 2, 1e-12);
  EXPECT_NEAR(wrapAngle(-M_PI), M_PI, 1e-12);
  const RelativePose4 r = relativePose4({1, 2, 3}, ypr(3.0, 0.1, 0.2), {2, 1, 3.5}, ypr(-3.0, 0.0, 0.1));
  EXPECT_NEAR(r.dyaw, 2 * M_PI - 6.0, 1e-12);
  EXPECT_TRUE((ypr(3.0, 0.1, 0.2) * r.t_from_to).isApprox(Eigen::Vector3d(1, -1, 0.5), 1e-12));
}

TEST(PoseGraph, EdgeJacobiansMatchNumerical) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int trial = 0; trial < 20; ++trial) {
    const Eigen::Matrix3d tilt = (Eigen::AngleAxisd(0.3 * u(rng), Eigen::Vector3d::UnitY()) *
                                  Eigen::AngleAxisd(0.3 * u(rng), Eigen::Vector3d::UnitX()))
                                     .toRotationMatrix();
    const RelativePose4 meas{Eigen::Vector3d(u(rng), u(rng), u(rng)), 0.5 * u(rng)};
    const FourDofEdgeCost cost(meas, tilt, 0.05, 0.01);
    Eigen::Vector3d p_i(u(rng), u(rng), u(rng)), p_j(3 * u(rng), 3 * u(rng), u(rng));
    double yaw_i = 3 * u(rng), yaw_j = 3 * u(rng);
    const double* params[] = {p_i.data(), &yaw_i, p_j.data(), &yaw_j};
    Eigen::Vector4d r;
    Eigen::Matrix<double, 4, 3, Eigen::RowMajor> Jpi, Jpj;
    Eigen::Vector4d Jyi, Jyj;
    double* jac[] = {Jpi.data(), Jyi.data(), Jpj.data(), Jyj.data()};
    ASSERT_TRUE(cost.Evaluate(params, r.data(), jac));
    const auto residual = [&](const Eigen::Vector3d& pi, double yi, const Eigen::Vector3d& pj, double yj) {
      const double* ps[] = {pi.data(), &yi, pj.data(), &yj};
      Eigen::Vector4d out;
      cost.Evaluate(ps, out.data(), nullptr);
      return Eigen::VectorXd(out);
    };
    test::expectJacobianNear(
        Jpi, test::numericJacobian([&](const Eigen::VectorXd& d) { return residual(p_i + d, yaw_i, p_j, yaw_j); }, 3),
        1e-6, "p_i");
    test::expectJacobianNear(
        Jyi,
        test::numericJacobian([&](const Eigen::VectorXd& d) { return residual(p_i, yaw_i + d(0), p_j, yaw_j); }, 1),
        1e-6, "yaw_i");
    test::expectJacobianNear(
        Jpj, test::numericJacobian([&](const Eigen::VectorXd& d) { return residual(p_i, yaw_i, p_j + d, yaw_j); }, 3),
        1e-6, "p_j");
    test::expectJacobianNear(
        Jyj,
        test::numericJacobian([&](const Eigen::VectorXd& d) { return residual(p_i, yaw_i, p_j, yaw_j + d(0)); }, 1),
        1e-6, "yaw_j");
  }
}

/// Two laps of a 20 m x 10 m block (yaw turning, slight roll and pitch), as truth and as an
/// odometry that drifts in yaw and position.
struct Laps {
  std::vector<Eigen::Vector3d> p_true, p_odom;
  std::vector<Eigen::Quaterniond> q_true, q_odom;
};
Laps twoLaps() {
  Laps l;
  const int n = 240;
  for (int k = 0; k < n; ++k) {
    const double s = 2 * M_PI * 2.0 * k / n;  // two laps
    const Eigen::Vector3d p(10 * std::cos(s), 5 * std::sin(s), 0.3 * std::sin(3 * s));
    const double yaw = std::atan2(5 * std::cos(s), -10 * std::sin(s));
    l.p_true.push_back(p);
    l.q_true.push_back(ypr(yaw, 0.05 * std::sin(s), 0.03 * std::cos(2 * s)));
    if (k == 0) {
      l.p_odom.push_back(p);
      l.q_odom.push_back(l.q_true[0]);
      continue;
    }
    // odometry integrates each true increment with a 1 % scale error and a yaw bias of 1.5 mrad
    const RelativePose4 step = relativePose4(l.p_true[k - 1], l.q_true[k - 1], p, l.q_true[k]);
    l.p_odom.push_back(l.p_odom.back() + l.q_odom.back() * (1.01 * step.t_from_to));
    l.q_odom.push_back(Eigen::Quaterniond(rotZ(step.dyaw + 0.0015) * rotZ(yawOf(l.q_odom.back())) *
                                          rotZ(yawOf(l.q_true[k])).transpose() * l.q_true[k].toRotationMatrix()));
  }
  return l;
}

double rmse(const std::vector<Eigen::Vector3d>& a, const std::vector<Eigen::Vector3d>& b) {
  double s = 0;
  for (std::size_t i = 0; i < a.size(); ++i) s += (a[i] - b[i]).squaredNorm();
  return std::sqrt(s / static_cast<double>(a.size()));
}

TEST(PoseGraph, LoopEdgesCorrectADriftedTrajectory) {
  const Laps l = twoLaps();
  PoseGraph graph;
  for (std::size_t k = 0; k < l.p_odom.size(); ++k) graph.addKeyframe(static_cast<TimeNs>(k), l.p_odom[k], l.q_odom[k]);
  // loops: the second lap sees the places of the first (true relative poses, as PnP would measure them)
  const std::size_t half = l.p_odom.size() / 2;
  for (std::size_t k = half; k < l.p_odom.size(); k += 10)
    graph.addLoop({k - half, k, relativePose4(l.p_true[k - half], l.q_true[k - half], l.p_true[k], l.q_true[k])});
  const PoseGraphSolve solve = graph.optimize();
  EXPECT_TRUE(solve.converged);
  EXPECT_LT(solve.final_cost, 0.5 * solve.initial_cost);
  std::vector<Eigen::Vector3d> corrected;
  for (std::size_t k = 0; k < l.p_odom.size(); ++k) {
    Eigen::Vector3d p;
    Eigen::Quaterniond q;
    graph.correctedPose(k, p, q);
    corrected.push_back(p);
    // the yaw bias is spread over each lap: the worst heading error falls from 0.36 rad to that of half a lap's drift
    EXPECT_LT(Eigen::AngleAxisd(q.conjugate() * l.q_true[k]).angle(), 0.1) << k;
  }
  const double before = rmse(l.p_odom, l.p_true), after = rmse(corrected, l.p_true);
  // what loops can correct: the second lap onto the first, each lap closed; the drift inside
  // the first lap is only spread (least squares), so the RMSE falls 4-5x, the end 10x
  EXPECT_GT(before, 1.0);
  EXPECT_LT(after, 0.3 * before) << "before " << before << " m, after " << after << " m";
  EXPECT_LT((corrected.back() - l.p_true.back()).norm(), 0.1 * (l.p_odom.back() - l.p_true.back()).norm());
  // a keyframe after the optimization is moved by the newest node's correction
  Eigen::Vector3d p;
  Eigen::Quaterniond q;
  graph.correctedAt(graph.nodes().back().t_ns + 1, l.p_odom.back(), l.q_odom.back(), p, q);
  EXPECT_LT((p - corrected.back()).norm(), 1e-9);
}

TEST(PoseGraph, OneWrongLoopIsHeldOffByTheRobustLoss) {
  const Laps l = twoLaps();
  const std::size_t half = l.p_odom.size() / 2;
  PoseGraph right, with_wrong;
  for (std::size_t k = 0; k < l.p_odom.size(); ++k) {
    right.addKeyframe(static_cast<TimeNs>(k), l.p_odom[k], l.q_odom[k]);
    with_wrong.addKeyframe(static_cast<TimeNs>(k), l.p_odom[k], l.q_odom[k]);
  }
  for (std::size_t k = half; k < l.p_odom.size(); k += 10) {
    const LoopEdge e{k - half, k, relativePose4(l.p_true[k - half], l.q_true[k - half], l.p_true[k], l.q_true[k])};
    right.addLoop(e);
    with_wrong.addLoop(e);
  }
  // a place confused with another 8 m away, rotated by 90 degrees (a parked car seen twice)
  with_wrong.addLoop({20, half + 90, RelativePose4{Eigen::Vector3d(8, 0, 0), M_PI / 2}});
  right.optimize();
  with_wrong.optimize();
  std::vector<Eigen::Vector3d> a, b;
  for (std::size_t k = 0; k < l.p_odom.size(); ++k) {
    Eigen::Vector3d p;
    Eigen::Quaterniond q;
    right.correctedPose(k, p, q);
    a.push_back(p);
    with_wrong.correctedPose(k, p, q);
    b.push_back(p);
  }
  EXPECT_LT(rmse(b, l.p_true), 2.0 * rmse(a, l.p_true) + 0.05);
}

}  // namespace
}  // namespace idyvins::map

namespace idyvins::map {
namespace {

TEST(PoseGraph, ASessionRelocalizedInALoadedMapLandsOnItAndLeavesTheMapAlone) {
  // The map: the first lap's true poses. The run: the second lap's drifting odometry in its own
  // frame (turned by 1 rad about z and shifted), with times that overlap the map's.
  const Laps l = twoLaps();
  const std::size_t half = l.p_odom.size() / 2;
  std::vector<PoseGraphNode> map_nodes;
  for (std::size_t k = 0; k < half; ++k) {
    PoseGraphNode n;
    n.t_ns = static_cast<TimeNs>(k);
    n.p_odom = n.p = l.p_true[k];
    n.q_odom = l.q_true[k];
    n.yaw = yawOf(l.q_true[k]);
    map_nodes.push_back(n);
  }
  PoseGraph graph;
  graph.loadMap(map_nodes, {});
  EXPECT_EQ(graph.sessionStart(), half);
  const Eigen::Matrix3d R_run = rotZ(1.0);
  const Eigen::Vector3d t_run(5, -3, 0.2);
  // odometry of the second lap, restarted from the truth at its first pose, then moved into the run's frame
  std::vector<Eigen::Vector3d> p_run;
  std::vector<Eigen::Quaterniond> q_run;
  for (std::size_t k = half; k < l.p_odom.size(); ++k) {
    const Eigen::Matrix3d drift = rotZ(yawOf(l.q_odom[half]) - yawOf(l.q_true[half])).transpose();
    const Eigen::Vector3d p_lap = drift * (l.p_odom[k] - l.p_odom[half]) + l.p_true[half];
    const Eigen::Quaterniond q_lap(drift * l.q_odom[k].toRotationMatrix());
    p_run.push_back(R_run * p_lap + t_run);
    q_run.push_back(Eigen::Quaterniond(R_run * q_lap.toRotationMatrix()));
    graph.addKeyframe(static_cast<TimeNs>(k - half), p_run.back(), q_run.back());
  }
  EXPECT_TRUE(graph.nodes()[half].fixed);  // the session's gauge until it is tied to the map
  EXPECT_THROW(graph.loadMap(map_nodes, {}), std::logic_error);
  // correctedAt reads the session's nodes, not the map's (same times)
  Eigen::Vector3d p;
  Eigen::Quaterniond q;
  graph.correctedAt(5, p_run[5], q_run[5], p, q);
  EXPECT_LT((p - p_run[5]).norm(), 1e-9);
  // tie it to the map with the transform its first keyframe implies, then loops to the map
  graph.relocalize(-1.0, -(R_run.transpose() * t_run));
  EXPECT_FALSE(graph.nodes()[half].fixed);
  graph.correctedPose(half, p, q);
  EXPECT_LT((p - l.p_true[half]).norm(), 1e-9);
  for (std::size_t k = half; k < l.p_odom.size(); k += 10)
    graph.addLoop({k - half, k, relativePose4(l.p_true[k - half], l.q_true[k - half], l.p_true[k], l.q_true[k])});
  EXPECT_TRUE(graph.optimize().converged);
  std::vector<Eigen::Vector3d> corrected, truth, odom_in_map;
  for (std::size_t k = half; k < l.p_odom.size(); ++k) {
    graph.correctedPose(k, p, q);
    corrected.push_back(p);
    truth.push_back(l.p_true[k]);
    odom_in_map.push_back(R_run.transpose() * (p_run[k - half] - t_run));
  }
  for (std::size_t k = 0; k < half; ++k) EXPECT_EQ(graph.nodes()[k].p, l.p_true[k]) << "map node " << k << " moved";
  const double before = rmse(odom_in_map, truth), after = rmse(corrected, truth);
  EXPECT_GT(before, 0.5);
  EXPECT_LT(after, 0.2 * before) << "before " << before << " m, after " << after << " m";
}

TEST(LoopConsistency, ALoopMayUndoTheDriftOfThePathSinceTheGraphLastFixedThePoseNotMore) {
  const LoopOptions options;  // 0.3 m + 3 % of the path; 0.05 rad + 0.001 rad/m
  const Eigen::Vector3d p_old(10, 5, 1);
  const Eigen::Quaterniond q_old = ypr(0.4, 0.05, -0.03);
  // The new keyframe 2 m ahead and 1 m left of the old one, turned 0.2 rad: the loop says exactly that.
  const RelativePose4 rel{Eigen::Vector3d(2, 1, 0), 0.2};
  const Eigen::Vector3d p_now = p_old + q_old * rel.t_from_to;
  const Eigen::Quaterniond q_now = ypr(0.6, 0.05, -0.03);
  EXPECT_TRUE(loopWithinDrift(p_old, q_old, p_now, q_now, rel, 0, options));
  // The estimate 0.25 m off: within the base; 0.5 m off: only after 10 m of path (0.3 + 0.3 m).
  const Eigen::Vector3d east = Eigen::Vector3d::UnitX();
  EXPECT_TRUE(loopWithinDrift(p_old, q_old, p_now + 0.25 * east, q_now, rel, 0, options));
  EXPECT_FALSE(loopWithinDrift(p_old, q_old, p_now + 0.5 * east, q_now, rel, 5, options));
  EXPECT_TRUE(loopWithinDrift(p_old, q_old, p_now + 0.5 * east, q_now, rel, 10, options));
  // A place that repeats 10.2 m along (the city block's facade): refused unless the path since
  // the graph was last solved is long enough for such drift (> 330 m).
  EXPECT_FALSE(loopWithinDrift(p_old, q_old, p_now + 10.2 * east, q_now, rel, 20, options));
  EXPECT_FALSE(loopWithinDrift(p_old, q_old, p_now + 10.2 * east, q_now, rel, 300, options));
  EXPECT_TRUE(loopWithinDrift(p_old, q_old, p_now + 10.2 * east, q_now, rel, 340, options));
  // Yaw: 0.1 rad off needs 50 m of path.
  EXPECT_FALSE(loopWithinDrift(p_old, q_old, p_now, ypr(0.7, 0.05, -0.03), rel, 40, options));
  EXPECT_TRUE(loopWithinDrift(p_old, q_old, p_now, ypr(0.7, 0.05, -0.03), rel, 60, options));
}

}  // namespace
}  // namespace idyvins::map
