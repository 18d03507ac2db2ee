// Reader throughput on the real EuRoC excerpt (29120 IMU rows, 95 stereo pairs).

#include <benchmark/benchmark.h>

#include "io/data_source.h"
#include "io/euroc_dataset.h"

namespace {

const std::string kMicro = std::string(IDYVINS_SHARED_DATA) + "/euroc_v101_micro";

void BM_ReadImuCsv(benchmark::State& state) {
  std::size_t n = 0;
  for (auto _ : state) {
    const auto imu = idyvins::io::readImuCsv(kMicro + "/mav0/imu0/data.csv");
    n = imu.size();
    benchmark::DoNotOptimize(imu.data());
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations() * n));
}
BENCHMARK(BM_ReadImuCsv)->Unit(benchmark::kMillisecond);

void BM_StreamStereoFrames(benchmark::State& state) {
  const auto ds = idyvins::io::readEurocDataset(kMicro);
  for (auto _ : state) {
    idyvins::io::EurocSource source(ds, 752, 480);
    while (auto m = source.next()) benchmark::DoNotOptimize(&*m);
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations() * ds.pairs.size()));
}
BENCHMARK(BM_StreamStereoFrames)->Unit(benchmark::kMillisecond);

}  // namespace
