#pragma once
// The sliding-window estimator's parameters: the single place their defaults live, with
// their config keys (core/params.h). VINS-Fusion's solver and time-offset keys keep their
// names and meaning.

#include "core/params.h"

namespace idyvins::backend {

struct EstimatorOptions {
  // VINS-Fusion's solver keys.
  /// Wall-clock cap per solve, seconds; applied only with time_limited.
  double max_solver_time_s = 0.04;
  int max_num_iterations = 8;
  double keyframe_parallax_px = 10.0;  ///< mean parallax for a new keyframe, pixels
  /// Cap each solve at max_solver_time_s of wall clock, as VINS-Fusion does, for live use.
  /// Results then depend on machine load; off, solves stop on max_num_iterations and
  /// Ceres' convergence tolerances only (deterministic).
  bool time_limited = false;
  /// A solve has converged when an iteration lowers the cost by less than this fraction of
  /// it (Ceres' own default is 1e-6; docs/results.md has the measurement behind the value).
  double function_tolerance = 1e-4;
  /// The window's own solver (window_problem.h: Ceres' dogleg restated, landmarks eliminated one
  /// at a time) or Ceres itself on the same problem.
  bool window_solver = true;

  // Camera–IMU time offset (VINS-Fusion's keys): image stamp + td = IMU time.
  bool estimate_td = false;  ///< estimate td online in the window (DESIGN §4.11)
  double td_s = 0.0;         ///< the offset, or its initial value with estimate_td, seconds

  // Camera–IMU extrinsics (VINS-Fusion's estimate_extrinsic): 0 keeps body_T_cam0/1 as written;
  // 1 refines the left camera's mount in the window, the stereo pair rigid, from the config's
  // values (a prior of extrinsic_prior_deg/_m on them); 2 starts the rotation from the hand–eye
  // calibration of the tracks against the gyroscope, then as 1 (backend/extrinsic.h).
  int estimate_extrinsic = 0;
  double extrinsic_prior_deg = 5.0;  ///< deg, σ of the prior on the mount's rotation (its start value)
  double extrinsic_prior_m = 0.05;   ///< m, σ of the prior on the mount's translation

  // Measurement model and window management.
  /// Pixel noise of projection factors (the one default of it; ProjectionWeight takes it from
  /// here). Tighter than VINS-Fusion's 1.5 px: the tracks are more accurate than that, and with
  /// the prior share below it is what the validation statics need (docs/results.md, A prior
  /// that counts each landmark once).
  double sigma_px = 0.5;
  double huber_px = 1.0;    ///< Huber threshold on the whitened residual
  double outlier_px = 3.0;  ///< mean reprojection error that removes a landmark
  /// A right observation whose reprojection error after a solve exceeds this drops out of its
  /// landmark (the left track stays; VINS-Fusion judges only whole landmarks, as outlier_px
  /// does). A right match that slid along an edge or onto an occluder is off by pixels and
  /// biases the depth, hence the scale (docs/results.md, right observations judged alone,
  /// both families). 0: right observations are never judged alone; nor are they with estimate_td.
  double stereo_outlier_px = 1.0;
  double init_rotation_check_deg = 3.0;  ///< PnP vs gyro disagreement that rejects an init frame
  int min_pnp_points = 15;
  int clear_after_observations = 4;  ///< a candidate that passes with this many observations becomes static
  /// Extension of DESIGN §4.6 (not in the paper), in the modes with post-processing (config/
  /// modes.h switches it off in the others): a landmark that fails the outlier_px test is
  /// confirmed dynamic like a failing candidate (its track leaves the window for good, dynamic
  /// map) instead of being dropped and re-triangulated from its next observation.
  bool confirm_outliers = true;
  /// Fraction of the marginalization prior's information kept at each keyframe (1: all, as
  /// VINS-Fusion). Below 1 the prior fades: what frames k keyframes old contributed weighs
  /// prior_fading^k (docs/results.md: the validation family's scale error).
  double prior_fading = 1.0;
  /// A landmark whose anchor keyframe leaves enters the prior with all its window
  /// observations and then lives on with them in the window (VINS-Fusion's rule): a long
  /// track's observations are counted once per re-anchoring. With this key it brings only
  /// Landmark::priorShare() of that information (docs/method.md, The estimator).
  bool prior_landmark_share = true;
  /// When a landmark's anchor leaves the window: keep the point that best fits all its window
  /// observations (true), or move it onto its next observation's ray at its estimated depth
  /// (false, VINS-Fusion). FeatureManager::removeOldest; docs/results.md for both families.
  bool reanchor_triangulate = false;
  /// Each landmark estimates its anchor ray with its inverse depth (3 parameters) and its
  /// anchor observation is a residual like the others, so re-anchoring keeps the point and
  /// takes no measurement as exact (false: the ray is the anchor observation, VINS-Fusion).
  /// Not with estimate_td (a config error). docs/results.md for every family.
  bool estimate_anchor_ray = false;

