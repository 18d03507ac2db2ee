#pragma once
// The projection factors of one landmark as the window's solve and the marginalization build
// them: left and right observations, the time offset's treatment, candidate weights, the
// estimated-ray form.

#include <map>
#include <memory>
#include <optional>
#include <vector>

#include "backend/feature_manager.h"
#include "backend/projection_factors.h"

namespace ceres {
class CostFunction;
}  // namespace ceres

namespace idyvins::backend {

/// One projection factor of a landmark; its blocks are (pose of the anchor frame, pose of
/// `frame`, [T_b_c0 with ExtrinsicUse::block,] inverse depth) or, for the stereo factor within the anchor frame (frame
/// −1), the inverse depth alone; a factor with the time offset adds the td block last.
struct LandmarkFactor {
  std::shared_ptr<ceres::CostFunction> cost;
  int frame;  ///< -1 for the one-frame stereo factor
};

/// How a landmark's factors treat the time offset.
struct TdUse {
  bool block = false;  ///< each factor carries the td block
  /// Without the block: observations moved to this offset (the current estimate) when
  /// estimating, so the factors hold no information on td; nullopt: observations as they are.
  std::optional<double> moved_to;
};

/// Whether a landmark's two-frame factors carry the left camera's mount T_b_c0 as a block
/// (estimate_extrinsic; after the two poses, before the inverse depth), the stereo pair rigid.
struct ExtrinsicUse {
  bool block = false;
  Extrinsic T_c0_c1;  ///< the right camera in the left one
};

/// The projection factors of one landmark, weighted by `w_static` (and by the scale pointed to
/// for a frame in `scale_of_frame`); with `ray`, those of its estimated-ray form (block: ray x,
/// y, inverse depth; the anchor observation is a residual like the others).
std::vector<LandmarkFactor> landmarkFactors(const Landmark& lm, const Rig& rig, const ProjectionWeight& w_static,
                                            const TdUse& td, const std::map<int, const double*>& scale_of_frame = {},
                                            bool ray = false, const ExtrinsicUse& ex = {});

/// A landmark the window's solve uses (usable, finite inverse depth).
bool inSolve(const Landmark& lm);

}  // namespace idyvins::backend
