// `idyvins run`: the whole system on a dataset: front end + estimator, trajectory and stats.

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "backend/estimator.h"
#include "commands.h"
#include "core/error.h"
#include "eval/trajectory_metrics.h"
#include "frontend/feature_tracker.h"
#include "io/config.h"
#include "io/data_source.h"
#include "io/trajectory_io.h"
#include "prefetch.h"
#include "progress.h"

namespace idyvins::app {
namespace {

struct RunArgs {
  std::string config, dataset, out, mode;
  std::size_t max_frames = 0;
};

std::unique_ptr<frontend::FeatureFilter> makeFilter(Mode mode, const Config& c) {
  switch (mode) {
    case Mode::kRansac: return std::make_unique<frontend::RansacFilter>(c.tracker.f_threshold);
    case Mode::kSeg: return std::make_unique<frontend::SegFilter>();
    default: return nullptr;
  }
}

int runRun(const RunArgs& a) {
  Config config = loadConfig(a.config);
  if (!a.mode.empty() && !parseMode(a.mode, config.dynamic.mode))
    throw CLI::ValidationError("--mode", "expected " + modeNames() + ", got '" + a.mode + "'");
  const Mode mode = config.dynamic.mode;
  if (mode == Mode::kIdy || mode == Mode::kIdyPre || mode == Mode::kIdyBa)
    throw InputError(a.config, std::string("mode '") + toString(mode) +
                                   "' is not implemented yet (the dynamic-landmark issue); use baseline, ransac or seg");
  if (!config.use_imu || config.num_cam != 2)
    throw InputError(a.config, "idyvins runs stereo + IMU configs only (imu: 1, num_of_cam: 2)");
  io::EurocDataset ds = io::readEurocDataset(a.dataset);
  const bool has_gt = ds.has_groundtruth;
  std::vector<StampedPose> gt;
  for (const auto& g : ds.groundtruth) gt.push_back({g.t_ns, g.p_w_b, g.q_w_b});
  io::EurocSource source(std::move(ds), config.image_width, config.image_height, mode == Mode::kSeg);
  std::error_code ec;
  std::filesystem::create_directories(a.out, ec);
  if (ec) throw InputError(a.out, "cannot create output folder: " + ec.message());

  frontend::FeatureTracker tracker(config);
  auto filter = makeFilter(mode, config);
  backend::Estimator estimator(config);
  const std::size_t total = a.max_frames ? std::min(a.max_frames, source.frameCount()) : source.frameCount();
  ProgressBar bar(std::string("run ") + toString(mode), total, "frames");
  std::vector<StampedPose> trajectory;
  nlohmann::json frames = nlohmann::json::array(), resets = nlohmann::json::array();
  std::size_t count = 0;
  TimeNs first_t = 0, last_t = 0, init_t = -1;
  double sum_track = 0, sum_opt = 0, sum_filter = 0;
  std::string last_status;
  const auto wall_start = std::chrono::steady_clock::now();
  PrefetchSource prefetch(source, 4);
  while (count < total) {
    auto m = prefetch.next();
    if (!m) break;
    if (const auto* imu = std::get_if<ImuSample>(&*m)) {
      estimator.addImu(*imu);
      continue;
    }
    const auto& frame = std::get<StereoFrame>(*m);
    if (count == 0) first_t = frame.t_ns;
    last_t = frame.t_ns;
    const frontend::FeatureFrame ff = tracker.track(frame, frontend::MotionPrior{}, filter.get(),
                                                    frame.left_mask.empty() ? nullptr : &frame.left_mask);
    const backend::FrameResult r = estimator.addFrame(ff);
    ++count;
    if (r.initialized) {
      trajectory.push_back({r.t_ns, r.state.p_w_b, r.state.q_w_b});
      if (init_t < 0) init_t = r.t_ns;
    }
    if (r.reset) resets.push_back({{"t_ns", r.t_ns}, {"frame", count - 1}, {"why", r.status}});
    if (r.reset) tracker.reset();
    sum_track += ff.tracking_ms;
    sum_filter += ff.filter_ms;
    sum_opt += r.optimization_ms;
    last_status = r.status;
    frames.push_back({{"t_ns", r.t_ns},
                      {"tracking_ms", ff.tracking_ms},
                      {"filter_ms", ff.filter_ms},
                      {"optimization_ms", r.optimization_ms},
                      {"features", ff.features.size()},
                      {"removed", ff.removed.size()},
                      {"landmarks", r.landmarks},
                      {"keyframe", r.keyframe},
                      {"initialized", r.initialized},
                      {"status", r.status}});
    bar.update(count);
  }
  bar.finish();
  const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  if (count == 0) throw InputError(a.dataset, "no stereo frames");
  const std::string out = a.out;
  io::writeTum(out + "/trajectory.tum", trajectory);
  io::writeEurocCsv(out + "/trajectory.csv", trajectory);
  const double seq_s = toSeconds(last_t - first_t);
  nlohmann::json summary = {{"frames", count},
                            {"mode", toString(mode)},
                            {"sequence_s", seq_s},
                            {"wall_s", wall_s},
                            {"realtime_factor", seq_s / wall_s},
                            {"mean_tracking_ms", sum_track / count},
                            {"mean_filter_ms", sum_filter / count},
                            {"mean_optimization_ms", sum_opt / count},
                            {"poses", trajectory.size()},
                            {"initialized_at_s", init_t >= 0 ? toSeconds(init_t - first_t) : -1.0},
                            {"resets", resets}};
  double ate = -1, path = 0;
  if (has_gt && trajectory.size() > 2) {
    try {
      const auto r = eval::computeAte(gt, trajectory, eval::AlignMode::kSe3, 10'000'000);
      ate = r.stats.rmse;
      std::vector<StampedPose> gt_pairs;
      for (const auto& [i, j] : r.pairs) gt_pairs.push_back(gt[i]);
      path = eval::pathLength(gt_pairs);
      summary["ate_rmse_m"] = ate;
      summary["path_length_m"] = path;
    } catch (const std::exception&) {
    }
  }
  std::ofstream(out + "/stats.json") << nlohmann::json{{"summary", summary}, {"frames", frames}}.dump(1) << "\n";
  std::printf("%zu frames (%.1f s) in %.1f s (%.1fx real time), mode %s\n", count, seq_s, wall_s, seq_s / wall_s,
              toString(mode));
  if (init_t >= 0)
    std::printf("initialized at %.2f s; %zu poses; %zu resets\n", toSeconds(init_t - first_t), trajectory.size(),
                resets.size());
  else
    std::printf("not initialized: %s\n", last_status.c_str());
  std::printf("mean tracking %.2f ms, filter %.3f ms, optimization %.2f ms per frame\n", sum_track / count,
              sum_filter / count, sum_opt / count);
  if (ate >= 0) std::printf("ATE RMSE (SE3) %.4f m over %.1f m (%.2f%%)\n", ate, path, 100 * ate / path);
  std::printf("wrote %s/trajectory.tum, trajectory.csv, stats.json\n", out.c_str());
  return kOk;
}

}  // namespace

void registerRun(CLI::App& app, int& exit_code) {
  auto a = std::make_shared<RunArgs>();
  CLI::App* cmd = app.add_subcommand(
      "run",
      "Run stereo-inertial odometry on a EuRoC folder: front end (stereo KLT) and the\n"
      "sliding-window estimator. Writes OUT/trajectory.tum (TUM), OUT/trajectory.csv (EuRoC)\n"
      "and OUT/stats.json (per-frame timing, feature counts, status, resets). Offline and\n"
      "deterministic: frames are processed as fast as possible, in order.");
  cmd->add_option("-c,--config", a->config, "VINS-Fusion config")->required();
  cmd->add_option("-d,--dataset", a->dataset, "EuRoC folder")->required();
  cmd->add_option("-o,--out", a->out, "output folder")->required();
  cmd->add_option("--mode", a->mode, "overrides the config's mode: " + modeNames());
  cmd->add_option("--frames", a->max_frames, "stop after this many frames (0 = all)");
  cmd->callback([a, &exit_code] { exit_code = runRun(*a); });
}

}  // namespace idyvins::app
