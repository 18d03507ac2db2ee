// Front-end cost per stereo frame (752x480, max_cnt 150), single-threaded, on a
// rendered city sequence: KLT + flow-back + detection + stereo + undistortion.

#include <benchmark/benchmark.h>

#include <algorithm>
#include <map>
#include <opencv2/core/utility.hpp>

#include "frontend/feature_tracker.h"
#include "sim/simulator.h"

namespace {

using namespace idyvins;

std::vector<StereoFrame> renderSequence(const std::string& scene, sim::Level level, std::size_t n) {
  sim::SimOptions o;
  o.scene.scene = scene;
  o.scene.level = level;
  o.duration_s = static_cast<double>(n) / 20.0;
  const sim::Scene s(o);
  std::vector<StereoFrame> frames;
  for (std::size_t k = 0; k < n; ++k) {
    const sim::SceneFrame f = s.renderFrame(k);
    StereoFrame sf;
    sf.t_ns = f.t_ns;
    sf.index = k;
    sf.left = f.cam[0].image;
    sf.right = f.cam[1].image;
    frames.push_back(sf);
  }
  return frames;
}

void trackerBench(benchmark::State& state, const std::string& scene, sim::Level level) {
  cv::setNumThreads(1);
  static std::map<std::string, std::vector<StereoFrame>> cache;
  auto& frames = cache[scene + std::to_string(static_cast<int>(level))];
  if (frames.empty()) frames = renderSequence(scene, level, 200);
  sim::SimOptions o;
  const Config rig = sim::rigConfig(o);
  std::vector<double> ms;
  for (auto _ : state) {
    frontend::FeatureTracker tracker(rig.rig(), rig.tracker);
    for (const auto& f : frames) {
      const frontend::FeatureFrame out = tracker.track(f, frontend::MotionPrior{}, nullptr);
      ms.push_back(out.tracking_ms);
      benchmark::DoNotOptimize(out.features.data());
    }
  }
  std::sort(ms.begin(), ms.end());
  double sum = 0;
  for (double v : ms) sum += v;
  state.counters["mean_ms"] = sum / ms.size();
  state.counters["min_ms"] = ms.front();
  state.counters["median_ms"] = ms[ms.size() / 2];
  state.counters["max_ms"] = ms.back();
  state.counters["frames"] = static_cast<double>(ms.size());
}

void BM_TrackerCityNone(benchmark::State& s) { trackerBench(s, "city", sim::Level::kNone); }
void BM_TrackerCityHigh(benchmark::State& s) { trackerBench(s, "city", sim::Level::kHigh); }
void BM_TrackerParkingLotHigh(benchmark::State& s) { trackerBench(s, "parking_lot", sim::Level::kHigh); }
BENCHMARK(BM_TrackerCityNone)->Unit(benchmark::kMillisecond)->Iterations(3);
BENCHMARK(BM_TrackerCityHigh)->Unit(benchmark::kMillisecond)->Iterations(3);
BENCHMARK(BM_TrackerParkingLotHigh)->Unit(benchmark::kMillisecond)->Iterations(3);

}  // namespace
