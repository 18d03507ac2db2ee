#include "frontend/track_quality.h"

#include <algorithm>
#include <cmath>
#include <memory>

#include "camera/camera_model.h"

namespace idyvins::frontend {
namespace {

/// The q-quantile (0..1) of `v` by nearest rank; 0 for an empty vector.
double quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  const auto k = static_cast<std::size_t>(
      std::min<double>(static_cast<double>(v.size()) - 1, std::ceil(q * static_cast<double>(v.size())) - 1));
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}

}  // namespace

double epipolarDistancePx(const Eigen::Matrix3d& E_c1_c0, double f1, const Eigen::Vector2d& xy0,
                          const Eigen::Vector2d& xy1) {
  const Eigen::Vector3d line = E_c1_c0 * xy0.homogeneous();
  return f1 * std::abs(xy1.homogeneous().dot(line)) / std::max(line.head<2>().norm(), 1e-12);
}

TrackQuality::TrackQuality(const camera::Rig& rig) {
  if (!rig.stereo()) return;
  const Eigen::Isometry3d T_c1_c0 = rig.T_b_c[1].inverse() * rig.T_b_c[0];
  const Eigen::Vector3d t = T_c1_c0.translation();
  Eigen::Matrix3d t_hat;
  t_hat << 0, -t.z(), t.y(), t.z(), 0, -t.x(), -t.y(), t.x(), 0;
  E_c1_c0_ = t_hat * T_c1_c0.linear();
  f1_ = camera::makeCamera(rig.cams[1])->focal();
  stereo_ = true;
}

void TrackQuality::add(const FeatureFrame& frame) {
  ++frames_;
  for (const Feature& f : frame.features) {
    ++features_;
    int& len = length_[f.id];
    len = std::max(len, f.track_length);
    if (!f.has_right) continue;
    ++with_right_;
    if (stereo_) epipolar_px_.push_back(epipolarDistancePx(E_c1_c0_, f1_, f.xy, f.xy_right));
  }
}

TrackQualitySummary TrackQuality::summary() const {
  TrackQualitySummary s;
  s.frames = frames_;
  s.features = features_;
  s.with_right = with_right_;
  s.right_fraction = features_ ? static_cast<double>(with_right_) / static_cast<double>(features_) : 0.0;
  s.epipolar_median_px = quantile(epipolar_px_, 0.5);
  s.epipolar_p99_px = quantile(epipolar_px_, 0.99);
  std::vector<double> lengths;
  lengths.reserve(length_.size());
  for (const auto& [id, len] : length_) lengths.push_back(len);
  s.tracks = lengths.size();
  s.track_length_median = quantile(lengths, 0.5);
  return s;
}

}  // namespace idyvins::frontend
