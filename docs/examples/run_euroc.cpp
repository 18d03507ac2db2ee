// idyvins embedded as a library: the whole system on a EuRoC folder (or a ROS1 bag), writing
// the files `idyvins run` writes. README.md and docs/architecture.md show excerpts of this
// file; a test builds it against the installed package and checks its outputs against
// `idyvins run`'s.
//
// Usage: run_euroc CONFIG DATASET OUT   (OUT: new, empty, or an earlier run's)

#include <cstdio>
#include <string>
#include <variant>

#include "idyvins/config/config.h"
#include "idyvins/core/error.h"
#include "idyvins/pipeline/run.h"
#include "idyvins/pipeline/run_outputs.h"
#include "idyvins/pipeline/system.h"

int main(int argc, char** argv) {
  if (argc != 4) {
    std::fprintf(stderr, "usage: run_euroc CONFIG DATASET OUT\n");
    return 2;
  }
  try {
    idyvins::Config config = idyvins::loadConfig(argv[1]);  // a VINS-Fusion config
    // System(config) alone runs one thread with no feedback delay: another (equally valid)
    // trajectory than `idyvins run`, whose default RunOptions::twoThreads() is used here.
    idyvins::pipeline::System system(config, idyvins::pipeline::RunOptions::twoThreads());  // as `idyvins run`
    idyvins::io::OpenedDataset dataset = idyvins::pipeline::openDataset(argv[2], config);
    idyvins::pipeline::RunOutputsOptions files;  // every file `idyvins run` writes, staged in OUT
    files.inputs = {argv[1], argv[2]};
    files.masks = dataset.has_masks;
    idyvins::pipeline::RunOutputs outputs(argv[3], files);
    outputs.attach(system);  // stats.json while the run goes (observers: system.addObserver)
    std::size_t poses = 0;
    while (auto m = dataset.source->next()) {  // IMU samples and stereo frames in time order
      if (const auto* imu = std::get_if<idyvins::ImuSample>(&*m)) {
        system.addImu(*imu);
      } else if (const auto* out = system.addFrame(std::get<idyvins::StereoFrame>(*m))) {  // newest finished
        if (out->estimate.initialized) ++poses;  // out->estimate.state: p_w_b, q_w_b, v_w, biases
      }
    }
    const idyvins::pipeline::Result result = system.finish();  // maps, trajectory, counters
    idyvins::pipeline::RunEnd end;
    end.groundtruth = dataset.groundtruth;  // ATE in stats.json, groundtruth.tum
    outputs.write(system, result, end);     // trajectory.tum, state.csv, PLY maps, stats.json, ...
    outputs.publish();
    std::printf("%zu poses while running, %zu in the trajectory, %zu static map points\n", poses,
                result.trajectory.size(), result.static_map.size());
  } catch (const idyvins::InputError& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 1;
  }
  return 0;
}
