// The IDY dynamic preprocessing (DESIGN §4.1-4.4 + the stereo motion test) on one
// frame of 150 tracked stereo features, the paper's Table II setting.

#include <benchmark/benchmark.h>

#include <random>

#include "camera/camera_model.h"
#include "core/so3.h"
#include "dynamic/dynamic.h"

namespace {

using namespace idyvins;
using Eigen::Vector2d;
using Eigen::Vector3d;

void BM_IdyFilter150(benchmark::State& state) {
  const bool stereo = state.range(0) != 0;
  camera::CameraParams cp;
  cp.fx = cp.fy = 380;
  cp.cx = 376;
  cp.cy = 240;
  cp.width = 752;
  cp.height = 480;
  const auto cam = camera::makeCamera(cp);
  Eigen::Isometry3d T_r_l = Eigen::Isometry3d::Identity();
  T_r_l.translation() = Vector3d(-0.11, 0, 0);
  frontend::MotionPrior prior;
  prior.valid = true;
  prior.q_prev_cur = expQuat(Vector3d(0.01, -0.02, 0.005));
  prior.t_prev_cur = Vector3d(0.02, 0.01, 0.4);
  prior.cov_p = Eigen::Matrix3d::Identity() * 1e-6;
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(-1, 1);
  std::normal_distribution<double> noise(0, 0.3 / 380);
  const Eigen::Matrix3d R = prior.q_prev_cur.toRotationMatrix();
  std::vector<frontend::Feature> feats(150), work;
  std::vector<frontend::FilterItem> items(150);
  auto proj = [](const Vector3d& p) { return Vector2d(p.head<2>() / p.z()); };
  for (int i = 0; i < 150; ++i) {
    const Vector3d p_prev(4 * u(rng), 2 * u(rng), 8 + 6 * u(rng));
    Vector3d p_cur = R.transpose() * (p_prev - prior.t_prev_cur);
    if (i < 20) p_cur += Vector3d(0.3, 0, 0.2);  // a moving object
    feats[i].id = i;
    feats[i].xy = proj(p_cur) + Vector2d(noise(rng), noise(rng));
    feats[i].has_right = true;
    feats[i].xy_right = proj(T_r_l * p_cur) + Vector2d(noise(rng), noise(rng));
    items[i].tracked = true;
    items[i].prev_xy = proj(p_prev);
    items[i].prev_has_right = true;
    items[i].prev_xy_right = proj(T_r_l * p_prev);
  }
  dynamic::IdyOptions o;
  o.stereo.enabled = stereo;
  o.T_r_l = T_r_l;
  frontend::FilterContext ctx{cam.get(), &prior, nullptr, 0, 50'000'000};
  std::size_t eliminated = 0, candidates = 0;
  for (auto _ : state) {
    // A fresh filter per frame: the same frame applied again would read as motion
    // against its own stereo anchors (the work per feature is the same either way).
    dynamic::IdyFilter filter(o);
    work = feats;
    for (int i = 0; i < 150; ++i) {
      items[i].feature = &work[i];
      items[i].remove = false;
    }
    filter.apply(ctx, items);
    benchmark::DoNotOptimize(items.data());
    eliminated = filter.lastStats().eliminated;
    candidates = filter.lastStats().candidates;
  }
  state.counters["eliminated"] = static_cast<double>(eliminated);
  state.counters["candidates"] = static_cast<double>(candidates);
}
BENCHMARK(BM_IdyFilter150)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

}  // namespace
