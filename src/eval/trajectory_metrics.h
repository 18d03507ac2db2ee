#pragma once
// Trajectory evaluation with evo's conventions (github.com/MichaelGrupp/evo):
// association by nearest time stamp from the shorter trajectory, Umeyama
// alignment of the estimate onto the reference, ATE on positions, RPE over
// path-length deltas with consecutive pairs taken on the estimate.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>
#include <utility>
#include <vector>

#include "core/measurements.h"

namespace idyvins::eval {

/// Alignment of the estimate onto the reference.
enum class AlignMode { kSe3, kSim3, kPosYaw, kNone };
bool parseAlignMode(const std::string& text, AlignMode& mode);
const char* toString(AlignMode mode);

/// p_ref ≈ s R p_est + t.
struct Similarity {
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  double s = 1.0;
  Eigen::Vector3d apply(const Eigen::Vector3d& p) const { return s * (R * p) + t; }
};

/// Index pairs (reference, estimate) matched by time stamp: for each stamp of the
/// trajectory with fewer poses (the estimate when both are equal), the nearest
/// stamp of the other, kept when |Δt| ≤ max_dt_ns (evo's rule; ties: first index).
std::vector<std::pair<std::size_t, std::size_t>> associate(const std::vector<StampedPose>& ref,
                                                           const std::vector<StampedPose>& est, TimeNs max_dt_ns);

/// Umeyama's least-squares similarity mapping `src` onto `dst` (columns are points);
/// with_scale = false fixes s = 1. Throws std::invalid_argument when degenerate.
Similarity umeyama(const Eigen::Matrix3Xd& src, const Eigen::Matrix3Xd& dst, bool with_scale);

/// 4-DoF alignment: translation and a rotation about the world z axis only.
Similarity alignPositionYaw(const Eigen::Matrix3Xd& src, const Eigen::Matrix3Xd& dst);

/// Error statistics as evo reports them (std is the population std).
struct ErrorStats {
  std::size_t n = 0;
  double rmse = 0, mean = 0, median = 0, std = 0, min = 0, max = 0, sse = 0;
};
ErrorStats computeStats(const std::vector<double>& errors);

/// ATE result: statistics, per-pair errors, the alignment, the associated index pairs.
struct AteResult {
  ErrorStats stats;
  std::vector<double> errors;
  std::vector<TimeNs> stamps;  ///< reference stamps of the pairs
  Similarity alignment;
  std::vector<std::pair<std::size_t, std::size_t>> pairs;
};

/// Absolute trajectory error (translation part) after alignment.
AteResult computeAte(const std::vector<StampedPose>& ref, const std::vector<StampedPose>& est, AlignMode align,
                     TimeNs max_dt_ns);

/// RPE (translation part) for a path-length delta in metres, on associated poses
/// (est already aligned or not: the relative error does not depend on a rigid alignment).
ErrorStats computeRpe(const std::vector<StampedPose>& ref_assoc, const std::vector<StampedPose>& est_assoc,
                      double delta_m);

/// Path length of a trajectory (sum of position steps).
double pathLength(const std::vector<StampedPose>& poses);

}  // namespace idyvins::eval
