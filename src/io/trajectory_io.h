#pragma once
// Trajectory files: TUM (`t x y z qx qy qz qw`, seconds) and EuRoC CSV
// (`#timestamp [ns], p xyz, q wxyz`, optionally the 17-column ground truth).

#include <string>
#include <vector>

#include "core/measurements.h"

namespace idyvins::io {

/// Writes a TUM trajectory (exact decimal seconds, 9 digits). Throws InputError if unwritable.
void writeTum(const std::string& path, const std::vector<StampedPose>& poses);

/// Writes a EuRoC-style CSV trajectory (time in ns, position, quaternion w x y z).
void writeEurocCsv(const std::string& path, const std::vector<StampedPose>& poses);

/// Writes the 17-column EuRoC state CSV (time ns, p, q wxyz, v, gyro bias, accel bias), the
/// format of `state_groundtruth_estimate0/data.csv`.
void writeStateCsv(const std::string& path, const std::vector<GroundTruthState>& states);

/// Reads a TUM trajectory (8 whitespace-separated columns, increasing time).
std::vector<StampedPose> readTum(const std::string& path);

/// Reads a EuRoC CSV trajectory: 8 columns (t, p, q wxyz) or the 17-column ground truth.
std::vector<StampedPose> readEurocCsv(const std::string& path);

/// Reads either format: a first data line with commas is EuRoC CSV, otherwise TUM.
std::vector<StampedPose> readTrajectory(const std::string& path);

}  // namespace idyvins::io
