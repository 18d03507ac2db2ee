// `idyvins run`: the whole system (pipeline::System) on a dataset; writes the trajectory,
// the maps and stats. Parse arguments, open the source, drive the pipeline, write outputs.

#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <unistd.h>
#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>

#include "commands.h"
#include "input.h"
#include "core/build_info.h"
#include "core/checksum.h"
#include "core/error.h"
#include "io/bag_dataset.h"
#include "io/config.h"
#include "io/data_source.h"
#include "io/output_folder.h"
#include "io/ply.h"
#include "io/trajectory_io.h"
#include "pipeline/observers.h"
#include "pipeline/outputs.h"
#include "pipeline/system.h"
#include "prefetch.h"
#include "progress.h"

namespace idyvins::app {
namespace {

struct RunArgs {
  std::string config, dataset, out, mode, dump_observations, groundtruth_topic, save_map, load_map;
  std::string command_line;  ///< as typed (run.json)
  std::size_t max_frames = 0;
  bool solver_time_limit = false, localization_only = false, force = false;
  int threads = 2, feedback_delay = -1;
};

/// Advances a progress bar with every frame.
class ProgressObserver final : public pipeline::FrameObserver {
 public:
  ProgressObserver(Mode mode, std::size_t total) : bar_(std::string("run ") + toString(mode), total, "frames") {}
  void onFrame(const StereoFrame&, const pipeline::FrameOutput& out) override { bar_.update(out.index + 1); }
  void finish() { bar_.finish(); }

