#pragma once
// The feature tracker's parameters: the single place their defaults live, with their
// config keys (core/params.h). VINS-Fusion's tracker keys keep their names and meaning.

#include "core/params.h"

namespace idyvins::frontend {

struct TrackerParams {
  // VINS-Fusion's keys.
  int max_cnt = 150;         ///< features kept per frame
  double min_dist = 30;      ///< px between features
  double f_threshold = 1.0;  ///< px, F-matrix RANSAC threshold (mode ransac)
  bool flow_back = true;     ///< forward-backward KLT check
  /// `equalize` (VINS-Mono's key): CLAHE (clip limit 3, 8 x 8 tiles) on both images before
  /// tracking, detection and stereo matching (on the real EuRoC excerpt it gives more
  /// features a right match, docs/method.md).
  bool equalize = false;
  /// Before the previous frame's tracks are followed, the current image's brightness is mapped
  /// to the previous image's (gain and offset as for the right image below). KLT assumes equal
  /// brightness; an auto-exposure step under vignetting otherwise shifts every track radially.
  bool temporal_gain_compensation = false;

  // Stereo matching.
  /// Before the left -> right search, the right image's brightness is mapped to the left's
  /// (gain and offset from the two images' mean and standard deviation) when they differ by
  /// more than 1 %. KLT assumes equal brightness; EuRoC's right camera is darker than its left.
  bool stereo_gain_compensation = true;
  /// A right match farther than this from its epipolar line (known extrinsics) is dropped.
  double stereo_epipolar_px = 2.0;
  /// Each right match is refined by aligning the left patch to the right image, gain and
  /// bias invariant, and kept when that converges within 1 px of KLT's: 1 with an affine
  /// warp (as the first-patch alignment), 2 with a translation only; 0 keeps KLT's match.
  /// KLT's disparity is biased by left/right brightness differences a global gain does not
  /// remove (vignetting, saturation), most on near, weakly textured surfaces.
  int stereo_refine = 0;
  /// A right match whose patch correlates worse than this with the left one (ZNCC of the
  /// patch_half patches) is dropped: such matches are more often wrong (> 1 px or hidden)
  /// or beside a vehicle than the rest (docs/method.md). -1 switches the check off.
  double stereo_min_zncc = 0.8;
  /// 1: a match that fails only that check is kept out of the motion tests (the feature has
  /// no right match there) but still reaches the estimator as a stereo observation: on oblique
  /// near surfaces (a garage floor) the correlation drops with the perspective difference,
  /// not with the match, and without them the estimated path came out long (docs/method.md).
  /// 0: the match is dropped everywhere.
  bool stereo_zncc_motion_only = true;

  // Pyramidal KLT.
  int klt_window = 13;  ///< px; smaller than VINS-Fusion's 21: less drift under perspective change (measured)
  /// Pyramid levels above the full image, OpenCV's maxLevel (4 = five images); with the
  /// 13 px window the capture range is about VINS-Fusion's 21 px window on 3 levels.
  int klt_max_level = 4;
  /// maxLevel of the backward checks: they start at the forward start point, so a narrow
  /// basin suffices (VINS-Fusion uses 1 for its reverse check).
  int klt_back_max_level = 1;
  int klt_iterations = 30;    ///< KLT stops after this many iterations ...
  double klt_epsilon = 0.01;  ///< ... or when the update is below this (px)
  double flow_back_px = 0.5;  ///< max forward-backward distance
  int border_px = 1;          ///< a track nearer the image border than this is dropped
  /// Rays farther off the optical axis are neither detected nor tracked (lensMask). The
  /// window's residuals live on the normalized plane, where a pixel's noise grows as 1/cos²θ
  /// (33× at 80°, 130× at 85°): a circular 185° fisheye's rim costs more than it gives
  /// (docs/results.md, "A circular 185° fisheye"). 90 and above: every ray in front.
  double max_ray_angle_deg = 80.0;

