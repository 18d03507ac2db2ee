#pragma once
// EuRoC ASL folder reader: mav0/{cam0,cam1,imu0,state_groundtruth_estimate0}.

#include <optional>
#include <string>
#include <vector>

#include "core/measurements.h"

namespace idyvins::io {

/// One row of a camera's data.csv.
struct ImageRecord {
  TimeNs t_ns = 0;
  std::string path;     ///< absolute or dataset-relative path of the PNG
  int csv_line = 0;     ///< line in data.csv, for error messages
  bool exists = false;  ///< the image file is present
};

/// A stereo pair: indices into cam0 and cam1 records.
struct StereoPair {
  TimeNs t_ns = 0;  ///< cam0 time stamp
  std::size_t i0 = 0, i1 = 0;
};

/// Options for reading a EuRoC folder.
struct EurocOptions {
  TimeNs pair_tolerance_ns = 1'000'000;  ///< max |t0 - t1| for a stereo pair
  bool left_only = false;                ///< one camera: cam1 not read, every cam0 row is a frame
};

/// Everything a EuRoC ASL folder holds, validated (time order, numbers, files).
struct EurocDataset {
  std::string root;  ///< the mav0 folder
  std::vector<ImuSample> imu;
  std::vector<ImageRecord> cam0, cam1;              ///< cam1 empty when the folder has none
  std::vector<StereoPair> pairs;                    ///< cam0/cam1 rows matched by time stamp
  std::vector<std::size_t> unmatched0, unmatched1;  ///< rows without a partner
  std::vector<GroundTruthState> groundtruth;        ///< empty when absent
  bool has_groundtruth = false;
  bool stereo() const { return !cam1.empty(); }
};

/// Reads and validates a EuRoC folder (`dir` holds `mav0/` or is `mav0`).
/// Matched pairs must have both image files; unmatched rows are reported in
/// unmatched0/1, not errors. Throws InputError naming file and line.
EurocDataset readEurocDataset(const std::string& dir, const EurocOptions& options = {});

/// Reads a camera data.csv (`#timestamp [ns],filename`); images under `data_dir`.
std::vector<ImageRecord> readImageList(const std::string& csv_path, const std::string& data_dir);

/// Reads an IMU data.csv (t, w_xyz, a_xyz), strictly increasing time.
std::vector<ImuSample> readImuCsv(const std::string& path);

/// Reads a EuRoC ground-truth state file (17 columns), strictly increasing time.
std::vector<GroundTruthState> readGroundTruthCsv(const std::string& path);

/// Loads an image as 8-bit gray; throws InputError if it is missing, unreadable,
/// or (when expected_width > 0) of another size.
cv::Mat loadGrayImage(const ImageRecord& record, const std::string& csv_path, int expected_width, int expected_height);

/// Pairs two time-sorted lists by nearest time stamp within the tolerance.
void pairByTime(const std::vector<ImageRecord>& cam0, const std::vector<ImageRecord>& cam1, TimeNs tolerance_ns,
                std::vector<StereoPair>& pairs, std::vector<std::size_t>& unmatched0,
                std::vector<std::size_t>& unmatched1);

}  // namespace idyvins::io
