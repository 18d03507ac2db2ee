#pragma once
// One time-ordered stream of IMU samples and stereo frames, whatever the
// dataset's origin; the estimator never knows where data came from.

#include <memory>
#include <optional>
#include <string>
#include <variant>

#include "core/measurements.h"
#include "io/euroc_dataset.h"

namespace idyvins::io {

/// One item of the stream: an IMU sample or a stereo frame.
using Measurement = std::variant<ImuSample, StereoFrame>;

/// A source of measurements in time order (an IMU sample with the same
/// stamp as a frame comes before it).
class DataSource {
 public:
  virtual ~DataSource() = default;
  /// The next measurement, or nullopt at the end. Throws InputError on bad data.
  virtual std::optional<Measurement> next() = 0;
  /// Number of stereo frames in the whole stream (for progress bars).
  virtual std::size_t frameCount() const = 0;
};

/// Streams a EuRoC folder; images are loaded lazily and checked against the
/// expected size (0 = no check).
class EurocSource : public DataSource {
 public:
  /// With load_masks, mav0/cam0/mask/<image name> is read into StereoFrame::left_mask
  /// (an error if missing: seg mode needs every mask).
  EurocSource(EurocDataset dataset, int expected_width, int expected_height, bool load_masks = false);
  std::optional<Measurement> next() override;
  std::size_t frameCount() const override { return dataset_.pairs.size(); }
  const EurocDataset& dataset() const { return dataset_; }

 private:
  EurocDataset dataset_;
  int width_, height_;
  bool load_masks_;
  std::size_t next_imu_ = 0, next_pair_ = 0;
};

}  // namespace idyvins::io
