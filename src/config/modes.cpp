#include "config/modes.h"

#include <stdexcept>

namespace idyvins {

const std::vector<ModeTraits>& modeTable() {
  // mode, name, filter, needs_masks, eliminate, follow_eliminated, weights_and_post
  static const std::vector<ModeTraits> kModes = {
      {Mode::kBaseline, "baseline", FilterKind::kNone, false, false, false, false},
      {Mode::kRansac, "ransac", FilterKind::kRansac, false, false, false, false},
      {Mode::kSeg, "seg", FilterKind::kSeg, true, false, false, false},
      {Mode::kIdy, "idy", FilterKind::kIdy, false, true, true, true},
      {Mode::kIdyPre, "idy-pre", FilterKind::kIdy, false, true, true, false},
      {Mode::kIdyBa, "idy-ba", FilterKind::kIdy, false, false, false, true},
  };
  return kModes;
}

const ModeTraits& traitsOf(Mode mode) {
  for (const ModeTraits& t : modeTable())
    if (t.mode == mode) return t;
  throw std::invalid_argument("unknown mode");
}

const char* toString(Mode mode) { return traitsOf(mode).name; }

bool parseMode(const std::string& text, Mode& mode) {
  for (const ModeTraits& t : modeTable()) {
    if (text == t.name) {
      mode = t.mode;
      return true;
    }
  }
  return false;
}

std::string modeNames() {
  std::string s;
  for (const ModeTraits& t : modeTable()) s += (s.empty() ? "" : "|") + std::string(t.name);
  return s;
}

ModeOptions optionsFor(const Config& c) {
  const ModeTraits& m = traitsOf(c.mode);
  ModeOptions o{c.tracker, c.estimator, c.idy, m.eliminate};
  // Eliminated features never reach the estimator again, but the tracker keeps following
  // them so that no new corner is seeded on the same moving object (DESIGN §4.9;
  // `follow_eliminated: 0` ends their tracks).
  o.tracker.follow_eliminated = m.follow_eliminated && c.tracker.follow_eliminated;
  o.tracker.lost_track_test = m.follow_eliminated && c.tracker.lost_track_test;
  o.estimator.candidate_weights = o.estimator.post_process = m.weights_and_post;      // DESIGN §4.5, §4.6
  o.estimator.confirm_outliers = m.weights_and_post && c.estimator.confirm_outliers;  // DESIGN §4.9
  if (c.num_cam == 2 && c.T_b_c.size() >= 2) o.idy.T_r_l = c.T_b_c[1].inverse() * c.T_b_c[0];
  return o;
}

}  // namespace idyvins
