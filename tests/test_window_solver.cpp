// The window's own solver against Ceres (DENSE_SCHUR, DOGLEG) on small stereo windows: the same
// minimum to 1e-9, the same iterates step by step, and the same problem handed to either.

#include <ceres/ceres.h>
#include <gtest/gtest.h>

#include <memory>
#include <random>

#include "backend/extrinsic.h"
#include "backend/marginalization.h"
#include "backend/parameter_blocks.h"
#include "backend/projection_factors.h"
#include "backend/window_problem.h"
#include "core/so3.h"

namespace idyvins::backend {
namespace {

using Eigen::Quaterniond;
using Eigen::Vector2d;
using Eigen::Vector3d;

/// A small stereo window: poses along a street, landmarks in front, observations with pixel noise;
/// the start values perturbed. rays: landmarks as (x, y, inverse depth) blocks.
struct StereoWindow {
  std::vector<std::array<double, 7>> poses;
  std::vector<double> inv_depth;
  std::vector<std::array<double, 3>> rays;
  std::vector<std::shared_ptr<ceres::CostFunction>> costs;
  std::shared_ptr<MarginalizationPrior> prior;
  std::shared_ptr<ceres::CostFunction> prior_cost;
  ceres::HuberLoss huber{1.0};
  PoseManifold manifold;

  StereoWindow(bool ray, unsigned seed) {
    std::mt19937 rng(seed);
    std::normal_distribution<double> px(0.0, 0.5 / 400.0), pose_noise(0.0, 0.02), n01(0.0, 1.0);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    const int n_frames = 5, n_points = 30;
    Extrinsic left, right;
    left.q_b_c =
        Quaterniond(Eigen::AngleAxisd(-M_PI / 2, Vector3d::UnitZ()) * Eigen::AngleAxisd(-M_PI / 2, Vector3d::UnitX()));
    right = left;
    right.t_b_c = left.q_b_c * Vector3d(0.11, 0, 0);
    std::vector<Eigen::Isometry3d> truth;
    for (int i = 0; i < n_frames; ++i) {
      Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
      T.translation() = Vector3d(0.4 * i, 0.05 * std::sin(i), 0.0);
      T.linear() = Eigen::AngleAxisd(0.03 * i, Vector3d::UnitZ()).toRotationMatrix();
      truth.push_back(T);
      const Vector3d p =
          T.translation() + (i > 0 ? Vector3d(pose_noise(rng), pose_noise(rng), pose_noise(rng)) : Vector3d::Zero());
      const Quaterniond q =
          Quaterniond(T.linear()) *
          (i > 0 ? expQuat(Vector3d(0.2 * pose_noise(rng), 0.2 * pose_noise(rng), 0.2 * pose_noise(rng)))
                 : Quaterniond::Identity());
      std::array<double, 7> b;
      setPose(p, q, b.data());
      poses.push_back(b);
    }
    const ProjectionWeight w{400.0, 1.0, nullptr};
    inv_depth.resize(n_points);
    rays.resize(n_points);
    for (int k = 0; k < n_points; ++k) {
      const int anchor = k % 3;
      const Vector3d pc(2.0 * u(rng), 1.0 * u(rng), 6.0 + 4.0 * (u(rng) + 1.0));  // in the anchor's left camera
      const Vector3d pw = truth[anchor] * (left.q_b_c * pc + left.t_b_c);
      const Vector2d xy_a = pc.head<2>() / pc.z() + Vector2d(px(rng), px(rng));
      inv_depth[k] = (1.0 / pc.z()) * (1.0 + 0.1 * n01(rng));
      rays[k] = {xy_a.x(), xy_a.y(), inv_depth[k]};
      auto observe = [&](int frame, const Extrinsic& cam) {
        const Vector3d pb = truth[frame].inverse() * pw;
        const Vector3d c = cam.q_b_c.conjugate() * (pb - cam.t_b_c);
        return Vector2d(c.head<2>() / c.z() + Vector2d(px(rng), px(rng)));
      };
      auto add = [&](std::shared_ptr<ceres::CostFunction> c, int frame) {
        costs.push_back(std::move(c));
        owner.push_back({k, frame, anchor});
      };
      if (ray) add(std::make_shared<AnchorRayObservation>(xy_a, w), -2);
      for (int j = anchor + 1; j < n_frames; ++j) {
        if (ray) {
          add(std::make_shared<ProjectionTwoFrameRay>(observe(j, left), left, left, w), j);
          add(std::make_shared<ProjectionTwoFrameRay>(observe(j, right), left, right, w), j);
        } else {
          add(std::make_shared<ProjectionTwoFrame>(xy_a, observe(j, left), left, left, w), j);
          add(std::make_shared<ProjectionTwoFrame>(xy_a, observe(j, right), left, right, w), j);
        }
      }
      if (ray)
        add(std::make_shared<ProjectionOneFrameTwoCamRay>(observe(anchor, right), left, right, w), -1);
      else
        add(std::make_shared<ProjectionOneFrameTwoCam>(xy_a, observe(anchor, right), left, right, w), -1);
    }
    // A dense prior over poses 1 and 2 (a marginalization prior's shape: many rows, two blocks).
    prior = std::make_shared<MarginalizationPrior>();
    for (int i : {1, 2}) {
      prior->blocks.push_back(poses[static_cast<std::size_t>(i)].data());
      prior->sizes.push_back(7);
      prior->tangent_sizes.push_back(6);
      Eigen::VectorXd x0(7);
      const Quaterniond q(truth[static_cast<std::size_t>(i)].linear());
      x0 << truth[static_cast<std::size_t>(i)].translation(), q.x(), q.y(), q.z(), q.w();
      prior->x0.push_back(x0);
    }
    prior->J0.resize(24, 12);
    prior->r0.resize(24);
    for (int r = 0; r < 24; ++r) {
      for (int c = 0; c < 12; ++c) prior->J0(r, c) = 30.0 * u(rng);
      prior->r0(r) = u(rng);
    }
  }

