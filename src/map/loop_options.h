#pragma once
// Loop closure's parameters: the single place their defaults live, with their config keys
// (core/params.h). Header-only, so the config reader needs no loop-closure library.

#include <cstddef>

#include "core/params.h"

namespace idyvins::map {

struct PlaceRecognitionOptions {
  int neighbours = 4;    ///< nearest descriptors looked up per query descriptor
  int max_hamming = 40;  ///< a neighbour farther than this (bits of 256) does not vote
  int min_votes = 15;    ///< a keyframe with fewer votes is no candidate
  std::size_t max_candidates = 3;
  /// faiss IndexBinaryHash: descriptors bucketed by their first hash_bits bits; a lookup visits
  /// the buckets within hash_flips bit flips of the query's.
  int hash_bits = 16, hash_flips = 1;
};

struct VerifyOptions {
  int max_hamming = 50;        ///< a match is at most this far (bits)
  double ratio = 0.8;          ///< and clearly nearer than the second nearest landmark
  int min_inliers = 25;        ///< PnP inliers needed for a loop
  double reprojection_px = 3;  ///< RANSAC inlier threshold
  double focal_px = 460;       ///< to turn it into normalized units (set from the left camera)
  int iterations = 200;
  /// A loop's PnP position uncertainty (worst axis, 1 sigma; positionSigma with 1 px noise and
  /// stereo-only depth, so it overstates) above this is refused: far landmarks leave the
  /// translation loose (docs/loop-closure.md#measured).
  double max_sigma_position_m = 0.35;
  double stereo_baseline_m = 0.11;  ///< depth uncertainty of the stored landmarks (set from the rig)
};

struct PoseGraphOptions {
  int odometry_neighbours = 4;       ///< odometry edges from each keyframe to this many predecessors (VINS-Fusion: 4)
  double odometry_sigma_t = 0.1;     ///< m
  double odometry_sigma_yaw = 0.01;  ///< rad
  double loop_sigma_t = 0.1;         ///< m
  double loop_sigma_yaw = 0.01;      ///< rad
  double loop_huber = 1.0;           ///< Huber threshold of loop edges, in sigmas
  int max_iterations = 50;
};

struct LoopOptions {
  bool enabled = false;     ///< the config's loop_closure
  double min_age_s = 20.0;  ///< a keyframe is matched only against keyframes at least this much older
  int extra_corners = 150;  ///< recognition corners detected beside the landmarks' own
  /// A keyframe nearer than this to the last one the loop closer took (and turned less than
  /// min_keyframe_turn_rad) is skipped: the database grows with the places seen, not with time.
  double min_keyframe_distance_m = 0.3;
  double min_keyframe_turn_rad = 0.17;
  /// A loop may move the newest keyframe from its corrected pose by at most the drift the
  /// odometry can have gathered since the graph last fixed it: base + rate x the path (odometry
  /// length) since the later of the old keyframe and the last solved node; more is refused.
  double max_loop_shift_m = 0.3;
  double max_loop_shift_per_m = 0.03;  ///< 3 % of the path
  double max_loop_yaw_rad = 0.05;      ///< likewise the yaw: base,
  double max_loop_yaw_per_m = 0.001;   ///< rad per metre of path
  double max_tilt_rad = 0.1;           ///< PnP's roll/pitch disagreeing with the odometry's by more: refused
  /// The pose graph is solved at the first loop and at a relocalization at once, then at most
  /// every this many keyframes while loops come, and at the end (VINS-Fusion solves whenever
  /// its thread is free; here the points are fixed in the keyframe stream: deterministic).
  int graph_solve_interval = 10;
  /// Dynamic candidates not yet cleared join the keyframe's landmarks (PnP, descriptors, saved
  /// maps). Off: they are kept apart (docs/loop-closure.md#candidates).
  bool use_candidates = false;
  /// Relocalization in a loaded map: a match is confirmed by another within this many keyframes
  /// implying the same map <- odometry transform (within the two tolerances below).
  int relocalization_window = 3;
  double relocalization_tolerance_m = 0.5;
  double relocalization_tolerance_rad = 0.05;
  PlaceRecognitionOptions recognition;
  VerifyOptions verify;
  PoseGraphOptions graph;

  /// Declares the config keys (core/params.h); the rest keep their defaults.
  void declareParams(ParamVisitor& v) {
    v.section("Loop closure (DESIGN §7)");
    v.param({"loop_closure", "0/1, close loops: trajectory_loop.tum, loops.csv (VINS-Mono's key)"}, enabled);
    v.param(
        {"loop_min_age", "s, a keyframe is matched against keyframes at least this much older", ParamRule::kPositive},
        min_age_s);
    v.param({"loop_min_inliers", "PnP inliers that make a loop", ParamRule::kPositive}, verify.min_inliers);
    v.param({"loop_extra_corners", "recognition corners per keyframe beside the landmarks'", ParamRule::kNonNegative},
            extra_corners);
    v.param({"loop_max_position_sigma",
             "m, a loop whose PnP position is more uncertain (1 sigma, worst axis) is refused", ParamRule::kPositive},
            verify.max_sigma_position_m);
    v.param({"loop_use_candidates", "0/1, dynamic candidates not yet cleared join the loop closer's landmarks"},
            use_candidates);
    v.param(
        {"loop_max_shift",
         "m, a loop moving the newest keyframe farther from its corrected pose (plus the drift allowance) is refused",
         ParamRule::kPositive},
        max_loop_shift_m);
    v.param(
        {"loop_max_drift", "drift allowance of loop_max_shift per metre travelled since the graph last fixed the pose",
         ParamRule::kNonNegative},
        max_loop_shift_per_m);
    v.param(
        {"loop_keyframe_distance", "m, keyframes nearer than this to the last one taken are skipped (unless turned)",
         ParamRule::kNonNegative},
        min_keyframe_distance_m);
  }
};

}  // namespace idyvins::map
