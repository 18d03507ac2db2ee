#pragma once
// How well a front end holds on a sequence, from its output alone (no ground truth):
// the share of features with a right-image match, how far the right matches lie from
// their epipolar lines under the calibrated extrinsics, and how long tracks live.
// `idyvins track` prints it; the real-EuRoC test asserts on it.

#include <Eigen/Core>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "camera/rig.h"
#include "frontend/feature_frame.h"

namespace idyvins::frontend {

struct TrackQualitySummary {
  std::size_t frames = 0, features = 0, with_right = 0;
  double right_fraction = 0;      ///< features with a right match / features
  double epipolar_median_px = 0;  ///< distance of right matches to their epipolar line (cam1 pixels)
  double epipolar_p99_px = 0;
  std::size_t tracks = 0;          ///< distinct feature ids
  double track_length_median = 0;  ///< frames per track (its longest observed length), median over tracks
};

/// Distance in cam1 pixels of the right observation xy1 (normalized) to the epipolar line
/// of the left observation xy0 under E_c1_c0 (x1ᵀ E x0 = 0), with cam1's focal length f1.
double epipolarDistancePx(const Eigen::Matrix3d& E_c1_c0, double f1, const Eigen::Vector2d& xy0,
                          const Eigen::Vector2d& xy1);

class TrackQuality {
 public:
  /// Stereo extrinsics and cam1's focal length from the rig (a mono rig: no epipolar figures).
  explicit TrackQuality(const camera::Rig& rig);
  void add(const FeatureFrame& frame);
  TrackQualitySummary summary() const;

 private:
  bool stereo_ = false;
  Eigen::Matrix3d E_c1_c0_ = Eigen::Matrix3d::Zero();
  double f1_ = 0;
  std::size_t frames_ = 0, features_ = 0, with_right_ = 0;
  std::vector<double> epipolar_px_;
  std::unordered_map<std::uint64_t, int> length_;
};

}  // namespace idyvins::frontend
