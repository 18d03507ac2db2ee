// Marginalizing then re-solving gives the estimate of the full problem.

#include <ceres/ceres.h>
#include <gtest/gtest.h>

#include <random>

#include "backend/imu_factor.h"
#include "backend/marginalization.h"
#include "backend/parameter_blocks.h"
#include "backend/projection_factors.h"
#include "core/so3.h"

namespace idyvins::backend {
namespace {

using Eigen::Quaterniond;
using Eigen::Vector2d;
using Eigen::Vector3d;

/// Linear factor r = W (Σ_k s_k x_k − z) over 3-vectors, s_k = ±1.
class LinearFactor final : public ceres::CostFunction {
 public:
  LinearFactor(std::vector<double> signs, Vector3d z, Eigen::Matrix3d W) : signs_(std::move(signs)), z_(z), W_(W) {
    for (std::size_t k = 0; k < signs_.size(); ++k) mutable_parameter_block_sizes()->push_back(3);
    set_num_residuals(3);
  }
  bool Evaluate(double const* const* x, double* residuals, double** jacobians) const override {
    Vector3d sum = -z_;
    for (std::size_t k = 0; k < signs_.size(); ++k) sum += signs_[k] * Eigen::Map<const Vector3d>(x[k]);
    Eigen::Map<Vector3d> r(residuals);
    r = W_ * sum;
    if (!jacobians) return true;
    for (std::size_t k = 0; k < signs_.size(); ++k) {
      if (!jacobians[k]) continue;
      Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> J(jacobians[k]);
      J = signs_[k] * W_;
    }
    return true;
  }

