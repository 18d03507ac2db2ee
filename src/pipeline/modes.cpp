#include "pipeline/modes.h"

#include <stdexcept>

namespace idyvins::pipeline {

namespace {
// mode, filter, needs_masks, eliminate, follow_eliminated, weights_and_post
constexpr ModeTraits kModes[] = {
    {Mode::kBaseline, FilterKind::kNone, false, false, false, false},
    {Mode::kRansac, FilterKind::kRansac, false, false, false, false},
    {Mode::kSeg, FilterKind::kSeg, true, false, false, false},
    {Mode::kIdy, FilterKind::kIdy, false, true, true, true},
    {Mode::kIdyPre, FilterKind::kIdy, false, true, true, false},
    {Mode::kIdyBa, FilterKind::kIdy, false, false, false, true},
};
}  // namespace

const ModeTraits& traitsOf(Mode mode) {
  for (const ModeTraits& t : kModes)
    if (t.mode == mode) return t;
  throw std::invalid_argument("unknown mode");
}

}  // namespace idyvins::pipeline