 private:
  ProgressBar bar_;
};

/// The signal that asked the run to stop (SIGINT, SIGTERM), 0 while none did. A signal
/// handler can only set a flag: this is the command's, not the library's.
std::atomic<int> g_stop_signal{0};
extern "C" void onStopSignal(int sig) { g_stop_signal = sig; }

/// Feeds the source to the system in time order until it ends, max_frames or a stop
/// signal; returns the number of frames.
std::size_t drive(io::DataSource& source, pipeline::System& system, std::size_t max_frames) {
  PrefetchSource prefetch(source, 4);  // decodes the next images while the system works
  std::size_t frames = 0;
  while (frames < max_frames && g_stop_signal == 0) {
    auto m = prefetch.next();
    if (!m) break;
    if (const auto* imu = std::get_if<ImuSample>(&*m)) {
      system.addImu(*imu);
      continue;
    }
    system.addFrame(std::get<StereoFrame>(*m));
    ++frames;
  }
  return frames;
}

/// The loop-closure lines of the run's summary (nothing when it was off).
void printLoops(const nlohmann::json& l, TimeNs first_t_ns) {
  if (l.is_null()) return;
  std::printf("loop closure: %zu keyframes (%zu skipped, too near the last), %zu loops closed; %.1f ms per keyframe, "
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
      std::fprintf(stderr, "warning: %zu map keyframes loaded, never relocalized in the map (%zu unconfirmed "
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

void printSummary(const nlohmann::json& s, const std::string& out) {
  const double seq_s = s["sequence_s"], wall_s = s["wall_s"];
  std::printf("%zu frames (%.1f s) in %.1f s (%.1fx real time), mode %s, %d thread%s (%s)\n",
              s["frames"].get<std::size_t>(), seq_s, wall_s, seq_s / wall_s, s["mode"].get<std::string>().c_str(),
              s["threads"].get<int>(), s["threads"].get<int>() == 1 ? "" : "s",
              s["threads"].get<int>() == 1 ? "sequential" : "front end of frame k+1 beside the back end of frame k");
  if (s["initialized_at_s"].get<double>() >= 0)
    std::printf("initialized at %.2f s; %zu poses (%.1f%% of the frames); %zu resets\n",
                s["initialized_at_s"].get<double>(), s["poses"].get<std::size_t>(),
                100 * s["pose_share"].get<double>(), s["resets"].size());
  else
    std::printf("not initialized: %s\n", s["last_status"].get<std::string>().c_str());
  if (s["td_estimated"].get<bool>())
    std::printf("camera-IMU time offset td estimated: %.3f ms at the end\n", 1e3 * s["td_s"].get<double>());
  const auto& dropped = s["imu_samples_dropped"];
  if (dropped["out_of_range"].get<std::size_t>() + dropped["out_of_order"].get<std::size_t>() > 0)
    std::printf("warning: IMU samples dropped: %zu not finite or beyond imu_max_acc / imu_max_gyr, %zu not after "
                "the previous sample's time\n",
                dropped["out_of_range"].get<std::size_t>(), dropped["out_of_order"].get<std::size_t>());
  if (dropped["spikes"].get<std::size_t>() > 0)
    std::printf("warning: %zu IMU spikes dropped (%zu samples beyond imu_spike_acc / imu_spike_gyr of the recent ones, "
                "back within imu_spike_max_ms)\n",
                s["imu_spikes"].get<std::size_t>(), dropped["spikes"].get<std::size_t>());
  if (const auto& u = s["unpaired_images"]; u["cam0"].get<std::size_t>() + u["cam1"].get<std::size_t>() > 0)
    std::printf("warning: stereo images without a partner within 1 ms, not processed: %zu left (cam0), %zu right "
                "(cam1)\n",
                u["cam0"].get<std::size_t>(), u["cam1"].get<std::size_t>());
  if (s["frames_beyond_imu"].get<std::size_t>() > 0)
    std::printf("warning: %zu frame(s) at the end not processed: their time (stamp + td) is after the last IMU sample\n",
                s["frames_beyond_imu"].get<std::size_t>());
  std::printf("mean tracking %.2f ms, filter %.3f ms, optimization %.2f ms, marginalization %.2f ms per frame\n",
              s["mean_tracking_ms"].get<double>(), s["mean_filter_ms"].get<double>(),
              s["mean_optimization_ms"].get<double>(), s["mean_marginalization_ms"].get<double>());
  for (const auto& r : s["resets"])
    std::printf("reset at %.3f s (frame %zu): %s; %s\n", 1e-9 * (r["t_ns"].get<double>() - s["first_t_ns"].get<double>()),
                r["frame"].get<std::size_t>(), r["why"].get<std::string>().c_str(),
                r["resumed_t_ns"].get<TimeNs>() < 0 ? "not initialized again"
                : r["continued_by"] == "imu"        ? "went on from the last good state, propagated with the IMU"
                : r["continued_by"] == "extrapolated" ? "went on from the last good state, at constant velocity across the IMU gap"
                : r["continued_by"] == "held"       ? "went on from the last good state, held across the gap"
                                                    : "started a new trajectory");
  printAte(s);
  printLoops(s["loop_closure"], s["first_t_ns"].get<TimeNs>());
  std::printf("map: %zu static points, %zu dynamic points\n", s["map_static_points"].get<std::size_t>(),
              s["map_dynamic_points"].get<std::size_t>());
  if (const auto& c = s["classification"]; !c.is_null())
    std::printf("vs ground-truth masks: %.1f%% of observations on moving objects flagged dynamic, %.2f%% of static ones; "
                "%.2f%% of the static map on moving objects\n",
                100 * c["moving_detected_fraction"].get<double>(), 100 * c["static_flagged_fraction"].get<double>(),
                100 * c["static_map_fraction_on_moving"].get<double>());
  std::printf("wrote %s/trajectory.tum, trajectory.csv, state.csv, stats.json, resets.csv, map_static.ply, map_dynamic.ply, "
              "map_all.ply, run.json%s%s (idyvins report %s: the run as a page)\n",
              out.c_str(), s.contains("ate_rmse_m") ? ", groundtruth.tum" : "",
              s["loop_closure"].is_null() ? "" : ", trajectory_loop.tum, loops.csv, map_static_loop.ply", out.c_str());
}

pipeline::System makeSystem(const RunArgs& a, Config& config) {
  config = loadConfig(a.config);
  if (!a.mode.empty() && !parseMode(a.mode, config.mode))
    throw CLI::ValidationError("--mode", "expected " + modeNames() + ", got '" + a.mode + "'");
  if (a.solver_time_limit) config.estimator.time_limited = true;
  if (!a.save_map.empty() || !a.load_map.empty()) config.loop.enabled = true;  // the map is the loop closer's database
  if (a.localization_only && a.load_map.empty())
    throw CLI::ValidationError("--localization-only", "needs --load-map DIR (the map to localize in)");
  if (a.localization_only && !a.save_map.empty())
    throw CLI::ValidationError("--save-map", "--localization-only leaves the map as loaded: nothing to save");
  pipeline::RunOptions run;
  run.pipelined = a.threads == 2;
  run.feedback_delay = a.feedback_delay >= 0 ? a.feedback_delay : (run.pipelined ? 1 : 0);
  if (run.pipelined && run.feedback_delay != 1)
    throw CLI::ValidationError("--feedback-delay", "a pipelined run (--threads 2) has a feedback delay of 1 frame");
  return pipeline::System(config, run);
}

/// The run's stats.json: written while the run goes (one line per frame) under a temporary name.
struct StatsFile {
  explicit StatsFile(const std::string& dir) : path(dir + "/stats.json"), part(path + ".part"), file(part), recorder(file) {
    if (!file) throw InputError(part, "cannot write file");
  }
  void finish(const nlohmann::json& summary) {
    recorder.finish(summary);
    file.close();
    if (!file) throw InputError(part, "write failed");
    std::error_code ec;
    std::filesystem::rename(part, path, ec);
    if (ec) throw InputError(path, "cannot rename " + part + ": " + ec.message());
  }
  std::string path, part;
  std::ofstream file;
  pipeline::StatsRecorder recorder;
};

/// OUT/run.json (how the run was made, for `idyvins report`) and OUT/groundtruth.tum (the
/// reference poses from 1 s before the first to 1 s after the last frame, when there are any).
void writeRunRecord(const std::string& dir, const RunArgs& a, const Config& config,
                    const std::vector<StampedPose>& gt, const pipeline::Result& result) {
  const auto text = [](const std::string& path) {
    std::ifstream in(path);
    if (!in) throw InputError(path, "cannot read file");
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  nlohmann::json files = nlohmann::json::array();
  files.push_back({{"path", config.path}, {"text", text(config.path)}});
  for (const std::string& cam : config.cam_paths) files.push_back({{"path", cam}, {"text", text(cam)}});
  std::error_code ec;
  const nlohmann::json record = {{"command", a.command_line},
                                 {"cwd", std::filesystem::current_path(ec).string()},
                                 {"dataset", a.dataset},
                                 {"config_files", files},
                                 {"build", {{"commit", buildCommit()}}}};
  std::ofstream out(dir + "/run.json");
  out << record.dump(1) << "\n";
  if (!out) throw InputError(dir + "/run.json", "write failed");
  if (gt.empty()) return;  // the span of the frames processed (a run stopped early may have no pose yet)
  const TimeNs from = result.summary.first_t_ns - 1'000'000'000, to = result.summary.last_t_ns + 1'000'000'000;
  std::vector<StampedPose> span;
  for (const StampedPose& p : gt)
    if (p.t_ns >= from && p.t_ns <= to) span.push_back(p);
  if (!span.empty()) io::writeTum(dir + "/groundtruth.tum", span);
}

/// Says how a run stopped by `sig` (SIGINT, SIGTERM) after `frames` of `total` frames ended and
/// returns its exit code, 128 + sig. Stopped before the first frame, it wrote nothing: OUT is
/// as it was (the staging folder goes with the run).
int reportStop(int sig, std::size_t frames, std::size_t total, const std::string& out) {
  const char* name = sig == SIGINT ? "SIGINT" : "SIGTERM";
  if (frames == 0)
    std::fprintf(stderr, "stopped by %s before the first frame: nothing written, %s as it was\n", name, out.c_str());
  else
    std::fprintf(stderr, "stopped by %s after %zu of %zu frames: %s holds the partial result (summary \"partial\": true)\n",
                 name, frames, total, out.c_str());
  return 128 + sig;
}

/// kOk, or kNoResult with the line saying why when the poses cover too few of the frames.
int resultCode(const pipeline::Result& result, const std::string& out) {
  const std::string why = pipeline::whyNoTrajectory(result);
  if (why.empty()) return kOk;
  std::fprintf(stderr, "error: no trajectory: %s (exit %d; the files are in %s for inspection)\n", why.c_str(), kNoResult,
               out.c_str());
  return kNoResult;
}

/// The config's and the dataset's warnings, one line each on stderr.
void printWarnings(const Config& config, const Input& in) {
  for (const auto* list : {&config.warnings, &in.warnings})
    for (const std::string& w : *list) std::fprintf(stderr, "warning: %s\n", w.c_str());
}

int runRun(const RunArgs& a) {
  Config config;
  pipeline::System system = makeSystem(a, config);
  if (!a.load_map.empty()) system.loadMap(map::loadMap(a.load_map), !a.localization_only, a.load_map);
  Input in = openInput(a.dataset, config, a.groundtruth_topic);
  printWarnings(config, in);
  // Refused before the run when it is not an earlier run to replace.
  io::OutputFolder folder(a.out, pipeline::runFolderOptions({a.dataset, a.config, a.load_map}, a.force));
  const std::size_t total = a.max_frames ? std::min(a.max_frames, in.source->frameCount()) : in.source->frameCount();
  const std::string dump = a.dump_observations.empty() ? "" : folder.extraFile(a.dump_observations);
  const std::string map_dir = a.save_map.empty() ? "" : folder.extraFolder(a.save_map);
  pipeline::ObservationRecorder observations(in.has_masks, /*keep_observations=*/!dump.empty());
  StatsFile stats(folder.path());
  ProgressObserver progress(system.mode(), total);
  if (in.has_masks || !dump.empty()) system.addObserver(observations);
  system.addObserver(stats.recorder);
  system.addObserver(progress);
  std::signal(SIGINT, onStopSignal);  // stop feeding, finish, write a result marked partial
  std::signal(SIGTERM, onStopSignal);
  const auto wall_start = std::chrono::steady_clock::now();
  const std::size_t frames = drive(*in.source, system, total);
  if (frames == 0 && g_stop_signal != 0) return reportStop(g_stop_signal, 0, total, a.out);  // OUT untouched
  if (frames == 0) throw InputError(a.dataset, "no stereo frames");
  const pipeline::Result result = system.finish();  // completes the frame still in flight
  progress.finish();
  const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();

  nlohmann::json summary = pipeline::summaryJson(result, system.mode(), wall_s);
  summary["threads"] = system.threads();
  summary["feedback_delay"] = system.runOptions().feedback_delay;
  summary["unpaired_images"] = {{"cam0", in.unpaired_cam0}, {"cam1", in.unpaired_cam1}};
  summary["build"] = {{"commit", buildCommit()}};
  summary["config_fnv1a64"] = configChecksum(config);
  const int sig = g_stop_signal;
  summary["partial"] = sig != 0;  // stopped by a signal: the frames before it only
  if (sig != 0) summary["stopped_by"] = sig == SIGINT ? "SIGINT" : "SIGTERM";
  if (in.has_masks) summary["classification"] = pipeline::toJson(observations.classify(result));
  if (!dump.empty()) observations.writeCsv(dump, result);
  pipeline::writeResultFiles(folder.path(), result);
  if (in.has_masks) {  // the static map's points on moving objects, for the report's ghost layer
    std::vector<io::LabelledPoint> ghosts;
    for (const auto& p : observations.staticMapOnMoving(result)) ghosts.push_back({p.p_w, 0});
    io::writePly(folder.path() + "/map_static_on_moving.ply", ghosts);
  }
  if (!map_dir.empty()) {
    map::SavedMap saved = system.loopCloser()->savedMap();
    saved.rig = pipeline::rigFingerprint(config);
    map::saveMap(map_dir, saved);
  }
  pipeline::addAte(summary, in.groundtruth, result);
  writeRunRecord(folder.path(), a, config, in.groundtruth, result);
  stats.finish(summary);
  for (const std::string& w : folder.publish()) std::fprintf(stderr, "warning: %s\n", w.c_str());
  summary["last_status"] = result.summary.last_status;
  printSummary(summary, a.out);
  return sig == 0 ? resultCode(result, a.out) : reportStop(sig, frames, total, a.out);
}

}  // namespace

std::string configChecksum(const Config& config) {
  std::uint64_t h = fnv1a64File(config.path);
  for (const std::string& cam : config.cam_paths) h = fnv1a64File(cam, h);
  return hex64(h);
}

namespace {

/// --out and --force.
void addOutputOptions(CLI::App* cmd, RunArgs& a) {
  cmd->add_option("-o,--out", a.out,
                  "output folder: new, empty, or an earlier run's (only its files, listed in its\n"
                  "idyvins_manifest.json, are replaced); anything else is refused before the run")
      ->required();
  cmd->add_flag("--force", a.force,
                "write into an --out holding files idyvins run did not write: they stay (one in the way of an\n"
                "output is moved aside to NAME.orig); also lets --dump-observations replace an existing file");
}

}  // namespace

void registerRun(CLI::App& app, int& exit_code, const std::string& command_line) {
  auto a = std::make_shared<RunArgs>();
  CLI::App* cmd = app.add_subcommand(
      "run",
      "Run stereo-inertial odometry on a EuRoC folder: front end (stereo KLT) and the\n"
      "sliding-window estimator. Writes OUT/trajectory.tum (TUM), OUT/trajectory.csv (EuRoC),\n"
      "OUT/state.csv (pose, velocity, biases; EuRoC ground-truth columns)\n"
      "OUT/stats.json (per-frame timing, feature counts, status, resets), OUT/resets.csv, and the maps as PLY;\n"
      "OUT/run.json (the command, its folder, the config files' text: what `idyvins report` shows) and,\n"
      "when the dataset has ground truth, OUT/groundtruth.tum (its poses over the run's time span);\n"
      "with the config's loop_closure: 1 also OUT/trajectory_loop.tum (every pose corrected by the final\n"
      "4-DoF pose graph), OUT/loops.csv (each loop closed) and OUT/map_static_loop.ply (the static\n"
      "landmarks of the loop closer's keyframes, moved with the corrected poses).\n"
      "Offline and deterministic: frames are processed in order as fast as possible and each\n"
      "solve stops on max_num_iterations or convergence, never on the clock, so the same input\n"
      "and config give the same outputs whatever the machine's load (timing fields aside).\n"
      "OUT is written whole (in OUT.partial-PID, swapped in when complete). SIGINT / SIGTERM:\n"
      "the frames so far are finished and written, marked partial in stats.json; exit 130 / 143.");
  cmd->add_option("-c,--config", a->config, "VINS-Fusion config")->required();
  cmd->add_option("-d,--dataset", a->dataset,
                  "EuRoC folder or ROS1 bag (topics from the config's imu_topic, image0_topic, image1_topic)")
      ->required();
  addOutputOptions(cmd, *a);
  cmd->add_option("--groundtruth-topic", a->groundtruth_topic,
                  "bag only: ground-truth topic (nav_msgs/Odometry, geometry_msgs/TransformStamped, PoseStamped or\n"
                  "PointStamped), e.g. /odometry (VIODE), /vicon/firefly_sbx/firefly_sbx or /leica/position (EuRoC);\n"
                  "overrides the config's groundtruth_topic");
  cmd->add_option("--mode", a->mode, "overrides the config's mode: " + modeNames());
  cmd->add_option("--save-map", a->save_map,
                  "write the keyframe database and pose graph to this folder (map.json, keyframes.bin,\n"
                  "loops.csv; docs/loop-closure.md); turns loop closure on");
  cmd->add_option("--load-map", a->load_map,
                  "start in a map saved by --save-map: relocalize against it (the first match the next keyframes\n"
                  "confirm), then close loops against it; trajectory_loop.tum is in the map's frame (written once\n"
                  "relocalized). With --save-map the map is extended by this run; turns loop closure on");
  cmd->add_flag("--localization-only", a->localization_only,
                "with --load-map: localize in the map without adding this run's keyframes to it");
  cmd->add_option("--frames", a->max_frames, "stop after this many frames (0 = all)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--threads", a->threads,
                  "2 (default): pipelined, the front end of frame k+1 runs beside the back end of frame k (its\n"
                  "motion prior comes from the state of frame k-1 propagated with the IMU; deterministic, equal\n"
                  "to --threads 1 --feedback-delay 1); 1: front end then back end for each frame")
      ->check(CLI::Range(1, 2));
  cmd->add_option("--feedback-delay", a->feedback_delay,
                  "frames between the back end's state and the front end that uses it: 1 (what --threads 2\n"
                  "does; with --threads 1 it reproduces a pipelined run) or 0 (the default with --threads 1)")
      ->check(CLI::Range(0, 1));
  cmd->add_flag("--solver-time-limit", a->solver_time_limit,
               "cap each solve at the config's max_solver_time of wall clock, as VINS-Fusion does (live use;\n"
               "results then depend on the machine's load). Same as solver_time_limit: 1 in the config");
  cmd->add_option("--dump-observations", a->dump_observations,
                  "write one CSV row per tracked observation (front-end label, d_s, stereo-test chi2, ground-truth mask, final fate)");
  cmd->callback([a, &exit_code, &command_line] {
    a->command_line = command_line;
    exit_code = runRun(*a);
  });
}

}  // namespace idyvins::app
