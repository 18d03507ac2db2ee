#include "pipeline/observers.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <stdexcept>

#include "core/error.h"
#include "pipeline/outputs.h"

namespace idyvins::pipeline {
namespace {

/// d_s histogram: 1 px² bins from 0 to 20, then one overflow bin.
std::vector<int> histogram(const std::vector<double>& d) {
  std::vector<int> h(21, 0);
  for (double v : d) ++h[std::min(20, static_cast<int>(v))];
  return h;
}

std::unordered_set<std::uint64_t> confirmedIds(const Result& result) {
  std::unordered_set<std::uint64_t> ids;
  for (const auto& p : result.dynamic_map)
    if (p.label == frontend::FeatureLabel::kConfirmedDynamic) ids.insert(p.id);
  return ids;
}

}  // namespace

void ObservationRecorder::onFrame(const StereoFrame& input, const FrameOutput& output) {
  const cv::Mat& mask = input.left_mask;
  auto on_moving = [&](const frontend::Feature& f) {
    if (!has_masks_ || mask.empty()) return false;
    const int u = static_cast<int>(std::lround(f.uv.x())), v = static_cast<int>(std::lround(f.uv.y()));
    return mask.at<std::uint8_t>(std::clamp(v, 0, mask.rows - 1), std::clamp(u, 0, mask.cols - 1)) != 0;
  };
  const float cred = output.idy ? static_cast<float>(output.idy->credibility) : 0.f;
  auto record = [&](const frontend::Feature& f) {
    const bool moving = on_moving(f);
    ++observations_seen_;
    eval::addObservation(tracks_, {f.id, moving, f.label == frontend::FeatureLabel::kEliminated});
    if (keep_observations_)
      observations_.push_back({f.id, moving, output.t_ns, static_cast<float>(f.uv.x()), static_cast<float>(f.uv.y()),
                               static_cast<float>(f.d_s_px2), cred, static_cast<float>(f.stereo_chi2),
                               static_cast<float>(f.stereo_depth),
                               static_cast<float>(f.has_right ? f.uv_right.x() : -1.0),
                               static_cast<float>(f.has_right ? f.uv_right.y() : -1.0), f.label, f.track_length});
  };
  for (const auto& f : output.features.features) record(f);
  for (const auto& f : output.features.removed) record(f);  // label kEliminated
  for (const auto& f : output.features.lost_moving) lost_moving_ids_.insert(f.id);
  outlier_ids_.insert(output.estimate.outlier_ids.begin(), output.estimate.outlier_ids.end());
}

void ObservationRecorder::relabelLostMoving() {
  for (auto& o : observations_)
    if (lost_moving_ids_.count(o.id)) o.label = frontend::FeatureLabel::kEliminated;
  for (const auto id : lost_moving_ids_)
    if (const auto it = tracks_.find(id); it != tracks_.end()) it->second.eliminated = true;
}

eval::DynamicClassification ObservationRecorder::classify(const Result& result) {
  relabelLostMoving();
  std::vector<std::uint64_t> static_ids;
  for (const auto& p : result.static_map) static_ids.push_back(p.id);
  return eval::classifyTracks(tracks_, confirmedIds(result), static_ids);
}

std::vector<backend::MapPoint> ObservationRecorder::staticMapOnMoving(const Result& result) const {
  std::vector<backend::MapPoint> out;
  if (!has_masks_) return out;
  for (const auto& p : result.static_map) {
    const auto it = tracks_.find(p.id);
    if (it != tracks_.end() && 2 * it->second.on_moving > it->second.observations) out.push_back(p);
  }
  return out;
}

void ObservationRecorder::writeCsv(const std::string& path, const Result& result) {
  if (!keep_observations_) throw std::logic_error("ObservationRecorder::writeCsv needs keep_observations");
  relabelLostMoving();
  const std::unordered_set<std::uint64_t> confirmed = confirmedIds(result);
  std::unordered_set<std::uint64_t> in_static;
  for (const auto& p : result.static_map) in_static.insert(p.id);
  std::ofstream f(path);
  if (!f) throw InputError(path, "cannot write file");
  f << "t_ns,id,u,v,track_length,frontend_label,d_s_px2,credibility,stereo_chi2,on_moving,confirmed_dynamic,"
       "in_static_map,outlier_removed,stereo_depth_m,u_right,v_right\n";
  static const char* kLabels[] = {"static", "candidate", "eliminated", "confirmed_dynamic"};
  for (const auto& o : observations_) {
    f << o.t_ns << ',' << o.id << ',' << o.u << ',' << o.v << ',' << o.track_length << ','
      << kLabels[static_cast<int>(o.label)] << ',' << o.d_s << ',' << o.credibility << ',' << o.stereo_chi2 << ','
      << (has_masks_ ? (o.on_moving ? "1" : "0") : "") << ',' << confirmed.count(o.id) << ',' << in_static.count(o.id)
      << ',' << outlier_ids_.count(o.id) << ',' << o.stereo_depth << ',';
    if (o.u_right >= 0)
      f << o.u_right << ',' << o.v_right;
    else
      f << ',';
    f << '\n';
  }
  if (!f) throw InputError(path, "write failed");
}

nlohmann::json toJson(const eval::DynamicClassification& c) {
  return {{"observations_on_moving", c.observations_on_moving},
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

StatsRecorder::StatsRecorder(std::ostream& out) : out_(out) { out_ << "{\n \"frames\": ["; }

void StatsRecorder::onFrame(const StereoFrame&, const FrameOutput& out) {
  out_ << (frames_++ ? ",\n  " : "\n  ") << frameJson(out).dump();
}

void StatsRecorder::finish(const nlohmann::json& summary) {
  std::string s = summary.dump(1);
  for (std::size_t pos = s.find('\n'); pos != std::string::npos; pos = s.find('\n', pos + 2)) s.insert(pos + 1, " ");
  out_ << (frames_ ? "\n ],\n" : "],\n") << " \"summary\": " << s << "\n}\n";
}

nlohmann::json StatsRecorder::frameJson(const FrameOutput& out) {
  const frontend::FeatureFrame& ff = out.features;
  const backend::FrameResult& r = out.estimate;
  nlohmann::json dyn = nullptr;
  if (out.idy) {
    const dynamic::FrameStats& st = *out.idy;
    dyn = {{"prior", st.prior_valid},
           {"credibility", st.credibility},
           {"tracked", st.tracked},
           {"eliminated", st.eliminated},
           {"candidates", st.candidates},
           {"cv_before", st.cv_before},
           {"cv_after", st.cv_after},
           {"stop_rule", st.stop_rule},
           {"d_s_hist", histogram(st.d_s)},
           {"d_s_hist_kept", histogram(st.d_s_kept)},
           {"candidates_in_window", r.candidates},
           {"confirmed_dynamic", r.confirmed_dynamic},
           {"outliers_confirmed_dynamic", r.outliers_confirmed},
           {"stereo_tested", st.stereo_tested},
           {"stereo_eliminated", st.stereo_eliminated},
           {"mono_tested", st.mono_tested},
           {"mono_eliminated", st.mono_eliminated},
           {"stereo_noise_scale", st.stereo_noise_scale},
           {"lost_tested", ff.lost_tested},
           {"lost_moving", ff.lost_moving.size()},
           {"cleared", r.cleared}};
  }
  return {{"t_ns", r.t_ns},
          {"dynamic", dyn},
          {"tracking_ms", ff.tracking_ms},
          {"filter_ms", ff.filter_ms},
          {"optimization_ms", r.optimization_ms},
          {"marginalization_ms", r.marginalization_ms},
          {"solve_iterations", r.solve.iterations},
          {"features", ff.features.size()},
          {"features_right", std::count_if(ff.features.begin(), ff.features.end(),
                                           [](const frontend::Feature& f) { return f.has_right; })},
          {"features_new", std::count_if(ff.features.begin(), ff.features.end(),
                                         [](const frontend::Feature& f) { return f.track_length == 1; })},
          {"removed", ff.removed.size()},
          {"lost_tracks", toJson(ff.lost_tracks)},
          {"lost_new", toJson(ff.lost_new)},
          {"landmarks", r.landmarks},
          {"right_outliers", r.right_outliers},
          {"keyframe", r.keyframe},
          {"initialized", r.initialized},
          {"td_s", r.td_s},
          {"extrinsic", r.extrinsic ? toJson(*r.extrinsic) : nlohmann::json()},
          {"status", r.status}};
}

bool isTimingField(const std::string& key) {
  const auto ends = [&](const std::string& tail) {
    return key.size() >= tail.size() && key.compare(key.size() - tail.size(), tail.size(), tail) == 0;
  };
  return ends("_ms") || key == "wall_s" || key == "realtime_factor" || key == "threads";
}

}  // namespace idyvins::pipeline