  // What the integration between two frames can bridge (issue: faults end a segment cleanly).
  /// Two IMU samples farther apart than this between two frames (a dropout, a time jump)
  /// reset the window: the gap is not integrated.
  double max_imu_gap_s = 0.1;
  /// Two frames farther apart than this (a camera dropout, a time jump) reset the window.
  double max_frame_gap_s = 1.0;
  /// An IMU gap (above max_imu_gap, or no samples yet) on an initialized stereo rig: the frame
  /// enters the window without an IMU factor, held by its stereo projection factors (its speed
  /// and biases carried, held constant while no IMU factor touches them); the IMU factors resume
  /// from the state the vision kept. false: the segment ends (a reset), as before.
  bool bridge_imu_gaps = true;
  /// The config's `imu` (not a key of its own): false runs stereo alone, every frame without an IMU
  /// factor, the first frame's pose held (the gauge), the world the first body frame (no gravity).
  bool use_imu = true;
  /// After a failure the new segment's first window has no marginalization prior: its
  /// biases are tied to the last good state's with these standard deviations until the first
  /// prior forms (0: free, as VINS-Fusion). Without it a window full of traffic can push the
  /// accelerometer bias past the failure test again (docs/faults.md). Only when the last good
  /// state's segment had solved kSettledFrames frames: biases from the first window's
  /// transient are not tied to (the new segment starts from zero ba, as the first start).
  double reset_bias_prior_acc = 0.2;   ///< m/s^2
  double reset_bias_prior_gyr = 0.02;  ///< rad/s

  // Set by the mode (config/modes.h), not config keys.
  /// DESIGN §4.5: candidate observations weighted by 1/m_j, recomputed every solver
  /// iteration from the current poses (modes idy, idy-ba).
  bool candidate_weights = false;
  /// DESIGN §4.6: confirm candidates as dynamic (leave the window) or clear them to static.
  bool post_process = false;
  /// Keep the oldest frame's yaw and position through each solve (backend/gauge.h); off in
  /// tests of the free gauge only.
  bool fix_gauge = true;

  /// The camera–IMU calibration's keys: the time offset and the extrinsics.
  void declareCalibrationParams(ParamVisitor& v) {
    v.section("Camera-IMU time offset: image stamp + td = IMU time (s)");
    v.param({"estimate_td", "0/1, estimate td online"}, estimate_td);
    v.param({"td", "s, the offset (initial value with estimate_td)", ParamRule::kTimeOffset}, td_s);
    v.section("Camera-IMU extrinsics (VINS-Fusion's estimate_extrinsic)");
    v.param({"estimate_extrinsic",
             "0: as written, 1: refined online from them, 2: rotation from the tracks (hand-eye), then refined",
             ParamRule::kExtrinsicMode},
            estimate_extrinsic);
    v.param({"extrinsic_prior_deg", "deg, sigma of the prior on the refined rotation (its start value)",
             ParamRule::kPositive},
            extrinsic_prior_deg);
    v.param(
        {"extrinsic_prior_m", "m, sigma of the prior on the refined translation (the config's)", ParamRule::kPositive},
        extrinsic_prior_m);
  }

