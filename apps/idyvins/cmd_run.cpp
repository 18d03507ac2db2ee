// `idyvins run`: the whole system (pipeline::System) on a dataset; writes the trajectory,
// the maps and stats. Parse arguments, open the source, drive the pipeline, write outputs.

#include <algorithm>
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <memory>

#include "commands.h"
#include "config/config.h"
#include "core/error.h"
#include "map/map_io.h"
#include "pipeline/outputs.h"
#include "pipeline/run.h"
#include "pipeline/run_outputs.h"
#include "pipeline/system.h"
#include "progress.h"
#include "run_print.h"

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

/// The run rules applied to `config` (pipeline::applyRunRequest); the system's run options.
pipeline::RunOptions applyArgs(const RunArgs& a, Config& config) {
  pipeline::RunRequest request;
  request.mode = a.mode;
  request.threads = a.threads;
  request.feedback_delay = a.feedback_delay;
  request.solver_time_limit = a.solver_time_limit;
  request.load_map = !a.load_map.empty();
  request.save_map = !a.save_map.empty();
  request.localization_only = a.localization_only;
  try {
    return pipeline::applyRunRequest(request, config);
  } catch (const pipeline::OptionError& e) {  // a usage error (exit 2), named as typed
    const auto flag = [](std::string name) {
      std::replace(name.begin(), name.end(), '_', '-');
      return "--" + name;
    };
    throw CLI::ValidationError(flag(e.option()), e.text(flag));
  }
}

int runRun(const RunArgs& a) {
  Config config = loadConfig(a.config);
  pipeline::System system(config, applyArgs(a, config));
  if (!a.load_map.empty()) system.loadMap(map::loadMap(a.load_map), !a.localization_only, a.load_map);
  io::OpenedDataset in = pipeline::openDataset(a.dataset, config, a.groundtruth_topic);
  printRunWarnings(config, in);
  pipeline::RunOutputsOptions files;  // the folder is refused now, before the run, when it is not an earlier run's
  files.inputs = {a.dataset, a.config, a.load_map};
  files.force = a.force;
  files.masks = in.has_masks;
  files.dump_observations = a.dump_observations;
  files.save_map = a.save_map;
  pipeline::RunOutputs outputs(a.out, files);
  const std::size_t total = a.max_frames ? std::min(a.max_frames, in.source->frameCount()) : in.source->frameCount();
  ProgressObserver progress(system.mode(), total);
  outputs.attach(system);
  system.addObserver(progress);
  std::signal(SIGINT, onStopSignal);  // stop feeding, finish, write a result marked partial
  std::signal(SIGTERM, onStopSignal);
  const auto wall_start = std::chrono::steady_clock::now();
  const std::size_t frames = pipeline::feed(*in.source, system, total, &g_stop_signal);
  if (frames == 0 && g_stop_signal != 0) return reportRunStop(g_stop_signal, 0, total, a.out);  // OUT untouched
  if (frames == 0) throw InputError(a.dataset, "no stereo frames");
  const pipeline::Result result = system.finish();  // completes the frame still in flight
  progress.finish();
  pipeline::RunEnd end;
  end.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  const int sig = g_stop_signal;
  end.extras = {{"unpaired_images", {{"cam0", in.unpaired_cam0}, {"cam1", in.unpaired_cam1}}},
                {"partial", sig != 0}};  // stopped by a signal: the frames before it only
  if (sig != 0) end.extras["stopped_by"] = sig == SIGINT ? "SIGINT" : "SIGTERM";
  end.groundtruth = in.groundtruth;
  const pipeline::RunRecord record{a.command_line, a.dataset};
  end.record = &record;
  nlohmann::json summary = outputs.write(system, result, end);
  for (const std::string& w : outputs.publish()) std::fprintf(stderr, "warning: %s\n", w.c_str());
  summary["last_status"] = result.summary.last_status;
  printRunSummary(summary, a.out);
  return sig == 0 ? runResultCode(result, a.out) : reportRunStop(sig, frames, total, a.out);
}

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
  cmd->add_option(
         "-d,--dataset", a->dataset,
         "EuRoC folder, ROS1 bag or ROS 2 bag (topics from the config's imu_topic, image0_topic, image1_topic)")
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
  cmd->add_option("--frames", a->max_frames, "stop after this many frames (0 = all)")->check(CLI::NonNegativeNumber);
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
                  "write one CSV row per tracked observation (front-end label, d_s, stereo-test chi2, ground-truth "
                  "mask, final fate)");
  cmd->callback([a, &exit_code, &command_line] {
    a->command_line = command_line;
    exit_code = runRun(*a);
  });
}

}  // namespace idyvins::app
