// libFuzzer targets for every reader of user input (`make fuzz`, docs/cli.md#fuzzing). One source,
// one target per reader (IDYVINS_FUZZ_TARGET): the input is written to a file and read as that
// reader reads it. A reader may only accept the input or throw InputError (one clear line); any
// other exception, crash or sanitizer report is a finding.

#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>

#include "config/config.h"
#include "core/error.h"
#include "io/bag_dataset.h"
#include "io/euroc_dataset.h"
#include "io/ros2_messages.h"
#include "io/trajectory_io.h"

namespace {

std::string scratch(const char* name) { return "/tmp/idyvins_fuzz_" + std::to_string(::getpid()) + "_" + name; }

void writeFile(const std::string& path, const std::uint8_t* data, std::size_t size) {
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  f.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
}

void readOnce(const std::uint8_t* data, std::size_t size) {
  using namespace idyvins;
#if IDYVINS_FUZZ_TARGET == 0  // VINS-Fusion config (its camera files are absent: the reader must say so)
  const std::string p = scratch("config.yaml");
  writeFile(p, data, size);
  loadConfig(p);
#elif IDYVINS_FUZZ_TARGET == 1  // camodocal camera file
  const std::string p = scratch("cam.yaml");
  writeFile(p, data, size);
  loadCameraFile(p);
#elif IDYVINS_FUZZ_TARGET == 2  // EuRoC imu0/data.csv
  const std::string p = scratch("imu.csv");
  writeFile(p, data, size);
  io::readImuCsv(p);
#elif IDYVINS_FUZZ_TARGET == 3  // EuRoC cam0/data.csv
  const std::string p = scratch("cam.csv");
  writeFile(p, data, size);
  io::readImageList(p, "/nonexistent");
#elif IDYVINS_FUZZ_TARGET == 4  // EuRoC ground truth
  const std::string p = scratch("gt.csv");
  writeFile(p, data, size);
  io::readGroundTruthCsv(p);
#elif IDYVINS_FUZZ_TARGET == 5  // trajectories for `eval` (TUM or EuRoC CSV, by content)
  const std::string p = scratch("traj.txt");
  writeFile(p, data, size);
  io::readTrajectory(p);
#elif IDYVINS_FUZZ_TARGET == 6  // ROS1 bags
  const std::string p = scratch("in.bag");
  writeFile(p, data, size);
  io::indexBag(p, io::BagTopics{});
#elif IDYVINS_FUZZ_TARGET == 7  // ROS 2 bags in MCAP
  const std::string p = scratch("in.mcap");
  writeFile(p, data, size);
  io::indexBag(p, io::BagTopics{});
#elif IDYVINS_FUZZ_TARGET == 8  // ROS 2 messages in CDR: every type idyvins reads
  try {
    io::decodeRos2Image(data, size, io::BagMessageKind::kImage);
  } catch (const io::BagMessageError&) {
  }
  try {
    io::decodeRos2Image(data, size, io::BagMessageKind::kCompressedImage);
  } catch (const io::BagMessageError&) {
  }
  try {
    io::decodeRos2Imu(data, size);
  } catch (const io::BagMessageError&) {
  }
  for (auto kind : {io::BagMessageKind::kOdometry, io::BagMessageKind::kTransform, io::BagMessageKind::kPose,
                    io::BagMessageKind::kPoint}) {
    try {
      io::decodeRos2Pose(data, size, kind);
    } catch (const io::BagMessageError&) {
    }
  }
#endif
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    readOnce(data, size);
  } catch (const idyvins::InputError&) {  // the one allowed way to refuse
  }
  return 0;
}