 private:
  std::vector<double> signs_;
  Vector3d z_;
  Eigen::Matrix3d W_;
};

ceres::Solver::Options tightOptions() {
  ceres::Solver::Options o;
  o.linear_solver_type = ceres::DENSE_QR;
  o.max_num_iterations = 2000;
  o.function_tolerance = 1e-16;
  o.gradient_tolerance = 1e-16;
  o.parameter_tolerance = 1e-16;
  return o;
}

TEST(Marginalization, LinearChainIsExactFromAnyLinearizationPoint) {
  std::mt19937 rng(3);
  std::normal_distribution<double> g(0.0, 1.0);
  auto r3 = [&]() -> Vector3d { return Vector3d(g(rng), g(rng), g(rng)); };
  auto W = [&]() -> Eigen::Matrix3d { return Eigen::Matrix3d::Identity() + 0.3 * Eigen::Matrix3d::Random(); };
  struct F {
    std::shared_ptr<LinearFactor> cost;
    std::vector<int> vars;
  };
  std::vector<F> factors = {
      {std::make_shared<LinearFactor>(std::vector<double>{1}, r3(), W()), {0}},
      {std::make_shared<LinearFactor>(std::vector<double>{-1, 1}, r3(), W()), {0, 1}},
      {std::make_shared<LinearFactor>(std::vector<double>{-1, 1}, r3(), W()), {1, 2}},
      {std::make_shared<LinearFactor>(std::vector<double>{-1, 1}, r3(), W()), {2, 3}},
      {std::make_shared<LinearFactor>(std::vector<double>{-1, 1}, r3(), W()), {3, 4}},
      {std::make_shared<LinearFactor>(std::vector<double>{-1, 1}, r3(), W()), {0, 4}},  // loop
      {std::make_shared<LinearFactor>(std::vector<double>{1}, r3(), W()), {2}},
  };
  std::vector<Vector3d> x(5), init(5);
  for (auto& v : init) v = 5.0 * r3();

  x = init;
  ceres::Problem full(borrowingProblemOptions());
  for (auto& f : factors) {
    std::vector<double*> b;
    for (int v : f.vars) b.push_back(x[v].data());
    full.AddResidualBlock(f.cost.get(), nullptr, b);
  }
  ceres::Solver::Summary summary;
  ceres::Solve(tightOptions(), &full, &summary);
  const std::vector<Vector3d> x_full = x;

  // Marginalize x0 at the (far from optimal) initial values.
  std::vector<Vector3d> y = init;
  Marginalizer marg;
  for (auto& f : factors) {
    if (std::find(f.vars.begin(), f.vars.end(), 0) == f.vars.end()) continue;
    MarginalizationTerm t{f.cost, nullptr, {}, {}};
    for (std::size_t k = 0; k < f.vars.size(); ++k) {
      t.blocks.push_back(y[f.vars[k]].data());
      if (f.vars[k] == 0) t.drop.push_back(static_cast<int>(k));
    }
    marg.add(t);
  }
  auto prior = std::make_shared<MarginalizationPrior>(marg.marginalize());
  ASSERT_EQ(prior->blocks.size(), 2u);  // x1 and x4
  MarginalizationFactor prior_factor(prior);
  ceres::Problem reduced(borrowingProblemOptions());
  reduced.AddResidualBlock(&prior_factor, nullptr, prior->blocks);
  for (auto& f : factors) {
    if (std::find(f.vars.begin(), f.vars.end(), 0) != f.vars.end()) continue;
    std::vector<double*> b;
    for (int v : f.vars) b.push_back(y[v].data());
    reduced.AddResidualBlock(f.cost.get(), nullptr, b);
  }
  ceres::Solve(tightOptions(), &reduced, &summary);
  for (int v = 1; v < 5; ++v) EXPECT_LT((y[v] - x_full[v]).norm(), 1e-6) << "x" << v;
}

/// A 4-frame visual-inertial window: poses, speed/biases, IMU factors, a prior on
/// frame 0, and landmarks (inverse depth) anchored in frames 0 and 1 with Huber loss.
struct Window {
  static constexpr int kFrames = 4;
  std::vector<std::vector<double>> pose, sb;
  std::vector<std::unique_ptr<imu::Preintegration>> pre;
  std::vector<std::shared_ptr<ImuFactor>> imu_factors;
  struct Landmark {
    int anchor;
    double inv_depth;
    std::vector<std::shared_ptr<ceres::CostFunction>> factors;  // one per observing frame j > anchor
    std::vector<int> frames;
    std::shared_ptr<ceres::CostFunction> stereo;
  };
  std::vector<Landmark> landmarks;
  std::shared_ptr<MarginalizationFactor> pose0_prior;
  std::shared_ptr<const MarginalizationPrior> pose0_prior_data;
  std::shared_ptr<ceres::LossFunction> huber = std::make_shared<ceres::HuberLoss>(1.0);
  PoseManifold manifold;
  Extrinsic ex0, ex1;
};

void buildWindow(Window& w) {
  std::mt19937 rng(11);
  std::normal_distribution<double> g(0.0, 1.0);
  auto r3 = [&](double s) -> Vector3d { return s * Vector3d(g(rng), g(rng), g(rng)); };
  // VINS-Fusion's EuRoC noise values; random-walk terms raised so that the bias
  // blocks are not near-singular at 0.1 s between frames (keeps the test's
  // 1e-6 comparison above the solver's numerical floor).
  const ImuNoise noise{0.1, 0.01, 0.05, 0.005, 9.81};
  w.ex0.q_b_c = Quaterniond(Eigen::Matrix3d((Eigen::Matrix3d() << 0, 0, 1, -1, 0, 0, 0, -1, 0).finished()));
  w.ex1 = w.ex0;
  w.ex1.t_b_c = Vector3d(0, -0.11, 0);
  // True states: predicted through random IMU data.
  std::vector<imu::NavState> truth(Window::kFrames);
  truth[0].v_w = Vector3d(1.5, 0.2, 0.1);
  for (int i = 0; i + 1 < Window::kFrames; ++i) {
    auto p = std::make_unique<imu::Preintegration>(Vector3d(0.2, 0, 9.81), Vector3d(0, 0, 0.2), Vector3d::Zero(),
                                                   Vector3d::Zero(), noise);
    for (int k = 0; k < 20; ++k) p->push(0.005, Vector3d(0.2, 0, 9.81) + r3(0.3), Vector3d(0, 0, 0.2) + r3(0.05));
    truth[i + 1] = p->predict(truth[i]);
    w.pre.push_back(std::move(p));
  }
  // Estimates: truth perturbed.
  for (int i = 0; i < Window::kFrames; ++i) {
    std::vector<double> pose(7), sb(9);
    setPose(truth[i].p_w_b + r3(0.02), truth[i].q_w_b * expQuat(r3(0.01)), pose.data());
    Eigen::Map<Eigen::Matrix<double, 9, 1>>(sb.data()) << truth[i].v_w + r3(0.05), r3(0.01), r3(0.001);
    w.pose.push_back(pose);
    w.sb.push_back(sb);
  }
  for (int i = 0; i + 1 < Window::kFrames; ++i) w.imu_factors.push_back(std::make_shared<ImuFactor>(w.pre[i].get()));
  // Prior on pose 0 (fixes the gauge), expressed as a linear prior.
  auto prior = std::make_shared<MarginalizationPrior>();
  prior->blocks = {w.pose[0].data()};
  prior->sizes = {7};
  prior->tangent_sizes = {6};
  prior->x0 = {Eigen::Map<Eigen::VectorXd>(w.pose[0].data(), 7)};
  prior->J0 = 100.0 * Eigen::MatrixXd::Identity(6, 6);
  prior->r0 = Eigen::VectorXd::Zero(6);
  w.pose0_prior_data = prior;
  w.pose0_prior = std::make_shared<MarginalizationFactor>(prior);
  // Landmarks ahead of the body (x forward), observed with 0.005 noise on the normalized plane.
  for (int anchor = 0; anchor < 2; ++anchor) {
    for (int n = 0; n < 12; ++n) {
      const Vector3d p_c(g(rng) * 2.0, g(rng) * 1.5, 4.0 + 8.0 * std::abs(g(rng)));
      const Vector3d pts_i(p_c.x() / p_c.z(), p_c.y() / p_c.z(), 1.0);
      Window::Landmark lm;
      lm.anchor = anchor;
      lm.inv_depth = 1.0 / p_c.z() * (1.0 + 0.05 * g(rng));
      const auto& ta = truth[anchor];
      for (int j = anchor + 1; j < Window::kFrames; ++j) {
        const auto& tj = truth[j];
        const Vector3d pj = transferPoint(pts_i, 1.0 / p_c.z(), ta.p_w_b, ta.q_w_b, tj.p_w_b, tj.q_w_b, w.ex0, w.ex0);
        const Vector2d obs = pj.head<2>() / pj.z() + 0.005 * Vector2d(g(rng), g(rng));
        lm.factors.push_back(std::make_shared<ProjectionTwoFrame>(pts_i.head<2>(), obs, w.ex0, w.ex0,
                                                                  ProjectionWeight{460.0, 1.5, nullptr}));
        lm.frames.push_back(j);
      }
      const Vector3d pr = transferPoint(pts_i, 1.0 / p_c.z(), ta.p_w_b, ta.q_w_b, ta.p_w_b, ta.q_w_b, w.ex0, w.ex1);
      lm.stereo = std::make_shared<ProjectionOneFrameTwoCam>(pts_i.head<2>(),
                                                             pr.head<2>() / pr.z() + 0.005 * Vector2d(g(rng), g(rng)),
                                                             w.ex0, w.ex1, ProjectionWeight{460.0, 1.5, nullptr});
      w.landmarks.push_back(std::move(lm));
    }
  }
}

void addStates(ceres::Problem& problem, Window& w, int first) {
  for (int i = first; i < Window::kFrames; ++i) {
    problem.AddParameterBlock(w.pose[i].data(), 7, &w.manifold);
    problem.AddParameterBlock(w.sb[i].data(), 9);
  }
}

void addLandmark(ceres::Problem& problem, Window& w, Window::Landmark& lm) {
  for (std::size_t k = 0; k < lm.factors.size(); ++k)
    problem.AddResidualBlock(lm.factors[k].get(), w.huber.get(), w.pose[lm.anchor].data(), w.pose[lm.frames[k]].data(),
                             &lm.inv_depth);
  problem.AddResidualBlock(lm.stereo.get(), w.huber.get(), &lm.inv_depth);
}

TEST(Marginalization, ScaledInformationScalesTheCostAndKeepsTheMinimum) {
  // A prior on one 3-vector from two linear factors, then faded to 0.3 of its information.
  std::mt19937 rng(5);
  std::normal_distribution<double> g(0.0, 1.0);
  auto r3 = [&]() -> Vector3d { return Vector3d(g(rng), g(rng), g(rng)); };
  Vector3d a = r3(), b = r3();
  Marginalizer marg;
  marg.add({std::make_shared<LinearFactor>(std::vector<double>{1}, r3(), Eigen::Matrix3d::Identity()),
            nullptr,
            {a.data()},
            {0}});
  marg.add({std::make_shared<LinearFactor>(std::vector<double>{-1, 1}, r3(), 2.0 * Eigen::Matrix3d::Identity()),
            nullptr,
            {a.data(), b.data()},
            {0}});
  auto full = std::make_shared<MarginalizationPrior>(marg.marginalize());
  auto faded = std::make_shared<MarginalizationPrior>(*full);
  faded->scaleInformation(0.3);
  MarginalizationFactor f_full(full), f_faded(faded);
  for (int trial = 0; trial < 5; ++trial) {
    Vector3d x = b + r3();
    const double* params[] = {x.data()};
    Vector3d r_full, r_faded;
    Eigen::Matrix<double, 3, 3, Eigen::RowMajor> J_full, J_faded;
    double* jf[] = {J_full.data()};
    double* jd[] = {J_faded.data()};
    ASSERT_TRUE(f_full.Evaluate(params, r_full.data(), jf));
    ASSERT_TRUE(f_faded.Evaluate(params, r_faded.data(), jd));
    EXPECT_NEAR(r_faded.squaredNorm(), 0.3 * r_full.squaredNorm(), 1e-9 * (1.0 + r_full.squaredNorm()));
    EXPECT_TRUE(J_faded.isApprox(std::sqrt(0.3) * J_full, 1e-12));
  }
  // Same minimizer: the faded prior's gradient vanishes where the full one's does.
  const Eigen::Matrix3d H = full->J0.transpose() * full->J0;
  const Vector3d x_min = b - H.ldlt().solve(full->J0.transpose() * full->r0);
  const double* params[] = {x_min.data()};
  Vector3d r;
  Eigen::Matrix<double, 3, 3, Eigen::RowMajor> J;
  double* jac[] = {J.data()};
  ASSERT_TRUE(f_faded.Evaluate(params, r.data(), jac));
  EXPECT_LT((J.transpose() * r).norm(), 1e-9);
}

TEST(Marginalization, VisualInertialWindowReSolvesToTheFullEstimate) {
  Window w;
  buildWindow(w);
  ceres::Problem full(borrowingProblemOptions());
  addStates(full, w, 0);
  full.AddResidualBlock(w.pose0_prior.get(), nullptr, w.pose[0].data());
  for (int i = 0; i + 1 < Window::kFrames; ++i)
    full.AddResidualBlock(w.imu_factors[i].get(), nullptr, w.pose[i].data(), w.sb[i].data(), w.pose[i + 1].data(),
                          w.sb[i + 1].data());
  for (auto& lm : w.landmarks) addLandmark(full, w, lm);
  ceres::Solver::Summary summary;
  ceres::Solve(tightOptions(), &full, &summary);
  ASSERT_EQ(summary.termination_type, ceres::CONVERGENCE) << summary.FullReport();

  // Marginalize frame 0 (pose, speed/bias) and the landmarks anchored in it.
  Marginalizer marg;
  marg.add({w.pose0_prior, nullptr, {w.pose[0].data()}, {0}});
  marg.add({w.imu_factors[0], nullptr, {w.pose[0].data(), w.sb[0].data(), w.pose[1].data(), w.sb[1].data()}, {0, 1}});
  for (auto& lm : w.landmarks) {
    if (lm.anchor != 0) continue;
    for (std::size_t k = 0; k < lm.factors.size(); ++k)
      marg.add({lm.factors[k], w.huber, {w.pose[0].data(), w.pose[lm.frames[k]].data(), &lm.inv_depth}, {0, 2}});
    marg.add({lm.stereo, w.huber, {&lm.inv_depth}, {0}});
  }
  auto prior = std::make_shared<MarginalizationPrior>(marg.marginalize());
  EXPECT_EQ(prior->blocks.size(), 4u);  // pose1, sb1 (IMU) and pose2, pose3 (projections)
  const auto optimum_pose = w.pose;
  const auto optimum_sb = w.sb;
  std::vector<double> optimum_depth;
  for (auto& lm : w.landmarks) optimum_depth.push_back(lm.inv_depth);

  // Re-solve the reduced problem from perturbed values.
  std::mt19937 rng(5);
  std::normal_distribution<double> g(0.0, 1.0);
  for (int i = 1; i < Window::kFrames; ++i) {
    Eigen::Matrix<double, 6, 1> d;
    for (int k = 0; k < 6; ++k) d(k) = 0.01 * g(rng);
    std::vector<double> moved(7);
    posePlus(w.pose[i].data(), d.data(), moved.data());
    w.pose[i] = moved;
    for (double& v : w.sb[i]) v += 0.001 * g(rng);
  }
  for (auto& lm : w.landmarks) lm.inv_depth *= 1.02;
  MarginalizationFactor prior_factor(prior);
  ceres::Problem reduced(borrowingProblemOptions());
  addStates(reduced, w, 1);
  reduced.AddResidualBlock(&prior_factor, nullptr, prior->blocks);
  for (int i = 1; i + 1 < Window::kFrames; ++i)
    reduced.AddResidualBlock(w.imu_factors[i].get(), nullptr, w.pose[i].data(), w.sb[i].data(), w.pose[i + 1].data(),
                             w.sb[i + 1].data());
  for (auto& lm : w.landmarks)
    if (lm.anchor == 1) addLandmark(reduced, w, lm);
  ceres::Solve(tightOptions(), &reduced, &summary);
  ASSERT_EQ(summary.termination_type, ceres::CONVERGENCE) << summary.FullReport();

  for (int i = 1; i < Window::kFrames; ++i) {
    for (int k = 0; k < 7; ++k) EXPECT_NEAR(w.pose[i][k], optimum_pose[i][k], 1e-6) << "pose " << i;
    for (int k = 0; k < 9; ++k) EXPECT_NEAR(w.sb[i][k], optimum_sb[i][k], 1e-6) << "speed/bias " << i;
  }
  for (std::size_t n = 0; n < w.landmarks.size(); ++n) {
    if (w.landmarks[n].anchor == 1) {
      EXPECT_NEAR(w.landmarks[n].inv_depth, optimum_depth[n], 1e-6);
    }
  }
}

}  // namespace
}  // namespace idyvins::backend
