#include "pipeline/run_outputs.h"

#include <filesystem>
#include <fstream>
#include <iterator>

#include "core/build_info.h"
#include "core/error.h"
#include "io/ply.h"
#include "io/trajectory_io.h"
#include "map/map_io.h"
#include "pipeline/observers.h"
#include "pipeline/outputs.h"
#include "pipeline/run.h"

namespace idyvins::pipeline {

/// The folder and the recorders that write while the run goes.
struct RunOutputs::Files {
  Files(const std::string& out, const RunOutputsOptions& o)
      : folder(out, runFolderOptions(o.inputs, o.force, o.extra_names)),
        dump(o.dump_observations.empty() ? "" : folder.extraFile(o.dump_observations)),
        map_dir(o.save_map.empty() ? "" : folder.extraFolder(o.save_map)),
        stats_path(folder.path() + "/stats.json"),
        stats_part(stats_path + ".part"),
        stats_file(stats_part),
        stats(stats_file),
        observations(o.masks, /*keep_observations=*/!dump.empty()) {
    if (!stats_file) throw InputError(stats_part, "cannot write file");
  }
  /// Closes stats.json with `summary` and gives it its final name.
  void finishStats(const nlohmann::json& summary) {
    stats.finish(summary);
    stats_file.close();
    if (!stats_file) throw InputError(stats_part, "write failed");
    std::error_code ec;
    std::filesystem::rename(stats_part, stats_path, ec);
    if (ec) throw InputError(stats_path, "cannot rename " + stats_part + ": " + ec.message());
  }

  io::OutputFolder folder;
  std::string dump, map_dir;
  std::string stats_path, stats_part;
  std::ofstream stats_file;
  StatsRecorder stats;
  ObservationRecorder observations;
};

namespace {

std::string fileText(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path, "cannot read file");
  return std::string(std::istreambuf_iterator<char>(in), {});
}

/// DIR/run.json: the command, its folder, the dataset, the config files' text, the build.
void writeRunJson(const std::string& dir, const RunRecord& r, const Config& config) {
  nlohmann::json files = nlohmann::json::array();
  files.push_back({{"path", config.path}, {"text", fileText(config.path)}});
  for (const std::string& cam : config.cam_paths) files.push_back({{"path", cam}, {"text", fileText(cam)}});
  std::error_code ec;
  const nlohmann::json record = {{"command", r.command_line},
                                 {"cwd", std::filesystem::current_path(ec).string()},
                                 {"dataset", r.dataset},
                                 {"config_files", files},
                                 {"build", {{"commit", buildCommit()}}}};
  std::ofstream out(dir + "/run.json");
  out << record.dump(1) << "\n";
  if (!out) throw InputError(dir + "/run.json", "write failed");
}

/// DIR/groundtruth.tum: the reference poses from 1 s before the first to 1 s after the last
/// frame (nothing when none are in that span).
void writeGroundTruthSpan(const std::string& dir, const std::vector<StampedPose>& gt, const Result& result) {
  const TimeNs from = result.summary.first_t_ns - 1'000'000'000, to = result.summary.last_t_ns + 1'000'000'000;
  std::vector<StampedPose> span;
  for (const StampedPose& p : gt)
    if (p.t_ns >= from && p.t_ns <= to) span.push_back(p);
  if (!span.empty()) io::writeTum(dir + "/groundtruth.tum", span);
}

}  // namespace

RunOutputs::RunOutputs(const std::string& out, RunOutputsOptions options)
    : options_(std::move(options)), files_(std::make_unique<Files>(out, options_)) {}

RunOutputs::~RunOutputs() = default;

std::vector<FrameObserver*> RunOutputs::observers() {
  std::vector<FrameObserver*> o;
  if (options_.masks || !files_->dump.empty()) o.push_back(&files_->observations);
  o.push_back(&files_->stats);
  return o;
}

void RunOutputs::attach(System& system) {
  for (FrameObserver* o : observers()) system.addObserver(*o);
}

const std::string& RunOutputs::path() const { return files_->folder.path(); }

nlohmann::json RunOutputs::write(const System& system, const Result& result, const RunEnd& end) {
  const std::string& dir = files_->folder.path();
  nlohmann::json summary = summaryJson(result, system.mode(), end.wall_s);
  summary["threads"] = system.threads();
  summary["feedback_delay"] = system.runOptions().feedback_delay;
  summary["build"] = {{"commit", buildCommit()}};
  summary["config_fnv1a64"] = configChecksum(system.config());
  summary.update(end.extras);
  if (options_.masks) summary["classification"] = toJson(files_->observations.classify(result));
  if (!files_->dump.empty()) files_->observations.writeCsv(files_->dump, result);
  writeResultFiles(dir, result);
  if (options_.masks) {  // the static map's points on moving objects, for the report's ghost layer
    std::vector<io::LabelledPoint> ghosts;
    for (const auto& p : files_->observations.staticMapOnMoving(result)) ghosts.push_back({p.p_w, 0});
    io::writePly(dir + "/map_static_on_moving.ply", ghosts);
  }
  if (!files_->map_dir.empty()) {
    map::SavedMap saved = system.loopCloser()->savedMap();
    saved.rig = rigFingerprint(system.config());
    map::saveMap(files_->map_dir, saved);
  }
  addAte(summary, end.groundtruth, result);
  if (const auto& e = result.summary.extrinsic) {  // the estimate, ready for the next run
    Config refined = system.config();
    refined.T_b_c = e->T_b_c;
    if (refined.estimator.estimate_extrinsic == 2) refined.estimator.estimate_extrinsic = 1;  // a usable guess now
    saveConfig(refined, dir + "/config_refined.yaml");
  }
  if (end.record) writeRunJson(dir, *end.record, system.config());
  if (!end.groundtruth.empty()) writeGroundTruthSpan(dir, end.groundtruth, result);
  files_->finishStats(summary);
  return summary;
}

std::vector<std::string> RunOutputs::publish() { return files_->folder.publish(); }

}  // namespace idyvins::pipeline
