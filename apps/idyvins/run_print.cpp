// The summary `idyvins run` prints from stats.json's summary (what the run did, its errors,
// the files it wrote).

#include "run_print.h"

#include <csignal>
#include <cstdio>

#include "commands.h"
#include "core/time.h"
#include "pipeline/outputs.h"

namespace idyvins::app {
namespace {

/// The loop-closure lines of the run's summary (nothing when it was off).
void printLoops(const nlohmann::json& l, TimeNs first_t_ns) {
  if (l.is_null()) return;
  std::printf(
      "loop closure: %zu keyframes (%zu skipped, too near the last), %zu loops closed; %.1f ms per keyframe, "
      "%.1f ms per pose-graph solve",
      l["keyframes"].get<std::size_t>(), l["keyframes_skipped"].get<std::size_t>(), l["loops"].get<std::size_t>(),
      l["mean_detect_ms_per_keyframe"].get<double>(), l["mean_graph_ms_per_solve"].get<double>());
  if (l.contains("ate_rmse_m")) std::printf("; ATE RMSE with loops %.4f m", l["ate_rmse_m"].get<double>());
  std::printf("\n");
  if (const auto& m = l["map"]; !m.is_null()) {
    if (m["relocalized"].get<bool>())
      std::printf("map: %zu keyframes loaded; relocalized %.1f s after the first frame, %zu loops to the map\n",
                  m["loaded_keyframes"].get<std::size_t>(),
                  1e-9 * static_cast<double>(m["first_relocalization_t_ns"].get<TimeNs>() - first_t_ns),
                  m["loops_to_map"].get<std::size_t>());
    else
      std::fprintf(stderr,
                   "warning: %zu map keyframes loaded, never relocalized in the map (%zu unconfirmed "
                   "matches): no trajectory_loop.tum; the poses are in the run's own odometry frame\n",
                   m["loaded_keyframes"].get<std::size_t>(), m["unconfirmed_matches"].get<std::size_t>());
  }
}

/// The ATE lines of a run with ground truth: SE3, sim(3) with the scale error, each segment's.
void printAte(const nlohmann::json& s) {
  if (s.contains("ate_rmse_m")) {
    const double ate = s["ate_rmse_m"], path = s["path_length_m"];
    std::printf("ATE RMSE (SE3) %.4f m over %.1f m (%.2f%%)\n", ate, path, 100 * ate / path);
    if (s.contains("ate_sim3_rmse_m"))
      std::printf("ATE RMSE (sim3) %.4f m, scale error %+.3f%% (positive: path too long)\n",
                  s["ate_sim3_rmse_m"].get<double>(), 100 * s["scale_error"].get<double>());
  }
  if (s.contains("segments"))
    for (const auto& g : s["segments"])
      if (!g["ate_rmse_m"].is_null())
        std::printf("  segment %.2f-%.2f s, %zu poses: ATE %.4f m on its own\n",
                    1e-9 * (g["from_t_ns"].get<double>() - s["first_t_ns"].get<double>()),
                    1e-9 * (g["to_t_ns"].get<double>() - s["first_t_ns"].get<double>()), g["poses"].get<std::size_t>(),
                    g["ate_rmse_m"].get<double>());
}

/// The input the run could not use: IMU samples dropped, unpaired images, frames beyond the IMU.
void printInputWarnings(const nlohmann::json& s) {
  const auto& dropped = s["imu_samples_dropped"];
  if (dropped["out_of_range"].get<std::size_t>() + dropped["out_of_order"].get<std::size_t>() > 0)
    std::printf(
        "warning: IMU samples dropped: %zu not finite or beyond imu_max_acc / imu_max_gyr, %zu not after "
        "the previous sample's time\n",
        dropped["out_of_range"].get<std::size_t>(), dropped["out_of_order"].get<std::size_t>());
  if (dropped["spikes"].get<std::size_t>() > 0)
    std::printf(
        "warning: %zu IMU spikes dropped (%zu samples beyond imu_spike_acc / imu_spike_gyr of the recent ones, "
        "back within imu_spike_max_ms)\n",
        s["imu_spikes"].get<std::size_t>(), dropped["spikes"].get<std::size_t>());
  if (const auto& u = s["unpaired_images"]; u["cam0"].get<std::size_t>() + u["cam1"].get<std::size_t>() > 0)
    std::printf(
        "warning: stereo images without a partner within 1 ms, not processed: %zu left (cam0), %zu right "
        "(cam1)\n",
        u["cam0"].get<std::size_t>(), u["cam1"].get<std::size_t>());
  if (s["frames_beyond_imu"].get<std::size_t>() > 0)
    std::printf(
        "warning: %zu frame(s) at the end not processed: their time (stamp + td) is after the last IMU sample\n",
        s["frames_beyond_imu"].get<std::size_t>());
}

}  // namespace

void printRunSummary(const nlohmann::json& s, const std::string& out) {
  const double seq_s = s["sequence_s"], wall_s = s["wall_s"];
  std::printf("%zu frames (%.1f s) in %.1f s (%.1fx real time), mode %s, %d thread%s (%s)\n",
              s["frames"].get<std::size_t>(), seq_s, wall_s, seq_s / wall_s, s["mode"].get<std::string>().c_str(),
              s["threads"].get<int>(), s["threads"].get<int>() == 1 ? "" : "s",
              s["threads"].get<int>() == 1 ? "sequential" : "front end of frame k+1 beside the back end of frame k");
  if (s["initialized_at_s"].get<double>() >= 0)
    std::printf("initialized at %.2f s; %zu poses (%.1f%% of the frames); %zu resets\n",
                s["initialized_at_s"].get<double>(), s["poses"].get<std::size_t>(), 100 * s["pose_share"].get<double>(),
                s["resets"].size());
  else
    std::printf("not initialized: %s\n", s["last_status"].get<std::string>().c_str());
  if (s["td_estimated"].get<bool>())
    std::printf("camera-IMU time offset td estimated: %.3f ms at the end\n", 1e3 * s["td_s"].get<double>());
  if (const auto& e = s["extrinsic"]; !e.is_null()) {
    std::printf("camera-IMU extrinsics (estimate_extrinsic %d): cam0 %s %.2f deg and %.1f cm from the config",
                e["estimate_extrinsic"].get<int>(), e["refined"].get<bool>() ? "refined," : "not refined (no motion),",
                e["rotation_change_deg"].get<double>(), 100 * e["translation_change_m"].get<double>());
    if (e["sigma_rot_deg"].get<double>() >= 0)
      std::printf(" (sigma %.3f deg, %.2f cm)", e["sigma_rot_deg"].get<double>(), 100 * e["sigma_t_m"].get<double>());
    std::printf("; %s/config_refined.yaml has them\n", out.c_str());
  }
  printInputWarnings(s);
  std::printf("mean tracking %.2f ms, filter %.3f ms, optimization %.2f ms, marginalization %.2f ms per frame\n",
              s["mean_tracking_ms"].get<double>(), s["mean_filter_ms"].get<double>(),
              s["mean_optimization_ms"].get<double>(), s["mean_marginalization_ms"].get<double>());
  for (const auto& r : s["resets"])
    std::printf("reset at %.3f s (frame %zu): %s; %s\n",
                1e-9 * (r["t_ns"].get<double>() - s["first_t_ns"].get<double>()), r["frame"].get<std::size_t>(),
                r["why"].get<std::string>().c_str(),
                r["resumed_t_ns"].get<TimeNs>() < 0 ? "not initialized again"
                : r["continued_by"] == "imu"        ? "went on from the last good state, propagated with the IMU"
                : r["continued_by"] == "extrapolated"
                    ? "went on from the last good state, at constant velocity across the IMU gap"
                : r["continued_by"] == "held" ? "went on from the last good state, held across the gap"
                                              : "started a new trajectory");
  printAte(s);
  printLoops(s["loop_closure"], s["first_t_ns"].get<TimeNs>());
  std::printf("map: %zu static points, %zu dynamic points\n", s["map_static_points"].get<std::size_t>(),
              s["map_dynamic_points"].get<std::size_t>());
  if (const auto& c = s["classification"]; !c.is_null())
    std::printf(
        "vs ground-truth masks: %.1f%% of observations on moving objects flagged dynamic, %.2f%% of static ones; "
        "%.2f%% of the static map on moving objects\n",
        100 * c["moving_detected_fraction"].get<double>(), 100 * c["static_flagged_fraction"].get<double>(),
        100 * c["static_map_fraction_on_moving"].get<double>());
  std::printf(
      "wrote %s/trajectory.tum, trajectory.csv, state.csv, stats.json, resets.csv, map_static.ply, map_dynamic.ply, "
      "map_all.ply, run.json%s%s (idyvins report %s: the run as a page)\n",
      out.c_str(), s.contains("ate_rmse_m") ? ", groundtruth.tum" : "",
      s["loop_closure"].is_null() ? "" : ", trajectory_loop.tum, loops.csv, map_static_loop.ply", out.c_str());
}

/// Says how a run stopped by `sig` (SIGINT, SIGTERM) after `frames` of `total` frames ended and
/// returns its exit code, 128 + sig. Stopped before the first frame, it wrote nothing: OUT is
/// as it was (the staging folder goes with the run).
int reportRunStop(int sig, std::size_t frames, std::size_t total, const std::string& out) {
  const char* name = sig == SIGINT ? "SIGINT" : "SIGTERM";
  if (frames == 0)
    std::fprintf(stderr, "stopped by %s before the first frame: nothing written, %s as it was\n", name, out.c_str());
  else
    std::fprintf(stderr,
                 "stopped by %s after %zu of %zu frames: %s holds the partial result (summary \"partial\": true)\n",
                 name, frames, total, out.c_str());
  return 128 + sig;
}

/// kOk, or kNoResult with the line saying why when the poses cover too few of the frames.
int runResultCode(const pipeline::Result& result, const std::string& out) {
  const std::string why = pipeline::whyNoTrajectory(result);
  if (why.empty()) return kOk;
  std::fprintf(stderr, "error: no trajectory: %s (exit %d; the files are in %s for inspection)\n", why.c_str(),
               kNoResult, out.c_str());
  return kNoResult;
}

/// The config's and the dataset's warnings, one line each on stderr.
void printRunWarnings(const Config& config, const io::OpenedDataset& in) {
  for (const auto* list : {&config.warnings, &in.warnings})
    for (const std::string& w : *list) std::fprintf(stderr, "warning: %s\n", w.c_str());
}

}  // namespace idyvins::app
