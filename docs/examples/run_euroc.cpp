// idyvins embedded as a library: the whole system on a EuRoC folder, the files `idyvins run`
// writes. README.md and docs/architecture.md show excerpts of this file; a test builds it
// against the installed package and checks its trajectory against `idyvins run`'s.
//
// Usage: run_euroc CONFIG DATASET OUT   (OUT must exist)

#include <cstdio>
#include <fstream>
#include <string>
#include <variant>

#include "idyvins/core/error.h"
#include "idyvins/io/config.h"
#include "idyvins/io/data_source.h"
#include "idyvins/pipeline/observers.h"
#include "idyvins/pipeline/outputs.h"
#include "idyvins/pipeline/system.h"

int main(int argc, char** argv) {
  if (argc != 4) {
    std::fprintf(stderr, "usage: run_euroc CONFIG DATASET OUT\n");
    return 2;
  }
  const std::string out_dir = argv[3];
  std::size_t poses = 0;
  try {
    // System(config) alone runs one thread with no feedback delay: another (equally valid)
    // trajectory than `idyvins run`, whose default RunOptions::twoThreads() is used here.
    idyvins::Config config = idyvins::loadConfig(argv[1]);  // a VINS-Fusion config
    idyvins::pipeline::System system(config, idyvins::pipeline::RunOptions::twoThreads());  // as `idyvins run`
    idyvins::io::EurocSource source(idyvins::io::readEurocDataset(argv[2]), config.image_width,
                                    config.image_height);
    std::ofstream stats_file(out_dir + "/stats.json");
    idyvins::pipeline::StatsRecorder stats(stats_file);  // optional observers: stats.json, ...
    system.addObserver(stats);
    while (auto m = source.next()) {  // IMU samples and stereo frames in time order
      if (const auto* imu = std::get_if<idyvins::ImuSample>(&*m)) {
        system.addImu(*imu);
      } else if (const auto* out = system.addFrame(std::get<idyvins::StereoFrame>(*m))) {  // newest finished
        if (out->estimate.initialized) ++poses;  // out->estimate.state: p_w_b, q_w_b, v_w, biases
      }
    }
    const idyvins::pipeline::Result result = system.finish();  // maps, trajectory, counters
    idyvins::pipeline::writeResultFiles(out_dir, result);       // trajectory.tum, state.csv, PLY maps
    stats.finish(idyvins::pipeline::summaryJson(result, config.mode, 0.0));  // closes stats.json
    std::printf("%zu poses while running, %zu in the trajectory, %zu static map points\n", poses,
                result.trajectory.size(), result.static_map.size());
  } catch (const idyvins::InputError& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 1;
  }
  return 0;
}