  /// Declares every config key of the struct (load, print and save visit this list).
  void declareParams(ParamVisitor& v) {
    v.section("Sliding-window optimization (VINS-Fusion's keys)");
    v.param({"max_solver_time", "s per solve, applied only with solver_time_limit 1", ParamRule::kPositive, true},
            max_solver_time_s);
    v.param({"max_num_iterations", "solver iterations per solve", ParamRule::kPositive, true}, max_num_iterations);
    v.param({"keyframe_parallax", "px, mean parallax of a new keyframe", ParamRule::kPositive, true},
            keyframe_parallax_px);
    v.param({"solver_time_limit", "0/1, cap solves at max_solver_time (results depend on load)"}, time_limited);
    v.param({"solver_function_tolerance", "relative cost decrease of convergence", ParamRule::kPositive},
            function_tolerance);
    v.param({"window_solver", "0/1, the window's own Schur-complement solver (1) or Ceres (0), the same method"},
            window_solver);
    declareCalibrationParams(v);
    v.section("Sliding-window measurement model");
    v.param({"projection_sigma_px", "px, pixel noise of projection factors", ParamRule::kPositive}, sigma_px);
    v.param({"projection_huber", "Huber threshold on the whitened residual", ParamRule::kPositive}, huber_px);
    v.param({"outlier_px", "px, mean reprojection error that removes a landmark", ParamRule::kPositive}, outlier_px);
    v.param(
        {"stereo_outlier_px", "px, reprojection error that drops one right observation (0: off; off with estimate_td)",
         ParamRule::kNonNegative},
        stereo_outlier_px);
    v.param(
        {"init_rotation_check_deg", "deg, PnP vs gyro disagreement that rejects an init frame", ParamRule::kPositive},
        init_rotation_check_deg);
    v.param({"min_pnp_points", "points of an initialization PnP", ParamRule::kPositive}, min_pnp_points);
    v.param({"candidate_clear_observations", "passing observations that clear a candidate", ParamRule::kPositive},
            clear_after_observations);
    v.param({"confirm_outliers_dynamic", "0/1, outlier landmarks confirmed dynamic (idy, idy-ba)"}, confirm_outliers);
    v.param({"prior_fading", "fraction of the prior's information kept per keyframe (1: all)", ParamRule::kFraction},
            prior_fading);
    v.param({"prior_landmark_share",
             "0/1, a re-anchored landmark brings 1/m of its information into the prior (1) or all of it (0)"},
            prior_landmark_share);
    v.param({"reanchor_triangulate",
             "0/1, a re-anchored landmark keeps its multi-view point (1) or takes its next ray (0)"},
            reanchor_triangulate);
    v.param({"estimate_anchor_ray", "0/1, landmarks estimate their anchor ray (3 parameters; needs estimate_td 0)"},
            estimate_anchor_ray);
    v.section("Faults: what the integration between two frames bridges (larger gaps reset the window)");
    v.param({"max_imu_gap", "s, largest gap between two IMU samples", ParamRule::kPositive}, max_imu_gap_s);
    v.param({"max_frame_gap", "s, largest gap between two frames", ParamRule::kPositive}, max_frame_gap_s);
    v.param({"bridge_imu_gaps",
             "0/1, an IMU gap on an initialized stereo rig is carried by stereo alone (1) or ends the segment (0)"},
            bridge_imu_gaps);
    v.param({"reset_bias_prior_acc",
             "m/s^2, after a failure: the accelerometer bias tied to the last good one, if settled (0: free)",
             ParamRule::kNonNegative},
            reset_bias_prior_acc);
    v.param({"reset_bias_prior_gyr",
             "rad/s, after a failure: the gyroscope bias tied to the last good one, if settled (0: free)",
             ParamRule::kNonNegative},
            reset_bias_prior_gyr);
  }
};

}  // namespace idyvins::backend
