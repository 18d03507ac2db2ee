// `idyvins run`: the whole system on a dataset: front end + estimator, trajectory and stats.

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <algorithm>
#include <optional>
#include <nlohmann/json.hpp>
#include <unordered_map>
#include <unordered_set>

#include "backend/estimator.h"
#include "dynamic/dynamic.h"
#include "io/ply.h"
#include "commands.h"
#include "core/error.h"
#include "eval/dynamic_metrics.h"
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
  std::string config, dataset, out, mode, dump_observations;
  std::size_t max_frames = 0;
};

std::unique_ptr<frontend::FeatureFilter> makeFilter(Mode mode, const Config& c) {
  switch (mode) {
    case Mode::kRansac: return std::make_unique<frontend::RansacFilter>(c.tracker.f_threshold);
    case Mode::kSeg: return std::make_unique<frontend::SegFilter>();
    case Mode::kIdy:
    case Mode::kIdyPre:
    case Mode::kIdyBa: {
      dynamic::IdyOptions o;
      o.lambda_dy = c.dynamic.lambda_dy;
      o.lambda_dy_c = c.dynamic.lambda_dy_c;
      o.eliminate = mode != Mode::kIdyBa;
      o.stereo = c.dynamic.stereo;
      o.stereo.enabled = o.stereo.enabled && c.num_cam == 2 && c.T_b_c.size() >= 2;
      if (o.stereo.enabled) o.T_r_l = c.T_b_c[1].inverse() * c.T_b_c[0];
      return std::make_unique<dynamic::IdyFilter>(o);
    }
    default: return nullptr;
  }
}

/// d_s histogram: 1 px² bins from 0 to 20, then one overflow bin.
std::vector<int> histogram(const std::vector<double>& d) {
  std::vector<int> h(21, 0);
  for (double v : d) ++h[std::min(20, static_cast<int>(v))];
  return h;
}

/// --dump-observations: one CSV row per tracked observation with the front end's
/// label and d_s, and the landmark's final fate in the estimator.
template <typename Records>
void writeObservations(const std::string& path, const Records& observations, const backend::Estimator& estimator,
                       const std::unordered_set<std::uint64_t>& outlier_ids, bool has_masks) {
  std::unordered_set<std::uint64_t> confirmed, in_static;
  for (const auto& p : estimator.dynamicMap()) confirmed.insert(p.id);
  for (const auto& p : estimator.staticMap()) in_static.insert(p.id);
  std::ofstream f(path);
  if (!f) throw InputError(path, "cannot write file");
  f << "t_ns,id,u,v,track_length,frontend_label,d_s_px2,credibility,stereo_chi2,on_moving,confirmed_dynamic,in_static_map,"
       "outlier_removed\n";
  static const char* kLabels[] = {"static", "candidate", "eliminated"};
  for (const auto& o : observations)
    f << o.t_ns << ',' << o.id << ',' << o.u << ',' << o.v << ',' << o.track_length << ','
      << kLabels[static_cast<int>(o.label)] << ',' << o.d_s << ',' << o.credibility << ',' << o.stereo_chi2 << ','
      << (has_masks ? (o.on_moving ? "1" : "0") : "") << ',' << confirmed.count(o.id) << ',' << in_static.count(o.id)
      << ',' << outlier_ids.count(o.id) << '\n';
  if (!f) throw InputError(path, "write failed");
}

