// Estimation math: preintegration per IMU sample, each factor's Evaluate (with
// Jacobians), camera projection and undistortion.

#include <benchmark/benchmark.h>

#include <random>

#include "backend/imu_factor.h"
#include "backend/marginalization.h"
#include "backend/parameter_blocks.h"
#include "backend/projection_factors.h"
#include "camera/camera_model.h"
#include "core/so3.h"
#include "imu/preintegration.h"

namespace {

using namespace idyvins;
using Eigen::Quaterniond;
using Eigen::Vector2d;
using Eigen::Vector3d;

const ImuNoise kNoise{0.1, 0.01, 0.001, 0.0001, 9.81};

void BM_PreintegrationPerSample(benchmark::State& state) {
  std::mt19937 rng(1);
  std::normal_distribution<double> g(0, 0.1);
  std::vector<Vector3d> acc(1000), gyr(1000);
  for (int i = 0; i < 1000; ++i) {
    acc[i] = Vector3d(g(rng), g(rng), 9.81 + g(rng));
    gyr[i] = Vector3d(g(rng), g(rng), g(rng));
  }
  imu::Preintegration pre(acc[0], gyr[0], Vector3d::Zero(), Vector3d::Zero(), kNoise);
  std::size_t k = 0;
  for (auto _ : state) {
    pre.push(0.005, acc[k % 1000], gyr[k % 1000]);
    ++k;
    if (k % 40 == 0) pre = imu::Preintegration(acc[0], gyr[0], Vector3d::Zero(), Vector3d::Zero(), kNoise);
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_PreintegrationPerSample);

imu::Preintegration makePre() {
  imu::Preintegration pre(Vector3d(0, 0, 9.81), Vector3d::Zero(), Vector3d::Zero(), Vector3d::Zero(), kNoise);
  for (int k = 0; k < 20; ++k) pre.push(0.005, Vector3d(0.1, 0.2, 9.8), Vector3d(0.01, -0.02, 0.1));
  return pre;
}

template <typename F>
void evaluateLoop(benchmark::State& state, const F& cost, std::vector<double*> blocks) {
  const auto& sizes = cost.parameter_block_sizes();
  std::vector<std::vector<double>> jac(sizes.size());
  std::vector<double*> jp;
  for (std::size_t k = 0; k < sizes.size(); ++k) {
    jac[k].resize(cost.num_residuals() * sizes[k]);
    jp.push_back(jac[k].data());
  }
  std::vector<double> r(cost.num_residuals());
  for (auto _ : state) {
    cost.Evaluate(blocks.data(), r.data(), jp.data());
    benchmark::DoNotOptimize(r.data());
  }
}

void BM_ImuFactorEvaluate(benchmark::State& state) {
  const imu::Preintegration pre = makePre();
  backend::ImuFactor f(&pre);
  double pi[7], pj[7], si[9] = {1, 0, 0}, sj[9] = {1, 0, 0};
  backend::setPose(Vector3d::Zero(), Quaterniond::Identity(), pi);
  backend::setPose(Vector3d(0.1, 0, 0), expQuat(Vector3d(0, 0, 0.01)), pj);
  evaluateLoop(state, f, {pi, si, pj, sj});
}
BENCHMARK(BM_ImuFactorEvaluate);

struct ProjSetup {
  double pi[7], pj[7], inv_depth = 0.1;
  backend::Extrinsic ex0, ex1;
  ProjSetup() {
    backend::setPose(Vector3d::Zero(), Quaterniond::Identity(), pi);
    backend::setPose(Vector3d(0.1, 0, 0), expQuat(Vector3d(0, 0, 0.01)), pj);
    ex1.t_b_c = Vector3d(0.11, 0, 0);
  }
};

void BM_ProjectionTwoFrameLeftEvaluate(benchmark::State& state) {
  ProjSetup s;
  backend::ProjectionTwoFrame f(Vector2d(0.1, 0.05), Vector2d(0.11, 0.05), s.ex0, s.ex0, {});
  evaluateLoop(state, f, {s.pi, s.pj, &s.inv_depth});
}
BENCHMARK(BM_ProjectionTwoFrameLeftEvaluate);

void BM_ProjectionTwoFrameRightEvaluate(benchmark::State& state) {
  ProjSetup s;
  backend::ProjectionTwoFrame f(Vector2d(0.1, 0.05), Vector2d(0.1, 0.05), s.ex0, s.ex1, {});
  evaluateLoop(state, f, {s.pi, s.pj, &s.inv_depth});
}
BENCHMARK(BM_ProjectionTwoFrameRightEvaluate);

void BM_ProjectionOneFrameTwoCamEvaluate(benchmark::State& state) {
  ProjSetup s;
  backend::ProjectionOneFrameTwoCam f(Vector2d(0.1, 0.05), Vector2d(0.09, 0.05), s.ex0, s.ex1, {});
  evaluateLoop(state, f, {&s.inv_depth});
}
BENCHMARK(BM_ProjectionOneFrameTwoCamEvaluate);

void BM_MarginalizationFactorEvaluate(benchmark::State& state) {
  // A prior of the size a 10-keyframe window leaves: 10 poses + 10 speed/biases.
  std::vector<std::vector<double>> blocks;
  auto prior = std::make_shared<backend::MarginalizationPrior>();
  for (int i = 0; i < 10; ++i) {
    blocks.emplace_back(7);
    backend::setPose(Vector3d(i, 0, 0), Quaterniond::Identity(), blocks.back().data());
    blocks.emplace_back(9, 0.0);
  }
  int n = 0;
  for (auto& b : blocks) {
    prior->blocks.push_back(b.data());
    prior->sizes.push_back(static_cast<int>(b.size()));
    prior->tangent_sizes.push_back(b.size() == 7 ? 6 : 9);
    prior->x0.push_back(Eigen::Map<Eigen::VectorXd>(b.data(), b.size()));
    n += prior->tangent_sizes.back();
  }
  prior->J0 = Eigen::MatrixXd::Random(n, n);
  prior->r0 = Eigen::VectorXd::Random(n);
  backend::MarginalizationFactor f(prior);
  evaluateLoop(state, f, prior->blocks);
}
BENCHMARK(BM_MarginalizationFactorEvaluate);

camera::CameraParams eurocCam0() {
  camera::CameraParams p;
  p.width = 752;
  p.height = 480;
  p.fx = 458.654, p.fy = 457.296, p.cx = 367.215, p.cy = 248.375;
  p.dist = {-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05};
  return p;
}

void BM_PinholeRadtanLift(benchmark::State& state) {
  const auto cam = camera::makeCamera(eurocCam0());
  Vector2d xy;
  double u = 10;
  for (auto _ : state) {
    cam->liftToNormalized(Vector2d(u, 400.0), xy);
    benchmark::DoNotOptimize(xy.data());
    u = u > 740 ? 10 : u + 7;
  }
}
BENCHMARK(BM_PinholeRadtanLift);

void BM_PinholeRadtanProjectWithJacobian(benchmark::State& state) {
  const auto cam = camera::makeCamera(eurocCam0());
  Vector2d uv;
  Eigen::Matrix<double, 2, 3> J;
  for (auto _ : state) {
    cam->project(Vector3d(0.3, -0.2, 2.0), uv, &J);
    benchmark::DoNotOptimize(J.data());
  }
}
BENCHMARK(BM_PinholeRadtanProjectWithJacobian);

}  // namespace