  // First-patch alignment.
  /// After KLT, align each track's first-appearance patch (affine, gain/bias invariant) to
  /// the new image and move the feature there: removes KLT's frame-to-frame drift. Tracks
  /// whose patch no longer matches are dropped (slid along an edge, occluded, on a depth
  /// discontinuity).
  bool align_first_patch = true;
  int patch_half = 7;                    ///< template of (2 half + 1)² px
  double min_patch_zncc = 0.8;           ///< below: the track is dropped
  double max_patch_correction_px = 2.0;  ///< KLT and alignment disagree by more: dropped
  /// With align_first_patch, no corner is detected within this many px of the image border.
  /// The default, patch_half + 2, keeps every first patch whole: a corner nearer the border
  /// has no whole first patch and followed KLT alone, drifting a fraction of a pixel per frame (and
  /// the detector's gradients reflect at the border, so an edge meeting it looks like a
  /// corner). Measurements: docs/method.md ("Corners at the border").
  int corner_margin_px = 9;
  /// Share of a first patch that must lie in the image (AlignOptions::min_inside). 1: the
  /// whole patch (a track is dropped when its patch reaches the border; stereo ZNCC needs
  /// both patches whole). Below 1: corners nearer the border than patch_half keep the part
  /// of their patch in the image, tracks keep aligning on the pixels in the image until
  /// less than this share remains, and the stereo ZNCC uses the offsets inside both
  /// images. Measured with corner_margin_px 2 on the standard and validation suites, and
  /// left at 1 (docs/method.md).
  double patch_min_inside = 1.0;

  // The lost-corner test's measurements (its judgement: dynamic::IdyOptions).
  /// With lost_track_test and follow_eliminated: a corner in its second frame
  /// that the min_dist pruning drops next to a followed eliminated track, and whose
  /// displacement since its first frame agrees with that track's within this many px, is
  /// judged moving with it (reported in FeatureFrame::lost_moving, like a lost corner judged
  /// moving). Such corners appear where a receding vehicle shrinks in the image
  /// (docs/method.md). 0 switches it off.
  double move_with_eliminated_px = 6.0;

  // A probe, not a tuning knob: tracks withheld from the back end at random.
  /// Per mille of the tracks the front end follows but does not hand on (pipeline::FrontEnd),
  /// chosen by a hash of the track id and `track_dropout_seed`: the same tracks in every frame,
  /// still followed, so no new corner takes their place. Runs with several seeds show how far a
  /// sequence's error moves when a few tracks go, the spread a change must beat to count
  /// (docs/results.md). 0 = off.
  int track_dropout_permille = 0;
  int track_dropout_seed = 0;  ///< which tracks track_dropout_permille withholds

  // Extensions of DESIGN §4.3 (not in the paper), run only in the modes whose table row says
  // follow_eliminated (idy, idy-pre; config/modes.h switches them off in the others).
  /// Keep following features the filter eliminated: they are reported in
  /// FeatureFrame::removed every frame and never output as features again, but they keep
  /// their place in the image so that no new corner is seeded on the same moving object.
  /// Off: an eliminated track ends, as DESIGN §4.3 says.
  bool follow_eliminated = true;
  /// Hand the new corners lost in their second frame to the filter's judgement
  /// (FeatureFilter::judgeLost; dynamic::IdyFilter moves a corner with a right match as a
  /// static point by the motion prior and asks the tracker to look for it there); those
  /// judged moving are reported in FeatureFrame::lost_moving (labelled dynamic). Such a corner
  /// never reaches the estimator's optimization (one observation): this labels, it does not filter.
  bool lost_track_test = true;

