#pragma once
// Parameters of the paper's method and of the dynamic-scene tests beside it: the single
// place their defaults live, with their config keys (core/params.h).

#include <Eigen/Geometry>
#include <optional>

#include "core/params.h"

namespace idyvins::dynamic {

/// Extension of DESIGN §4.3 (not in the paper): the stereo motion test
/// (dynamic::stereoMotionError) catches motion along the epipolar line, which d_s cannot
/// see (docs/method.md).
struct StereoMotionOptions {
  bool enabled = true;     ///< `stereo_motion_test`
  double chi2 = 18.47;     ///< χ²₄ at 99.9 %
  double sigma_px = 0.25;  ///< one KLT / stereo match
  int strikes = 2;         ///< consecutive failures before removal (an earlier failure marks a candidate)
  int anchor_frames =
      40;  ///< compare with the stereo observation up to this many frames back (1 = previous; 2 s at 20 Hz)
  double drift_mps = 0.02;  ///< drift of the chained priors
  /// With a value above `chi2`, a repeated failure removes the feature only when its χ²
  /// exceeds this or the failures reach `persistent_strikes`; otherwise it stays a
  /// candidate. 0 = every repeated failure removes (the default; on clean images slow
  /// traffic would be removed too late, docs/method.md).
  double remove_chi2 = 0;
  /// With `remove_chi2` on, this many consecutive failures remove the feature whatever its
  /// χ² (slow motion along the line of sight); 0 = never.
  int persistent_strikes = 3;
  /// A failure whose left-image residual alone is within this (χ², 2 dof; 5.99 = 95 %) is
  /// not counted (the right match is suspect: hidden, or at a silhouette). 0 = off. Looser
  /// gates cost recall (docs/method.md).
  double left_chi2 = 5.99;
  /// The tracker's noise is measured on every frame as a quantile of the χ² of the tested
  /// features (most are static); when that quantile exceeds this reference, the χ² are
  /// divided by quantile / reference before the tests (the test then holds its false-alarm
  /// rate on noisier images). Clean renders keep the 25 % quantile below 0.1 on every frame
  /// (no change); realistic images (blur, noise, weak texture) sit at 0.2-0.4. 0 = off.
  double noise_ref = 0.1;
  double noise_quantile = 0.25;  ///< the quantile (robust to 75 % moving)
  /// Points whose anchor disparity (f·b / depth) is below this are not judged (their stereo
  /// depth cannot tell motion from noise); 0 = judge all.
  double min_disparity_px = 0;
  /// Each feature's match noise σ_px² S with S its Feature::match_shape (stretched along an
  /// edge, where KLT and the stereo match slide) instead of σ_px² I; the depth's noise from
  /// S's component along the baseline. 0 = σ_px² I for every feature.
  bool shape = true;
};

/// Extension of DESIGN §4.3 (not in the paper) for one camera (no T_r_l): the depth-sign
/// test (dynamic::depthSign). It uses the stereo test's sigma_px, strikes, anchor_frames
/// and drift_mps.
struct MonoMotionOptions {
  bool enabled = true;  ///< `mono_motion_test`
  double z = 3.29;      ///< a failure: the inverse depth this many σ below 0 (one-sided 99.95 %)
};

struct IdyOptions {
  double lambda_dy = 4.0;    ///< px², elimination threshold (eq. 4)
  double lambda_dy_c = 1.0;  ///< px², candidate threshold (eq. 6)
  /// Extension of §4.2 (not in the paper): d_s is scored from a track's this-th observation
  /// on; earlier observations are neither in the elimination set (eq. 4-5) nor candidates
  /// (eq. 6), and their d_s_px2 stays 0. 2 (or 1) = every tracked observation (the paper).
  /// 3 spares a new corner's first KLT step, the noisiest on blurred images; measured on
  /// both families and left at 2 (docs/method.md).
  int ds_from_observation = 2;
  StereoMotionOptions stereo;
  MonoMotionOptions mono;
  // The lost-corner test's judgement (frontend::TrackerParams::lost_track_test).
  double lost_stereo_sigma_px = 0.25;   ///< per-coordinate match noise behind the depth tolerance
  double lost_base_tolerance_px = 2.0;  ///< tolerance on top of the depth and prior terms
  /// Not judged when the stereo depth measured at the predicted pixel is below this ratio
  /// of the predicted depth (the corner is hidden behind something nearer).
  double lost_occlusion_ratio = 0.8;
  /// Judged moved only when the best ZNCC of the first patch near the prediction is below
  /// this (a corner on a silhouette still half matches over the background).
  double lost_max_zncc = 0.5;
  /// Extension (not in the paper), imu: 0: the motion prior is the window's constant-velocity
  /// prediction; its position uncertainty is that of an unmodelled acceleration of this σ
  /// (½ σ Δt² per axis), which the credibility factor (eq. 3c) turns into tolerance.
  double cv_prior_acc_sigma = 2.0;

