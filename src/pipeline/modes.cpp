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

ModeOptions optionsFor(const Config& c) {
  const ModeTraits& m = traitsOf(c.mode);
  ModeOptions o{c.tracker, c.estimator, c.idy};
  // Eliminated features never reach the estimator again, but the tracker keeps following
  // them so that no new corner is seeded on the same moving object (DESIGN §4.9;
  // `follow_eliminated: 0` ends their tracks).
  o.tracker.keep_following_eliminated = m.follow_eliminated && c.idy.follow_eliminated;
  o.tracker.judge_lost_new_tracks = m.follow_eliminated && c.idy.lost_track_test;
  o.estimator.candidate_weights = o.estimator.post_process = m.weights_and_post;  // DESIGN §4.5, §4.6
  o.estimator.confirm_outliers = m.weights_and_post && c.idy.confirm_outliers;     // DESIGN §4.9
  o.idy.eliminate = m.eliminate;
  if (c.num_cam == 2 && c.T_b_c.size() >= 2) o.idy.T_r_l = c.T_b_c[1].inverse() * c.T_b_c[0];
  return o;
}

}  // namespace idyvins::pipeline