  struct Owner {
    int landmark, frame, anchor;  // frame -1: the anchor's stereo factor; -2: the anchor ray's own
  };
  std::vector<Owner> owner;

  double* landmark(int k, bool ray) {
    return ray ? rays[static_cast<std::size_t>(k)].data() : &inv_depth[static_cast<std::size_t>(k)];
  }

  WindowProblem problem(bool ray) {
    WindowProblem p;
    for (auto& b : poses) p.addParameterBlock(b.data(), 7, &manifold);
    p.setParameterBlockConstant(poses[0].data());
    prior_cost = std::make_shared<MarginalizationFactor>(prior);
    p.addResidualBlock(prior_cost.get(), nullptr, prior->blocks);
    for (std::size_t c = 0; c < costs.size(); ++c) {
      const Owner& o = owner[c];
      double* lm = landmark(o.landmark, ray);
      std::vector<double*> blocks;
      if (o.frame >= 0)
        blocks = {poses[static_cast<std::size_t>(o.anchor)].data(), poses[static_cast<std::size_t>(o.frame)].data()};
      blocks.push_back(lm);
      p.addResidualBlock(costs[c].get(), &huber, blocks);
      p.setLandmark(lm);
    }
    return p;
  }

  std::vector<double> state() const {
    std::vector<double> s;
    for (const auto& b : poses) s.insert(s.end(), b.begin(), b.end());
    s.insert(s.end(), inv_depth.begin(), inv_depth.end());
    for (const auto& r : rays) s.insert(s.end(), r.begin(), r.end());
    return s;
  }
};

ceres::Solver::Options ceresOptions(int iterations, double tolerance) {
  ceres::Solver::Options o;
  o.linear_solver_type = ceres::DENSE_SCHUR;
  o.trust_region_strategy_type = ceres::DOGLEG;
  o.max_num_iterations = iterations;
  o.function_tolerance = o.gradient_tolerance = o.parameter_tolerance = tolerance;
  o.num_threads = 1;
  return o;
}

/// Solves the same window with Ceres and with solveWindow; returns the two final states.
std::pair<std::vector<double>, std::vector<double>> solveBoth(bool ray, int iterations, double tolerance) {
  StereoWindow a(ray, 7), b(ray, 7);
  {
    WindowProblem pa = a.problem(ray);
    ceres::Problem problem(borrowingProblemOptions());
    pa.toCeres(problem);
    ceres::Solver::Summary summary;
    ceres::Solve(ceresOptions(iterations, tolerance), &problem, &summary);
    EXPECT_GT(summary.initial_cost, 2.0 * summary.final_cost);
  }
  WindowProblem pb = b.problem(ray);
  WindowSolverOptions o;
  o.max_num_iterations = iterations;
  o.function_tolerance = o.gradient_tolerance = o.parameter_tolerance = tolerance;
  const WindowSolverSummary s = solveWindow(pb, o);
  EXPECT_TRUE(s.usable);
  EXPECT_GT(s.initial_cost, 2.0 * s.final_cost);
  return {a.state(), b.state()};
}

void expectNear(const std::vector<double>& a, const std::vector<double>& b, double tol) {
  ASSERT_EQ(a.size(), b.size());
  double worst = 0;
  for (std::size_t i = 0; i < a.size(); ++i) worst = std::max(worst, std::abs(a[i] - b[i]));
  EXPECT_LT(worst, tol);
}

// Tolerances of 1e-18: both solvers iterate until no step helps (at 1e-15 Ceres may stop a few
// steps earlier, 5e-9 from the minimum along this window's flattest direction).
TEST(WindowSolver, ReachesCeresMinimumOnAStereoWindowTo1e9) {
  const auto [ceres_state, own_state] = solveBoth(false, 100, 1e-18);
  expectNear(ceres_state, own_state, 1e-9);
}

TEST(WindowSolver, ReachesCeresMinimumWithThreeDimensionalLandmarks) {
  const auto [ceres_state, own_state] = solveBoth(true, 100, 1e-18);
  expectNear(ceres_state, own_state, 1e-9);
}

TEST(WindowSolver, TakesCeresStepsOneByOne) {
  for (int iterations : {1, 2, 3}) {
    const auto [ceres_state, own_state] = solveBoth(false, iterations, 1e-6);
    expectNear(ceres_state, own_state, 1e-9);
  }
  // The start is far enough that the steps differ from each other (the comparison can fail).
  const auto [one, three] = std::make_pair(solveBoth(false, 1, 1e-6).second, solveBoth(false, 3, 1e-6).second);
  double moved = 0;
  for (std::size_t i = 0; i < one.size(); ++i) moved = std::max(moved, std::abs(one[i] - three[i]));
  EXPECT_GT(moved, 1e-6);
}

TEST(WindowSolver, RefusesAResidualWithTwoLandmarks) {
  StereoWindow w(false, 3);
  WindowProblem p;
  p.addParameterBlock(w.poses[0].data(), 7, &w.manifold);
  p.addParameterBlock(w.poses[1].data(), 7, &w.manifold);
  p.addResidualBlock(w.costs[1].get(), nullptr, {w.poses[0].data(), w.poses[1].data(), &w.inv_depth[0]});
  p.setLandmark(&w.inv_depth[0]);
  p.setLandmark(w.poses[1].data());
  EXPECT_THROW(solveWindow(p, WindowSolverOptions{}), std::invalid_argument);
}

TEST(WindowSolver, ABlockAddedByAResidualTakesTheManifoldGivenLater) {
  StereoWindow w(false, 4);
  WindowProblem p;
  p.addResidualBlock(w.costs[1].get(), nullptr, {w.poses[0].data(), w.poses[1].data(), &w.inv_depth[0]});
  ASSERT_EQ(p.blocks()[1].manifold, nullptr);
  p.addParameterBlock(w.poses[1].data(), 7, &w.manifold);
  EXPECT_EQ(p.blocks()[1].manifold, &w.manifold);
  ceres::Problem problem(borrowingProblemOptions());
  p.toCeres(problem);
  EXPECT_EQ(problem.GetManifold(w.poses[1].data()), &w.manifold);
  EXPECT_EQ(problem.GetManifold(w.poses[0].data()), nullptr);
}

TEST(WindowSolver, LeavesAProblemWithEveryBlockConstantAsItIs) {
  StereoWindow w(false, 5);
  WindowProblem p = w.problem(false);
  for (const auto& b : p.blocks()) p.setParameterBlockConstant(b.x);
  const std::vector<double> before = w.state();
  const WindowSolverSummary s = solveWindow(p, WindowSolverOptions{});
  EXPECT_TRUE(s.usable);
  EXPECT_TRUE(s.converged);
  EXPECT_EQ(s.successful_steps + s.unsuccessful_steps, 0);
  EXPECT_EQ(w.state(), before);
}

}  // namespace
}  // namespace idyvins::backend