int runRun(const RunArgs& a) {
  Config config = loadConfig(a.config);
  if (!a.mode.empty() && !parseMode(a.mode, config.dynamic.mode))
    throw CLI::ValidationError("--mode", "expected " + modeNames() + ", got '" + a.mode + "'");
  const Mode mode = config.dynamic.mode;
  const bool idy = mode == Mode::kIdy || mode == Mode::kIdyPre || mode == Mode::kIdyBa;
  if (!config.use_imu || config.num_cam != 2)
    throw InputError(a.config, "idyvins runs stereo + IMU configs only (imu: 1, num_of_cam: 2)");
  io::EurocDataset ds = io::readEurocDataset(a.dataset);
  const bool has_gt = ds.has_groundtruth;
  std::vector<StampedPose> gt;
  for (const auto& g : ds.groundtruth) gt.push_back({g.t_ns, g.p_w_b, g.q_w_b});
  const bool has_masks = !ds.cam0.empty() &&
                         std::filesystem::is_directory(std::filesystem::path(ds.root) / "cam0" / "mask");
  if (mode == Mode::kSeg && !has_masks) throw InputError(ds.root, "mode seg needs mav0/cam0/mask/ (ground-truth masks)");
  io::EurocSource source(std::move(ds), config.image_width, config.image_height, has_masks);
  std::error_code ec;
  std::filesystem::create_directories(a.out, ec);
  if (ec) throw InputError(a.out, "cannot create output folder: " + ec.message());

  frontend::TrackerParams tracker_params;
  // IDY elimination (DESIGN §4.3, session-3 refinement): eliminated features never reach
  // the estimator again, but the tracker keeps following them so that no new corner is
  // seeded on the same moving object.
  tracker_params.keep_following_eliminated = mode == Mode::kIdy || mode == Mode::kIdyPre;
  // Session-7 extension: new corners lost in their second frame, judged against the prior.
  tracker_params.judge_lost_new_tracks = tracker_params.keep_following_eliminated && config.dynamic.lost_track_test;
  frontend::FeatureTracker tracker(config, tracker_params);
  auto filter = makeFilter(mode, config);
  backend::EstimatorOptions est_options;
  est_options.candidate_weights = est_options.post_process = mode == Mode::kIdy || mode == Mode::kIdyBa;
  est_options.confirm_outliers = est_options.post_process && config.dynamic.confirm_outliers;
  backend::Estimator estimator(config, est_options);
  auto* idy_filter = dynamic_cast<dynamic::IdyFilter*>(filter.get());
  std::vector<io::LabelledPoint> eliminated_points;
  const std::size_t total = a.max_frames ? std::min(a.max_frames, source.frameCount()) : source.frameCount();
  ProgressBar bar(std::string("run ") + toString(mode), total, "frames");
  std::vector<StampedPose> trajectory;
  std::vector<GroundTruthState> states;  // the full estimated state, written as state.csv
  nlohmann::json frames = nlohmann::json::array(), resets = nlohmann::json::array();
  std::size_t count = 0, frames_without_prior = 0, lost_tested = 0, lost_moving = 0;
  std::unordered_set<std::uint64_t> lost_moving_ids;  // their only observation is relabelled at the end
  std::optional<std::pair<Eigen::Isometry3d, Eigen::Isometry3d>> prev_T_w_c;  // previous frame's cameras
  struct ObsRecord {
    std::uint64_t id;
    bool on_moving;
    TimeNs t_ns;
    float u, v, d_s, credibility, stereo_chi2;
    frontend::FeatureLabel label;
    int track_length;
  };
  std::vector<ObsRecord> observations;
  std::unordered_set<std::uint64_t> outlier_ids;  // landmarks the outlier test removed at least once
  TimeNs first_t = 0, last_t = 0, init_t = -1;
  double sum_track = 0, sum_opt = 0, sum_filter = 0, sum_marg = 0;
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
    frontend::MotionPrior prior;
    const backend::LatestState latest = estimator.latest();
    if (idy && latest.valid)
      prior = dynamic::motionPrior(latest.state, latest.t_ns, frame.t_ns, estimator.imuHistory(), config.imu,
                                   config.T_b_c[0]);
    const frontend::FeatureFrame ff = tracker.track(frame, prior, filter.get(),
                                                    mode == Mode::kSeg ? &frame.left_mask : nullptr);
    // Evaluation against the ground-truth masks (simulated datasets): every tracked
    // observation, and whether the front end eliminated it.
    if (has_masks || !a.dump_observations.empty()) {
      auto on_moving = [&](const frontend::Feature& f) {
        if (!has_masks) return false;
        const int u = static_cast<int>(std::lround(f.uv.x())), v = static_cast<int>(std::lround(f.uv.y()));
        return frame.left_mask.at<std::uint8_t>(std::clamp(v, 0, frame.left_mask.rows - 1),
                                                std::clamp(u, 0, frame.left_mask.cols - 1)) != 0;
      };
      const float cred = idy_filter ? static_cast<float>(idy_filter->lastStats().credibility) : 0.f;
      auto record = [&](const frontend::Feature& f) {
        observations.push_back({f.id, on_moving(f), frame.t_ns, static_cast<float>(f.uv.x()),
                                static_cast<float>(f.uv.y()), static_cast<float>(f.score), cred,
                                static_cast<float>(f.stereo_chi2), f.label,
                                f.track_length});
      };
      for (const auto& f : ff.features) record(f);
      for (const auto& f : ff.removed) record(f);  // label kEliminated
    }
    lost_tested += ff.lost_tested;
    lost_moving += ff.lost_moving.size();
    for (const auto& f : ff.lost_moving) {
      lost_moving_ids.insert(f.id);
      if (!prev_T_w_c) continue;  // dynamic map: triangulated in the frame it was seen in
      const auto& [T_w_c0, T_w_c1] = *prev_T_w_c;
      const Eigen::Vector3d p_w = backend::triangulateTwoViews(T_w_c0, f.xy, T_w_c1, f.xy_right);
      const double z = (T_w_c0.inverse() * p_w).z();
      if (z > 0.1 && z < 80.0) eliminated_points.push_back({p_w, 1});
    }
    const backend::FrameResult r = estimator.addFrame(ff);
    outlier_ids.insert(r.outlier_ids.begin(), r.outlier_ids.end());
    prev_T_w_c.reset();
    if (idy && r.initialized) {  // eliminated features with a stereo match go to the dynamic map
      Eigen::Isometry3d T_w_b = Eigen::Isometry3d::Identity();
      T_w_b.linear() = r.state.q_w_b.toRotationMatrix();
      T_w_b.translation() = r.state.p_w_b;
      const Eigen::Isometry3d T_w_c0 = backend::cameraPose(T_w_b, estimator.rig().T_b_c0);
      const Eigen::Isometry3d T_w_c1 = backend::cameraPose(T_w_b, estimator.rig().T_b_c1);
      prev_T_w_c.emplace(T_w_c0, T_w_c1);
      for (const auto& f : ff.removed) {
        if (!f.has_right) continue;
        const Eigen::Vector3d p_w = backend::triangulateTwoViews(T_w_c0, f.xy, T_w_c1, f.xy_right);
        const double z = (T_w_c0.inverse() * p_w).z();
        if (z > 0.1 && z < 80.0) eliminated_points.push_back({p_w, 1});
      }
    }
    ++count;
    if (r.initialized) {
      trajectory.push_back({r.t_ns, r.state.p_w_b, r.state.q_w_b});
      states.push_back({r.t_ns, r.state.p_w_b, r.state.q_w_b, r.state.v_w, r.state.bg, r.state.ba});
      if (init_t < 0) init_t = r.t_ns;
    }
    if (r.reset) resets.push_back({{"t_ns", r.t_ns}, {"frame", count - 1}, {"why", r.status}});
    if (r.reset) tracker.reset();
    sum_track += ff.tracking_ms;
    sum_filter += ff.filter_ms;
    sum_opt += r.optimization_ms;
    sum_marg += r.marginalization_ms;
    last_status = r.status;
    nlohmann::json dyn = nullptr;
    if (idy_filter) {
      const auto& st = idy_filter->lastStats();
      dyn = {{"prior", st.prior_valid},   {"credibility", st.credibility}, {"tracked", st.tracked},
             {"eliminated", st.eliminated}, {"candidates", st.candidates},  {"cv_before", st.cv_before},
             {"cv_after", st.cv_after},   {"stop_rule", st.stop_rule},     {"d_s_hist", histogram(st.d_s)}, {"d_s_hist_kept", histogram(st.d_s_kept)},
             {"candidates_in_window", r.candidates}, {"confirmed_dynamic", r.confirmed_dynamic},
             {"outliers_confirmed_dynamic", r.outliers_confirmed},
             {"stereo_tested", st.stereo_tested}, {"stereo_eliminated", st.stereo_eliminated},
             {"lost_tested", ff.lost_tested}, {"lost_moving", ff.lost_moving.size()},
             {"cleared", r.cleared}};
      if (!st.prior_valid) ++frames_without_prior;
    }
    frames.push_back({{"t_ns", r.t_ns},
                      {"dynamic", dyn},
                      {"tracking_ms", ff.tracking_ms},
                      {"filter_ms", ff.filter_ms},
                      {"optimization_ms", r.optimization_ms},
                      {"marginalization_ms", r.marginalization_ms},
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
  estimator.flushMap();
  std::vector<io::LabelledPoint> static_pts, dynamic_pts = eliminated_points;
  for (const auto& p : estimator.staticMap()) static_pts.push_back({p.p_w, 0});
  for (const auto& p : estimator.dynamicMap()) dynamic_pts.push_back({p.p_w, 2});
  nlohmann::json classification = nullptr;
  for (auto& o : observations)  // a lost new corner judged moving: its one observation
    if (lost_moving_ids.count(o.id)) o.label = frontend::FeatureLabel::kEliminated;
  if (has_masks) {
    std::vector<eval::MaskedObservation> masked;
    masked.reserve(observations.size());
    for (const auto& o : observations) masked.push_back({o.id, o.on_moving, o.label == frontend::FeatureLabel::kEliminated});
    std::unordered_set<std::uint64_t> confirmed;
    for (const auto& p : estimator.dynamicMap()) confirmed.insert(p.id);
    std::vector<std::uint64_t> static_ids;
    for (const auto& p : estimator.staticMap()) static_ids.push_back(p.id);
    const eval::DynamicClassification c = eval::classifyDynamic(masked, confirmed, static_ids);
    classification = {{"observations_on_moving", c.observations_on_moving},
                      {"observations_static", c.observations_static},
                      {"moving_detected_fraction", c.recall},
                      {"moving_detected_fraction_tracked", c.recall_tracked},
                      {"static_flagged_fraction", c.static_flagged},
                      {"precision", c.precision},
                      {"recall", c.recall},
                      {"f1", c.f1},
                      {"static_map_points_on_moving", c.static_map_on_moving},
                      {"static_map_fraction_on_moving", c.static_map_fraction_on_moving},
                      {"static_map_points_ever_on_moving", c.static_map_ever_on_moving},
                      {"static_map_fraction_ever_on_moving", c.static_map_fraction_ever_on_moving}};
  }
  if (!a.dump_observations.empty()) writeObservations(a.dump_observations, observations, estimator, outlier_ids, has_masks);
  std::vector<io::LabelledPoint> all = static_pts;
  all.insert(all.end(), dynamic_pts.begin(), dynamic_pts.end());
  io::writePly(out + "/map_static.ply", static_pts);
  io::writePly(out + "/map_dynamic.ply", dynamic_pts);
  io::writePly(out + "/map_all.ply", all);
  io::writeTum(out + "/trajectory.tum", trajectory);
  io::writeEurocCsv(out + "/trajectory.csv", trajectory);
  io::writeStateCsv(out + "/state.csv", states);
  const double seq_s = toSeconds(last_t - first_t);
  nlohmann::json summary = {{"frames", count},
                            {"mode", toString(mode)},
                            {"sequence_s", seq_s},
                            {"wall_s", wall_s},
                            {"realtime_factor", seq_s / wall_s},
                            {"mean_tracking_ms", sum_track / count},
                            {"mean_filter_ms", sum_filter / count},
                            {"mean_optimization_ms", sum_opt / count},
                            {"mean_marginalization_ms", sum_marg / count},
                            {"poses", trajectory.size()},
                            {"initialized_at_s", init_t >= 0 ? toSeconds(init_t - first_t) : -1.0},
                            {"frames_without_prior", frames_without_prior},
                            {"lost_new_corners_tested", lost_tested},
                            {"lost_new_corners_moving", lost_moving},
                            {"map_static_points", static_pts.size()},
                            {"map_dynamic_points", dynamic_pts.size()},
                            {"classification", classification},
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
  std::printf("mean tracking %.2f ms, filter %.3f ms, optimization %.2f ms, marginalization %.2f ms per frame\n",
              sum_track / count, sum_filter / count, sum_opt / count, sum_marg / count);
  if (ate >= 0) std::printf("ATE RMSE (SE3) %.4f m over %.1f m (%.2f%%)\n", ate, path, 100 * ate / path);
  std::printf("map: %zu static points, %zu dynamic points\n", static_pts.size(), dynamic_pts.size());
  if (has_masks)
    std::printf("vs ground-truth masks: %.1f%% of observations on moving objects flagged dynamic, %.2f%% of static ones; "
                "%.2f%% of the static map on moving objects\n",
                100 * classification["moving_detected_fraction"].get<double>(),
                100 * classification["static_flagged_fraction"].get<double>(),
                100 * classification["static_map_fraction_on_moving"].get<double>());
  std::printf("wrote %s/trajectory.tum, trajectory.csv, state.csv, stats.json, map_static.ply, map_dynamic.ply, map_all.ply\n",
              out.c_str());
  return kOk;
}

}  // namespace

void registerRun(CLI::App& app, int& exit_code) {
  auto a = std::make_shared<RunArgs>();
  CLI::App* cmd = app.add_subcommand(
      "run",
      "Run stereo-inertial odometry on a EuRoC folder: front end (stereo KLT) and the\n"
      "sliding-window estimator. Writes OUT/trajectory.tum (TUM), OUT/trajectory.csv (EuRoC),\n"
      "OUT/state.csv (pose, velocity, biases; EuRoC ground-truth columns)\n"
      "and OUT/stats.json (per-frame timing, feature counts, status, resets). Offline and\n"
      "deterministic up to the solver's wall-clock limit (max_solver_time): frames are\n"
      "processed as fast as possible, in order.");
  cmd->add_option("-c,--config", a->config, "VINS-Fusion config")->required();
  cmd->add_option("-d,--dataset", a->dataset, "EuRoC folder")->required();
  cmd->add_option("-o,--out", a->out, "output folder")->required();
  cmd->add_option("--mode", a->mode, "overrides the config's mode: " + modeNames());
  cmd->add_option("--frames", a->max_frames, "stop after this many frames (0 = all)");
  cmd->add_option("--dump-observations", a->dump_observations,
                  "write one CSV row per tracked observation (front-end label, d_s, stereo-test chi2, ground-truth mask, final fate)");
  cmd->callback([a, &exit_code] { exit_code = runRun(*a); });
}

}  // namespace idyvins::app
