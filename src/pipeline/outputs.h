#pragma once
// What a finished run leaves behind, for any embedder (the `idyvins run` command, a ROS
// node, a test): the trajectory and map files and the run summary of stats.json.

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "io/output_folder.h"
#include "pipeline/system.h"

namespace idyvins::pipeline {

/// Why tracks ended (frontend::TrackLosses) as a stats.json object: klt, border, backward,
/// alignment, pruned.
nlohmann::json toJson(const frontend::TrackLosses& l);
/// An extrinsic estimate: t_b_c0 (m), q_b_c0 (x y z w), whether it is refined, its σ (-1: none yet).
nlohmann::json toJson(const backend::ExtrinsicEstimate& e);

/// Writes into the existing `folder`: trajectory.tum (TUM), trajectory.csv (EuRoC),
/// state.csv (pose, velocity, biases in EuRoC's ground-truth columns), map_static.ply,
/// map_dynamic.ply and map_all.ply (labelled points), resets.csv (each reset: time, frame,
/// when and how the trajectory went on, why); each under NAME.part first, renamed
/// when complete. Throws InputError when a file cannot be written.
void writeResultFiles(const std::string& folder, const Result& result);

/// The run summary (stats.json's "summary"): frames, timing per stage, solve profile,
/// initialization, time offset, lost-corner counts, map sizes, resets; "classification"
/// is null (pipeline::toJson of the observation recorder's figures goes there).
nlohmann::json summaryJson(const Result& result, Mode mode, double wall_s);

/// The output folder of a run (`idyvins run --out`, the ROS node's `~out`): staged, replacing only
/// an earlier run's folder (its manifest, or, written before manifests, only the names a run writes,
/// run.json and stats.json among them, plus `extra_names`), never one of `inputs` (io/output_folder.h).
io::OutputFolderOptions runFolderOptions(std::vector<std::string> inputs, bool force,
                                         const std::vector<std::string>& extra_names = {});

/// A run "has a result" when its poses cover at least this share of its frames (`idyvins run`
/// exits 4 below it; the initialization window alone is 11 frames of 20 Hz).
inline constexpr double kMinPoseShare = 0.5;

/// Why a run has fewer poses than kMinPoseShare of its frames, in one line naming the cause
/// (the run ended before the initialization window filled, too few features, PnP or gravity
/// alignment failures and what usually causes them); empty when it has enough.
std::string whyNoTrajectory(const Result& result);

/// Adds ate_rmse_m (SE3 alignment, stamps associated within 10 ms) and path_length_m
/// against `groundtruth` to `summary`, and with a similarity alignment (evo's -as)
/// ate_sim3_rmse_m and scale_error = 1/s − 1 (positive: the estimated path is too long);
/// adds nothing when the two do not overlap. After
/// resets, "segments" holds each segment's span and its own ATE too (aligned on its own).
void addAte(nlohmann::json& summary, const std::vector<StampedPose>& groundtruth, const Result& result);

}  // namespace idyvins::pipeline
