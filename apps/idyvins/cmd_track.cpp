// `idyvins track`: the front end alone on a dataset (debugging, timing, figures).

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "commands.h"
#include "config/config.h"
#include "config/modes.h"
#include "core/error.h"
#include "eval/image_stats.h"
#include "frontend/feature_tracker.h"
#include "frontend/track_quality.h"
#include "io/data_source.h"
#include "pipeline/front_end.h"
#include "pipeline/run.h"
#include "progress.h"

namespace idyvins::app {
namespace {

struct TrackArgs {
  std::string config, dataset, mode = "baseline", save_tracks, json;
  std::size_t max_frames = 0;
  bool image_stats = false;
};

/// Prints the tracking figures and returns them as JSON.
nlohmann::json printTrackSummary(const std::string& mode, std::size_t frames, std::size_t features, std::size_t stereo,
                                 std::size_t removed, double ms, double filter_ms,
                                 const frontend::TrackQualitySummary& q) {
  std::printf(
      "%zu frames, mode %s: %.1f features/frame (%.0f%% with a stereo match), %.2f removed/frame, "
      "tracking %.2f ms/frame, filter %.3f ms/frame\n",
      frames, mode.c_str(), static_cast<double>(features) / frames, 100.0 * stereo / std::max<std::size_t>(features, 1),
      static_cast<double>(removed) / frames, ms / frames, filter_ms / frames);
  if (q.with_right)
    std::printf("right matches: distance to the epipolar line median %.2f px, p99 %.2f px (calibrated extrinsics)\n",
                q.epipolar_median_px, q.epipolar_p99_px);
  std::printf("tracks: %zu, median length %.0f frames\n", q.tracks, q.track_length_median);
  return {{"frames", frames},
          {"features_per_frame", static_cast<double>(features) / frames},
          {"right_fraction", q.right_fraction},
          {"epipolar_median_px", q.epipolar_median_px},
          {"epipolar_p99_px", q.epipolar_p99_px},
          {"tracks", q.tracks},
          {"track_length_median", q.track_length_median},
          {"tracking_ms", ms / frames}};
}

/// Prints the left images' statistics (--image-stats) and returns them as JSON.
nlohmann::json printImageFigures(const eval::SequenceFigures& s, double min_dist) {
  std::printf(
      "images (left): brightness mean %.1f, spread (std) %.1f, frame-to-frame variation %.1f %%; "
      "gradient median %.2f, p90 %.2f gray/px, flat (< 2 gray/px) %.1f %%; %zu Shi-Tomasi corners "
      "(quality 0.01, %g px apart)\n",
      s.mean.mean, s.mean.stddev, 100 * s.frame_mean_variation, s.mean.gradient_median, s.mean.gradient_p90,
      100 * s.mean.flat_fraction, s.mean.corners, min_dist);
  std::printf("vignetting (ring mean / centre, r = 0-0.2 ... 0.8-1 of the half diagonal):");
  for (double v : s.vignetting) std::printf(" %.3f", v);
  std::printf("; right / left brightness %.3f\n", s.right_left_ratio);
  return {{"brightness_mean", s.mean.mean},
          {"brightness_std", s.mean.stddev},
          {"frame_mean_variation", s.frame_mean_variation},
          {"gradient_median", s.mean.gradient_median},
          {"gradient_p90", s.mean.gradient_p90},
          {"flat_fraction", s.mean.flat_fraction},
          {"corners", s.mean.corners},
          {"vignetting", s.vignetting},
          {"right_left_ratio", s.right_left_ratio}};
}

int runTrack(const TrackArgs& a) {
  Config config = loadConfig(a.config);
  Mode mode;
  if (!parseMode(a.mode, mode) || traitsOf(mode).filter == FilterKind::kIdy)
    throw CLI::ValidationError("--mode", "expected baseline|ransac|seg for the front end alone, got '" + a.mode + "'");
  config.mode = mode;
  const io::OpenedDataset in =
      pipeline::openDataset(a.dataset, config, "", traitsOf(mode).needs_masks);  // a folder or a bag
  io::DataSource& source = *in.source;
  if (!a.save_tracks.empty()) {
    std::error_code ec;
    std::filesystem::create_directories(a.save_tracks, ec);
    if (ec) throw InputError(a.save_tracks, "cannot create folder: " + ec.message());
  }
  const bool swap = config.cam0_right;  // cam0 is the right camera: the system tracks on cam1
  config = leftFirst(config);
  pipeline::FrontEnd front_end(config);  // the front end exactly as `run` uses it
  const std::size_t total = a.max_frames ? std::min(a.max_frames, source.frameCount()) : source.frameCount();
  ProgressBar bar("track", total, "frames");
  std::size_t frames = 0, features = 0, stereo = 0, removed = 0;
  frontend::TrackQuality quality(config.rig());
  eval::SequenceStatistics images(config.tracker.min_dist);
  double ms = 0, filter_ms = 0;
  while (frames < total) {
    auto m = source.next();
    if (!m) break;
    const auto* given = std::get_if<StereoFrame>(&*m);
    if (!given) continue;
    const StereoFrame left_first = swap ? pipeline::leftFirst(*given) : StereoFrame{};
    const StereoFrame* f = swap ? &left_first : given;
    const frontend::FeatureFrame out = front_end.track(*f, frontend::MotionPrior{});
    ++frames;
    features += out.features.size();
    for (const auto& ft : out.features) stereo += ft.has_right;
    quality.add(out);
    if (a.image_stats) images.add(f->left, f->right);
    removed += out.removed.size();
    ms += out.tracking_ms;
    filter_ms += out.filter_ms;
    if (!a.save_tracks.empty()) {
      const std::string path = (std::filesystem::path(a.save_tracks) / (std::to_string(f->t_ns) + ".png")).string();
      if (!cv::imwrite(path, frontend::drawTracks(f->left, out))) throw InputError(path, "cannot write image");
    }
    bar.update(frames);
  }
  bar.finish();
  if (frames == 0) throw InputError(a.dataset, "no stereo frames");
  nlohmann::json j = printTrackSummary(a.mode, frames, features, stereo, removed, ms, filter_ms, quality.summary());
  if (a.image_stats) j["images"] = printImageFigures(images.figures(), config.tracker.min_dist);
  if (!a.json.empty()) {
    std::ofstream out(a.json);
    out << j.dump(1) << "\n";
    if (!out) throw InputError(a.json, "cannot write file");
  }
  return kOk;
}

}  // namespace

void registerTrack(CLI::App& app, int& exit_code) {
  auto a = std::make_shared<TrackArgs>();
  CLI::App* cmd = app.add_subcommand(
      "track",
      "Run the front end alone (stereo KLT tracker with the baseline, ransac or seg rejection)\n"
      "on a EuRoC folder or a ROS1 / ROS 2 bag; print feature counts, the share with a right-image match and their\n"
      "distance to the epipolar line, track lengths and timing; optionally save images with the\n"
      "tracks drawn (green kept, yellow dynamic candidates, red removed).");
  cmd->add_option("-c,--config", a->config, "VINS-Fusion config")->required();
  cmd->add_option("-d,--dataset", a->dataset, "EuRoC folder, ROS1 or ROS 2 bag (topics from the config)")->required();
  cmd->add_option("--mode", a->mode, "baseline | ransac | seg (seg reads mav0/cam0/mask/)");
  cmd->add_option("--save-tracks", a->save_tracks, "folder for the track images");
  cmd->add_option("--frames", a->max_frames, "stop after this many frames (0 = all)")->check(CLI::NonNegativeNumber);
  cmd->add_flag("--image-stats", a->image_stats,
                "also measure the input images: brightness and its spread, exposure variation between\n"
                "frames, gradient magnitudes, Shi-Tomasi corners, vignetting profile, right/left brightness");
  cmd->add_option("--json", a->json, "write the figures to this JSON file");
  cmd->callback([a, &exit_code] { exit_code = runTrack(*a); });
}

}  // namespace idyvins::app
