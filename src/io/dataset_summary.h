#pragma once
// Counts, rates, spans and gaps of a dataset's streams (what `idyvins info` prints).

#include <string>
#include <vector>

#include "io/euroc_dataset.h"

namespace idyvins::io {

/// Statistics of one time-stamped stream.
struct StreamStats {
  std::size_t count = 0;
  TimeNs first_ns = 0, last_ns = 0;
  double span_s = 0;     ///< last - first
  double rate_hz = 0;    ///< 1 / median interval
  double max_gap_s = 0;  ///< largest interval
  std::size_t gaps = 0;  ///< intervals longer than 1.5x the median
};

/// Computes stream statistics from increasing time stamps.
StreamStats streamStats(const std::vector<TimeNs>& stamps);

/// Statistics of every stream of a EuRoC dataset.
struct DatasetSummary {
  StreamStats imu, cam0, cam1, pairs, groundtruth;
  std::size_t unmatched0 = 0, unmatched1 = 0;
  std::size_t unmatched_missing_image = 0;  ///< unmatched rows whose PNG is absent
  bool stereo = false, has_groundtruth = false;
  double imu_before_first_frame_s = 0;  ///< first frame time - first IMU time
  double imu_after_last_frame_s = 0;    ///< last IMU time - last frame time
};

/// Summarizes a dataset.
DatasetSummary summarize(const EurocDataset& dataset);

/// What a dataset is checked against (the config's rig).
struct ExpectedRig {
  int num_cam = 2;       ///< 2: the dataset must have cam1
  bool use_imu = true;   ///< false: the IMU is not checked
  double g_norm = 9.81;  ///< m/s^2, the accelerometer median's reference
};

/// What `run` (and `info --config`) checks of a dataset against the config before any frame:
/// refused (InputError naming the file): stamps in another unit than ns (the IMU's or the
/// cameras' rate 1000x off), no IMU at the frame times, an accelerometer whose median is far
/// from g_norm (all zero, or in g), a gyroscope whose median rate is no rig's (deg/s), a stereo
/// config on a folder without cam1. Returned as warnings, one line each: an IMU rate below
/// 100 Hz or 5 samples per frame, an IMU starting after the first frame or ending before the
/// last, an accelerometer median off g_norm by more than 10 %.
std::vector<std::string> checkPlausible(const EurocDataset& dataset, const DatasetSummary& summary,
                                        const ExpectedRig& rig);

}  // namespace idyvins::io
