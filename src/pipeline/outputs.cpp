#include "pipeline/outputs.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>

#include "core/error.h"
#include "eval/trajectory_metrics.h"
#include "io/ply.h"
#include "io/trajectory_io.h"

namespace idyvins::pipeline {
namespace {

std::vector<io::LabelledPoint> plyPoints(const std::vector<backend::MapPoint>& a,
                                         const std::vector<backend::MapPoint>& b = {}) {
  std::vector<io::LabelledPoint> out;
  for (const auto* v : {&a, &b})
    for (const auto& p : *v) out.push_back({p.p_w, io::plyLabel(p.label)});
  return out;
}

/// Mean per solve of where the window solves spent their time (ms) and how they ended.
nlohmann::json solveProfileJson(const Summary& s) {
  const double n = static_cast<double>(std::max<std::size_t>(s.solves, 1));
  const backend::SolveProfile& t = s.solve_sum;
  return {{"solves", s.solves},
          {"converged_fraction", s.solves_converged / n},
          {"mean_iterations", t.iterations / n},
          {"mean_build_ms", t.build_ms / n},
          {"mean_preprocess_ms", t.preprocess_ms / n},
          {"mean_residual_ms", t.residual_ms / n},
          {"mean_jacobian_ms", t.jacobian_ms / n},
          {"mean_linear_solver_ms", t.linear_solver_ms / n},
          {"mean_minimizer_ms", t.minimizer_ms / n},
          {"mean_post_ms", t.post_ms / n}};
}

/// The summary's estimate_extrinsic record: both mounts as 4x4 rows, cam0's change from the config.
nlohmann::json extrinsicJson(const std::optional<ExtrinsicSummary>& e) {
  if (!e) return nullptr;
  nlohmann::json mounts = nlohmann::json::array();
  for (const Eigen::Isometry3d& T : e->T_b_c) {
    nlohmann::json rows = nlohmann::json::array();
    for (int i = 0; i < 4; ++i) rows.push_back({T(i, 0), T(i, 1), T(i, 2), T(i, 3)});
    mounts.push_back(rows);
  }
  nlohmann::json j = toJson(e->estimate);
  j["estimate_extrinsic"] = e->mode;
  j["body_T_cam"] = mounts;
  j["rotation_change_deg"] = e->rotation_change_deg;
  j["translation_change_m"] = e->translation_change_m;
  return j;
}

}  // namespace

nlohmann::json toJson(const backend::ExtrinsicEstimate& e) {
  return {{"t_b_c0", {e.t_b_c0.x(), e.t_b_c0.y(), e.t_b_c0.z()}},
          {"q_b_c0", {e.q_b_c0.x(), e.q_b_c0.y(), e.q_b_c0.z(), e.q_b_c0.w()}},
          {"refined", e.open},
          {"rotation_known", e.rotation_known},
          {"sigma_t_m", e.sigma_t_m},
          {"sigma_rot_deg", e.sigma_rot_deg}};
}

namespace {

void writeResetsCsv(const std::string& path, const std::vector<ResetEvent>& resets) {
  std::ofstream f(path);
  if (!f) throw InputError(path, "cannot write file");
  f << "#t_ns,frame,resumed_t_ns,continued_by,why\n";
  for (const auto& e : resets) {
    std::string why = e.why;  // one CSV field: no commas or quotes of its own
    for (char& c : why)
      if (c == ',' || c == '"') c = ';';
    f << e.t_ns << ',' << e.frame << ',' << e.resumed_t_ns << ',' << e.continued_by << ',' << why << '\n';
  }
  if (!f) throw InputError(path, "write failed");
}

/// The trajectory cut at the resets: poses from one reset to the next are one segment.
std::vector<std::vector<StampedPose>> segments(const Result& r) {
  std::vector<std::vector<StampedPose>> out(1);
  std::size_t next = 0;
  for (const auto& s : r.trajectory) {
    bool cut = false;
    while (next < r.summary.resets.size() && r.summary.resets[next].t_ns <= s.t_ns) {
      cut = true;
      ++next;
    }
    if (cut && !out.back().empty()) out.emplace_back();
    out.back().push_back(toStampedPose(s));
  }
  return out;
}

}  // namespace

void writeLoopsCsv(const std::string& path, const std::vector<map::LoopEvent>& loops) {
  std::ofstream f(path);
  f << "# old_t_ns,new_t_ns,old_keyframe,new_keyframe,votes,matches,inliers,dx,dy,dz,dyaw_rad,to_map,sigma_position_m"
       " (new keyframe in the old one's body frame, 4-DoF; keyframes are pose-graph nodes; to_map 1: the old"
       " keyframe is from the loaded map, its time on that map's clock; sigma_position_m: PnP position uncertainty)\n";
  char line[288];
  for (const auto& l : loops) {
    std::snprintf(line, sizeof(line), "%lld,%lld,%u,%u,%d,%d,%d,%.6f,%.6f,%.6f,%.6f,%d,%.4f\n",
                  static_cast<long long>(l.old_t_ns), static_cast<long long>(l.new_t_ns), l.old_keyframe,
                  l.new_keyframe, l.votes, l.matches, l.inliers, l.relative.t_from_to.x(), l.relative.t_from_to.y(),
                  l.relative.t_from_to.z(), l.relative.dyaw, l.to_map ? 1 : 0, l.sigma_position_m);
    f << line;
  }
  if (!f) throw InputError(path, "write failed");
}

nlohmann::json loopJson(const Result& r) {
  const map::LoopStats& st = r.loop_stats;
  const double k = std::max<double>(1.0, static_cast<double>(st.keyframes));
  return {{"keyframes", st.keyframes},
          {"keyframes_skipped", st.keyframes_skipped},
          {"loops", st.loops},
          {"candidates_checked", st.candidates_checked},
          {"refused_by_consistency", st.refused_by_consistency},
          {"mean_detect_ms_per_keyframe", st.sum_detect_ms / k},
          {"graph_solves", st.graph_solves},
          {"mean_graph_ms_per_solve", st.graph_solves ? st.sum_graph_ms / static_cast<double>(st.graph_solves) : 0.0},
          {"static_map_points", r.loop_static_map.size()},
          {"landmarks", st.landmarks},
          {"candidates_kept_apart", st.candidates_kept_apart},
          {"map", st.map_keyframes == 0
                      ? nlohmann::json()
                      : nlohmann::json{{"loaded_keyframes", st.map_keyframes},
                                       {"relocalized", st.relocalized},
                                       {"first_relocalization_t_ns", st.relocalized ? st.first_relocalization_t_ns : 0},
                                       {"loops_to_map", st.map_loops},
                                       {"unconfirmed_matches", st.relocalizations_unconfirmed}}}};
}

void writeResultFiles(const std::string& out, const Result& r) {
  // Each file is written under a temporary name and renamed when complete: a run stopped
  // while writing never leaves a cut file under a final name.
  const auto atomically = [&out](const std::string& name, const std::function<void(const std::string&)>& write) {
    const std::string path = out + "/" + name, part = path + ".part";
    write(part);
    std::error_code ec;
    std::filesystem::rename(part, path, ec);
    if (ec) throw InputError(path, "cannot rename " + part + ": " + ec.message());
  };
  std::vector<StampedPose> poses;
  std::vector<GroundTruthState> states;  // the full estimated state, written as state.csv
  for (const auto& s : r.trajectory) {
    poses.push_back(toStampedPose(s));
    states.push_back({s.t_ns, s.state.p_w_b, s.state.q_w_b, s.state.v_w, s.state.bg, s.state.ba});
  }
  atomically("map_static.ply", [&](const std::string& p) { io::writePly(p, plyPoints(r.static_map)); });
  atomically("map_dynamic.ply", [&](const std::string& p) { io::writePly(p, plyPoints(r.dynamic_map)); });
  atomically("map_all.ply", [&](const std::string& p) { io::writePly(p, plyPoints(r.static_map, r.dynamic_map)); });
  atomically("trajectory.tum", [&](const std::string& p) { io::writeTum(p, poses); });
  atomically("trajectory.csv", [&](const std::string& p) { io::writeEurocCsv(p, poses); });
  atomically("state.csv", [&](const std::string& p) { io::writeStateCsv(p, states); });
  atomically("resets.csv", [&](const std::string& p) { writeResetsCsv(p, r.summary.resets); });
  if (!r.loop_enabled) return;
  // In a loaded map the corrected poses are map poses only once the run relocalized.
  if (r.loop_stats.map_keyframes == 0 || r.loop_stats.relocalized)
    atomically("trajectory_loop.tum", [&](const std::string& p) { io::writeTum(p, r.loop_trajectory); });
  atomically("map_static_loop.ply", [&](const std::string& p) { io::writePly(p, plyPoints(r.loop_static_map)); });
  atomically("loops.csv", [&](const std::string& p) { writeLoopsCsv(p, r.loops); });
}

nlohmann::json toJson(const frontend::TrackLosses& l) {
  return {
      {"klt", l.klt}, {"border", l.border}, {"backward", l.backward}, {"alignment", l.alignment}, {"pruned", l.pruned}};
}

nlohmann::json summaryJson(const Result& r, Mode mode, double wall_s) {
  const Summary& s = r.summary;
  const double n = static_cast<double>(s.frames), seq_s = toSeconds(s.last_t_ns - s.first_t_ns);
  nlohmann::json resets = nlohmann::json::array();
  for (const auto& e : s.resets)
    resets.push_back({{"t_ns", e.t_ns},
                      {"frame", e.frame},
                      {"why", e.why},
                      {"resumed_t_ns", e.resumed_t_ns},
                      {"continued_by", e.continued_by}});
  std::vector<StampedPose> poses;  // the estimate's own path, with or without ground truth
  for (const auto& p : r.trajectory) poses.push_back(toStampedPose(p));
  const double est_s = poses.size() > 1 ? toSeconds(poses.back().t_ns - poses.front().t_ns) : 0.0;
  return {
      {"frames", s.frames},
      {"mode", toString(mode)},
      {"sequence_s", seq_s},
      {"estimate_path_length_m", poses.size() > 1 ? eval::pathLength(poses) : 0.0},
      {"estimate_duration_s", est_s},
      {"wall_s", wall_s},
      {"realtime_factor", seq_s / wall_s},
      {"mean_tracking_ms", s.sum_tracking_ms / n},
      {"mean_filter_ms", s.sum_filter_ms / n},
      {"mean_optimization_ms", s.sum_optimization_ms / n},
      {"mean_marginalization_ms", s.sum_marginalization_ms / n},
      {"solve_profile", solveProfileJson(s)},
      {"poses", r.trajectory.size()},
      {"pose_share", n > 0 ? static_cast<double>(r.trajectory.size()) / n : 0.0},
      {"init_failures", s.init_failures},
      {"first_t_ns", s.first_t_ns},
      {"initialized_at_s", s.init_t_ns >= 0 ? toSeconds(s.init_t_ns - s.first_t_ns) : -1.0},
      {"frames_without_prior", s.frames_without_prior},
      {"frames_beyond_imu", s.frames_beyond_imu},
      {"frames_stereo_only", s.frames_stereo_only},
      {"imu_samples_dropped",
       {{"out_of_range", s.imu_out_of_range}, {"out_of_order", s.imu_out_of_order}, {"spikes", s.imu_spike_samples}}},
      {"imu_spikes", s.imu_spikes},
      {"td_s", s.td_s},
      {"td_estimated", s.td_estimated},
      {"extrinsic", extrinsicJson(s.extrinsic)},
      {"lost_new_corners_tested", s.lost_tested},
      {"lost_new_corners_moving", s.lost_moving},
      {"lost_tracks", toJson(s.lost_tracks)},
      {"lost_new", toJson(s.lost_new)},
      {"map_static_points", r.static_map.size()},
      {"map_dynamic_points", r.dynamic_map.size()},
      {"classification", nullptr},
      {"resets", resets},
      {"loop_closure", r.loop_enabled ? loopJson(r) : nlohmann::json()}};
}

namespace {

/// What usually makes the estimator's initialization fail this way.
std::string initFailureHint(const std::string& status) {
  if (status.find("PnP failed") != std::string::npos)
    return "too few features tracked across frames, or no parallax between them (black, frozen or unmatched images?)";
  if (status.find("rotation disagrees") != std::string::npos)
    return "the gyroscope disagrees with the images' rotation (gyroscope in deg/s? body_T_cam0's rotation? td?)";
  if (status.find("alignment failed") != std::string::npos)
    return "the IMU is inconsistent with gravity and the visual motion (accelerometer units? g_norm? IMU stamps? "
           "stereo baseline?)";
  return "";
}

}  // namespace

io::OutputFolderOptions runFolderOptions(std::vector<std::string> inputs, bool force,
                                         const std::vector<std::string>& extra_names) {
  io::OutputFolderOptions o;
  o.tool = "run";
  o.inputs = std::move(inputs);
  o.force = force;
  o.legacy_names = {
      "trajectory.tum",  "trajectory.csv",      "state.csv",       "stats.json",          "stats.json.part",
      "resets.csv",      "map_static.ply",      "map_dynamic.ply", "map_all.ply",         "run.json",
      "groundtruth.tum", "trajectory_loop.tum", "loops.csv",       "map_static_loop.ply", "map_static_on_moving.ply"};
  o.legacy_names.insert(o.legacy_names.end(), extra_names.begin(), extra_names.end());
  o.legacy_required = {"run.json", "stats.json"};
  return o;
}

std::string whyNoTrajectory(const Result& r) {
  const Summary& s = r.summary;
  const std::size_t poses = r.trajectory.size();
  if (s.frames > 0 && static_cast<double>(poses) >= kMinPoseShare * static_cast<double>(s.frames)) return "";
  char share[96];
  std::snprintf(share, sizeof(share), "%zu poses for %zu frames (%.0f%%, at least %.0f%% expected)", poses, s.frames,
                s.frames ? 100.0 * static_cast<double>(poses) / static_cast<double>(s.frames) : 0.0,
                100 * kMinPoseShare);
  std::string why = std::string(share) + ": ";
  const double features = s.frames ? static_cast<double>(s.sum_features) / static_cast<double>(s.frames) : 0.0;
  const auto worst = std::max_element(s.init_failures.begin(), s.init_failures.end(),
                                      [](const auto& a, const auto& b) { return a.second < b.second; });
  if (s.frames == 0) return why + "no frame was processed";
  if (features < 10) {
    char f[64];
    std::snprintf(f, sizeof(f), "%.1f", features);
    return why + "too few features: " + f + " per frame on average (black, saturated or textureless images?)";
  }
  if (worst != s.init_failures.end()) {
    const std::string what = worst->first.substr(std::string("initializing: ").size());
    const std::string hint = initFailureHint(worst->first);
    return why + what + " (" + std::to_string(worst->second) + " times)" + (hint.empty() ? "" : ": " + hint);
  }
  if (poses == 0 && s.frames <= static_cast<std::size_t>(backend::kWindowSize))
    return why + "the run ended after " + std::to_string(s.frames) + " frame(s); initialization needs " +
           std::to_string(backend::kWindowSize + 1) + " frames";
  if (!s.resets.empty())
    return why + "reset at frame " + std::to_string(s.resets.back().frame) + ": " + s.resets.back().why;
  if (s.init_t_ns >= 0) {
    char at[96];
    std::snprintf(at, sizeof(at), "initialized only %.2f s after the first frame",
                  toSeconds(s.init_t_ns - s.first_t_ns));
    return why + at + " (an IMU starting late? no motion at the start?)";
  }
  return why + "last status: " + s.last_status;
}

void addAte(nlohmann::json& summary, const std::vector<StampedPose>& gt, const Result& r) {
  if (gt.empty() || r.trajectory.size() <= 2) return;
  std::vector<StampedPose> est;
  for (const auto& s : r.trajectory) est.push_back(toStampedPose(s));
  try {
    const auto ate = eval::computeAte(gt, est, eval::AlignMode::kSe3, 10'000'000);
    std::vector<StampedPose> gt_pairs;
    for (const auto& [i, j] : ate.pairs) gt_pairs.push_back(gt[i]);
    summary["ate_rmse_m"] = ate.stats.rmse;
    summary["path_length_m"] = eval::pathLength(gt_pairs);
  } catch (const std::exception&) {  // no overlap with the ground truth: no ATE
    return;
  }
  try {  // evo's -as: what is left once the scale is free, and the scale itself
    const auto sim3 = eval::computeAte(gt, est, eval::AlignMode::kSim3, 10'000'000);
    summary["ate_sim3_rmse_m"] = sim3.stats.rmse;
    summary["scale_error"] = 1.0 / sim3.alignment.s - 1.0;
  } catch (const std::exception&) {  // degenerate for a similarity (e.g. no motion): SE3 only
  }
  if (r.loop_enabled && r.loop_trajectory.size() > 2 && (r.loop_stats.map_keyframes == 0 || r.loop_stats.relocalized)) {
    try {
      summary["loop_closure"]["ate_rmse_m"] =
          eval::computeAte(gt, r.loop_trajectory, eval::AlignMode::kSe3, 10'000'000).stats.rmse;
    } catch (const std::exception&) {
    }
  }
  if (r.summary.resets.empty()) return;
  // With resets, the ATE of each segment on its own too (each aligned separately).
  nlohmann::json per = nlohmann::json::array();
  for (const auto& seg : segments(r)) {
    nlohmann::json j = {{"from_t_ns", seg.front().t_ns}, {"to_t_ns", seg.back().t_ns}, {"poses", seg.size()}};
    try {
      j["ate_rmse_m"] = seg.size() > 2
                            ? nlohmann::json(eval::computeAte(gt, seg, eval::AlignMode::kSe3, 10'000'000).stats.rmse)
                            : nlohmann::json();
    } catch (const std::exception&) {
      j["ate_rmse_m"] = nullptr;
    }
    per.push_back(j);
  }
  summary["segments"] = per;
}

}  // namespace idyvins::pipeline
