#pragma once
// The one label of features, landmarks and map points with respect to scene motion.

#include <cstdint>

namespace idyvins {

/// Label of a feature, landmark or map point with respect to scene motion (DESIGN §4.3–4.7):
/// static; candidate (marked, down-weighted); eliminated by the front end; confirmed
/// dynamic by the estimator's post-processing (map points and landmarks only).
enum class FeatureLabel : std::uint8_t { kStatic = 0, kCandidate = 1, kEliminated = 2, kConfirmedDynamic = 3 };

}  // namespace idyvins