  /// Declares every config key of the struct (load, print and save visit this list).
  void declareParams(ParamVisitor& v) {
    v.section("Feature tracker (VINS-Fusion's keys)");
    v.param({"max_cnt", "features kept per frame", ParamRule::kPositive, true}, max_cnt);
    v.param({"min_dist", "px between features", ParamRule::kNonNegative, true}, min_dist);
    v.param({"F_threshold", "px, F-matrix RANSAC threshold (mode ransac)", ParamRule::kPositive, true}, f_threshold);
    v.param({"flow_back", "0/1, forward-backward KLT check", ParamRule::kAny, true}, flow_back);
    v.param({"equalize", "0/1, CLAHE on both images"}, equalize);
    v.param({"temporal_gain_compensation", "0/1, current image's gain and offset mapped to the previous one's"},
            temporal_gain_compensation);
    v.section("Feature tracker: stereo matching");
    v.param({"stereo_gain_compensation", "0/1, right image's gain and offset mapped to the left's"},
            stereo_gain_compensation);
    v.param({"stereo_epipolar_px", "px from the epipolar line", ParamRule::kPositive}, stereo_epipolar_px);
    v.param({"stereo_refine", "0/1/2, right matches refined: 1 affine, 2 translation (gain and bias invariant)",
             ParamRule::kNonNegative},
            stereo_refine);
    v.param({"stereo_min_zncc", "ZNCC of the left and right patches, -1 = off", ParamRule::kCorrelation},
            stereo_min_zncc);
    v.param({"stereo_zncc_motion_only", "0/1, low-ZNCC right matches only kept out of the motion tests"},
            stereo_zncc_motion_only);
    v.section("Feature tracker: pyramidal KLT");
    v.param({"klt_window", "px, square window side", ParamRule::kPositive}, klt_window);
    v.param({"klt_max_level", "pyramid levels above the full image (OpenCV maxLevel)", ParamRule::kNonNegative},
            klt_max_level);
    v.param({"klt_back_max_level", "maxLevel of the backward checks", ParamRule::kNonNegative}, klt_back_max_level);
    v.param({"klt_iterations", "iterations per level", ParamRule::kPositive}, klt_iterations);
    v.param({"klt_epsilon", "px, update that stops KLT", ParamRule::kPositive}, klt_epsilon);
    v.param({"flow_back_px", "px, forward-backward distance", ParamRule::kPositive}, flow_back_px);
    v.param({"border_px", "px, tracks nearer the border are dropped", ParamRule::kNonNegative}, border_px);
    v.param({"max_ray_angle_deg", "deg off the axis beyond which nothing is tracked (90: all in front)",
             ParamRule::kPositive},
            max_ray_angle_deg);
    v.section("Feature tracker: first-patch alignment");
    v.param({"align_first_patch", "0/1, align each track's first patch"}, align_first_patch);
    v.param({"patch_half", "px, patch of (2 half + 1)^2 pixels", ParamRule::kPositive}, patch_half);
    v.param({"min_patch_zncc", "ZNCC below which a track is dropped", ParamRule::kCorrelation}, min_patch_zncc);
    v.param({"max_patch_correction_px", "px, KLT-alignment disagreement that drops a track", ParamRule::kPositive},
            max_patch_correction_px);
    v.param({"corner_margin_px", "px, no corner detected nearer the border", ParamRule::kNonNegative},
            corner_margin_px);
    v.param({"patch_min_inside", "share of a first patch in the image", ParamRule::kFraction}, patch_min_inside);
    v.section("Feature tracker: tracks withheld at random (a probe of a sequence's spread)");
    v.param({"track_dropout_permille", "per mille of the tracks withheld from the back end, 0 = off",
             ParamRule::kNonNegative},
            track_dropout_permille);
    v.param({"track_dropout_seed", "which tracks are withheld", ParamRule::kNonNegative}, track_dropout_seed);
    v.section("Feature tracker: eliminated tracks and lost new corners (idy, idy-pre)");
    v.param({"follow_eliminated", "0/1, eliminated features still followed (idy, idy-pre)"}, follow_eliminated);
    v.param({"lost_track_test", "0/1, lost new corners judged (idy, idy-pre)"}, lost_track_test);
    v.param({"move_with_eliminated_px", "px, displacement agreement with an eliminated track, 0 = off",
             ParamRule::kNonNegative},
            move_with_eliminated_px);
  }
};

}  // namespace idyvins::frontend