  // Set by the rig (config/modes.h), not a config key.
  /// Left camera -> right camera; the stereo motion test runs only with it.
  std::optional<Eigen::Isometry3d> T_r_l;

  /// Declares every config key of the struct (load, print and save visit this list).
  void declareParams(ParamVisitor& v) {
    v.section("IDY-VINS (DESIGN §4)");
    v.param({"lambda_dy", "px^2, elimination threshold (eq. 4)", ParamRule::kPositive}, lambda_dy);
    v.param({"lambda_dy_c", "px^2, candidate threshold (eq. 6), <= lambda_dy", ParamRule::kNonNegative}, lambda_dy_c);
    v.param({"ds_from_observation", "a track's observation from which d_s is scored, >= 2 (2 = the paper)",
             ParamRule::kPositive},
            ds_from_observation);
    v.section("IDY-VINS stereo motion test (DESIGN §4.9)");
    StereoMotionOptions& m = stereo;
    v.param({"stereo_motion_test", "0/1"}, m.enabled);
    v.param({"stereo_motion_chi2", "chi2 (4 dof) of a failure", ParamRule::kPositive}, m.chi2);
    v.param({"stereo_motion_sigma_px", "px, one match", ParamRule::kPositive}, m.sigma_px);
    v.param({"stereo_motion_strikes", "consecutive failures before removal", ParamRule::kPositive}, m.strikes);
    v.param({"stereo_motion_anchor_frames", "frames back to the anchor", ParamRule::kPositive}, m.anchor_frames);
    v.param({"stereo_motion_drift_mps", "m/s, drift of the chained priors", ParamRule::kNonNegative}, m.drift_mps);
    v.param({"stereo_motion_remove_chi2", "chi2 that removes on a repeated failure, 0 = stereo_motion_chi2",
             ParamRule::kNonNegative},
            m.remove_chi2);
    v.param({"stereo_motion_persistent_strikes", "failures that remove whatever the chi2, 0 = never",
             ParamRule::kNonNegative},
            m.persistent_strikes);
    v.param(
        {"stereo_motion_left_chi2", "chi2 (2 dof) of the left residual that spares, 0 = off", ParamRule::kNonNegative},
        m.left_chi2);
    v.param({"stereo_motion_noise_ref", "chi2 quantile above which the test scales, 0 = off", ParamRule::kNonNegative},
            m.noise_ref);
    v.param({"stereo_motion_noise_quantile", "quantile of the measured noise", ParamRule::kOpenUnit}, m.noise_quantile);
    v.param({"stereo_motion_min_disparity_px", "px, anchor disparity below which points are not judged",
             ParamRule::kNonNegative},
            m.min_disparity_px);
    v.param({"stereo_motion_shape", "0/1, each feature's noise shaped by its structure tensor"}, m.shape);
    v.param({"mono_motion_test",
             "0/1, one camera: the depth-sign test (uses the stereo test's sigma, strikes, "
             "anchor, drift)"},
            mono.enabled);
    v.param({"mono_motion_z", "sigmas of inverse depth below 0 that fail the depth-sign test", ParamRule::kPositive},
            mono.z);
    v.param({"cv_prior_acc_sigma", "m/s^2, imu: 0: unmodelled acceleration of the constant-velocity motion prior",
             ParamRule::kPositive},
            cv_prior_acc_sigma);
    v.section("IDY-VINS lost-corner test (lost_track_test)");
    v.param({"lost_stereo_sigma_px", "px, match noise behind the depth tolerance", ParamRule::kPositive},
            lost_stereo_sigma_px);
    v.param({"lost_base_tolerance_px", "px, tolerance on top of depth and prior", ParamRule::kNonNegative},
            lost_base_tolerance_px);
    v.param({"lost_occlusion_ratio", "measured / predicted depth below which a corner is hidden", ParamRule::kFraction},
            lost_occlusion_ratio);
    v.param({"lost_max_zncc", "best first-patch ZNCC near the prediction for 'moved'", ParamRule::kCorrelation},
            lost_max_zncc);
  }
};

}  // namespace idyvins::dynamic
