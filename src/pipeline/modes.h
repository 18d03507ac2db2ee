#pragma once
// The one table from a mode (DESIGN §4.8, the paper's Table I rows) to what it switches on,
// and the modules' parameters it gives for a config.

#include "io/config.h"

namespace idyvins::pipeline {

/// The front end's rejection filter of a mode.
enum class FilterKind { kNone, kRansac, kSeg, kIdy };

/// What a mode switches on.
struct ModeTraits {
  Mode mode;
  FilterKind filter;
  bool needs_masks;        ///< ground-truth masks of the left images (seg)
  bool eliminate;          ///< IDY: features over lambda_dy are removed (off: only marked, idy-ba)
  bool follow_eliminated;  ///< the tracker keeps following eliminated features (DESIGN §4.9)
  bool weights_and_post;   ///< candidate weights 1/m_j and post-processing (DESIGN §4.5, §4.6)
};

/// The row of `mode` in the table.
const ModeTraits& traitsOf(Mode mode);

/// The modules' parameters as config.mode runs them: the config's keys plus the fields the
/// mode and the rig set (TrackerParams, EstimatorOptions and IdyOptions mark them).
struct ModeOptions {
  frontend::TrackerParams tracker;
  backend::EstimatorOptions estimator;
  dynamic::IdyOptions idy;
};
ModeOptions optionsFor(const Config& config);

}  // namespace idyvins::pipeline
