#pragma once
// The one table of the modes (DESIGN §4.8, the paper's Table I rows): each mode's name and what
// it switches on, and the modules' parameters it gives for a config.

#include <string>
#include <vector>

#include "config/config.h"

namespace idyvins {

/// The front end's rejection filter of a mode.
enum class FilterKind { kNone, kRansac, kSeg, kIdy };

/// A mode's row: its name and what it switches on.
struct ModeTraits {
  Mode mode;
  const char* name;  ///< as the config's `mode` key and --mode write it
  FilterKind filter;
  bool needs_masks;        ///< ground-truth masks of the left images (seg)
  bool eliminate;          ///< IDY: features over lambda_dy are removed (off: only marked, idy-ba)
  bool follow_eliminated;  ///< the tracker may keep following eliminated features (DESIGN §4.9)
  bool weights_and_post;   ///< candidate weights 1/m_j and post-processing (DESIGN §4.5, §4.6)
};

/// Every mode's row, in the order of the Mode enum.
const std::vector<ModeTraits>& modeTable();

/// The row of `mode` in the table.
const ModeTraits& traitsOf(Mode mode);

/// The modules' parameters as config.mode runs them: the config's keys, with what the mode
/// does not run switched off (a key can only narrow what the mode runs), and the fields the
/// rig sets.
struct ModeOptions {
  frontend::TrackerParams tracker;
  backend::EstimatorOptions estimator;
  dynamic::IdyOptions idy;
  bool eliminate = true;  ///< the mode's ModeTraits::eliminate (dynamic::IdyFilter)
};
ModeOptions optionsFor(const Config& config);

}  // namespace idyvins
