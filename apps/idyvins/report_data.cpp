#include "report_data.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/error.h"
#include "eval/trajectory_metrics.h"
#include "io/open_dataset.h"
#include "io/ply.h"
#include "io/trajectory_io.h"

namespace fs = std::filesystem;

namespace idyvins::app {

namespace {

double round3(double v) { return std::isfinite(v) ? std::round(v * 1000.0) / 1000.0 : 0.0; }

/// Decimals that keep a quantity of this size to 1 part in 10^4: 3 (mm) for metres of motion, 6 for
/// a run that moved 1 cm; between 3 and 7.
int decimalsFor(double extent) {
  if (!(extent > 0) || !std::isfinite(extent)) return 3;
  return std::clamp(4 - static_cast<int>(std::floor(std::log10(extent))), 3, 7);
}

double roundTo(double v, int decimals) {
  const double k = std::pow(10.0, decimals);
  return std::isfinite(v) ? std::round(v * k) / k : 0.0;
}

/// The largest extent (max - min) of the poses' positions along any axis.
double extentOf(const std::vector<StampedPose>& poses) {
  if (poses.empty()) return 0;
  Eigen::Vector3d lo = poses[0].p_w_b, hi = lo;
  for (const StampedPose& p : poses) lo = lo.cwiseMin(p.p_w_b), hi = hi.cwiseMax(p.p_w_b);
  return (hi - lo).maxCoeff();
}

/// A JSON file, or InputError naming the line where it breaks.
nlohmann::json readJson(const std::string& path) {
  std::ifstream in(path);
  if (!in)
    throw InputError(path, "missing or unreadable: not an idyvins run folder ('idyvins run --out DIR' writes it)");
  const std::string text((std::istreambuf_iterator<char>(in)), {});
  try {
    return nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error& e) {
    const std::size_t at = std::min<std::size_t>(e.byte ? e.byte - 1 : 0, text.size());
    const int line = 1 + static_cast<int>(std::count(text.begin(), text.begin() + static_cast<long>(at), '\n'));
    throw InputError(path, line, "damaged JSON (" + std::string(e.what()) + ")");
  }
}

/// stats.json with the fields the page reads.
nlohmann::json readStats(const std::string& path) {
  nlohmann::json s = readJson(path);
  if (!s.is_object() || !s.contains("frames") || !s["frames"].is_array() || !s.contains("summary") ||
      !s["summary"].is_object() || !s["summary"].contains("first_t_ns") || !s["summary"].contains("mode"))
    throw InputError(
        path, "expected an idyvins stats.json: {\"frames\": [...], \"summary\": {\"first_t_ns\", \"mode\", ...}}");
  for (const nlohmann::json& f : s["frames"])
    if (!f.is_object() || !f.contains("t_ns") || !f["t_ns"].is_number_integer() || !f.contains("tracking_ms"))
      throw InputError(path, "a frame without t_ns / tracking_ms: " + f.dump().substr(0, 80));
  return s;
}

/// Per-frame series (time in s from the first frame), the d_s histogram summed over the run.
nlohmann::json frameSeries(const nlohmann::json& frames, std::int64_t first_t_ns, nlohmann::json& ds_hist) {
  static const char* const numeric[] = {"tracking_ms",        "filter_ms", "optimization_ms",
                                        "marginalization_ms", "features",  "landmarks"};
  static const char* const tracked[] = {"features_right", "features_new"};  // null in older runs' stats.json
  static const char* const dynamic[] = {
      "cv_before", "cv_after", "candidates", "eliminated", "candidates_in_window", "confirmed_dynamic"};
  nlohmann::json out = {{"t", nlohmann::json::array()}, {"status", nlohmann::json::array()}};
  std::vector<double> hist(21, 0.0), kept(21, 0.0);
  bool any_dynamic = false;
  for (const nlohmann::json& f : frames) {
    out["t"].push_back(round3(static_cast<double>(f["t_ns"].get<std::int64_t>() - first_t_ns) * 1e-9));
    out["status"].push_back(f.value("status", ""));
    for (const char* k : numeric) out[k].push_back(round3(f.value(k, 0.0)));
    for (const char* k : tracked) out[k].push_back(f.contains(k) ? nlohmann::json(f[k]) : nlohmann::json());
    const nlohmann::json& d = f.contains("dynamic") ? f["dynamic"] : nlohmann::json();
    any_dynamic = any_dynamic || d.is_object();
    for (const char* k : dynamic)
      out[k].push_back(d.is_object() && d.contains(k) ? nlohmann::json(round3(d[k].get<double>())) : nlohmann::json());
    if (!d.is_object()) continue;
    for (std::size_t i = 0; i < 21 && i < d.value("d_s_hist", std::vector<double>{}).size(); ++i) {
      hist[i] += d["d_s_hist"][i].get<double>();
      kept[i] += d["d_s_hist_kept"][i].get<double>();
    }
  }
  ds_hist = any_dynamic ? nlohmann::json{{"bin_px2", 1.0}, {"counts", hist}, {"kept", kept}} : nlohmann::json();
  return out;
}

/// Positions rounded to `decimals` (decimalsFor the run's motion: a 1 cm run is not a line of 1 mm steps).
nlohmann::json positions(const std::vector<StampedPose>& poses, const eval::Similarity& align, std::int64_t first_t_ns,
                         int decimals) {
  nlohmann::json out = {{"t", nlohmann::json::array()},
                        {"x", nlohmann::json::array()},
                        {"y", nlohmann::json::array()},
                        {"z", nlohmann::json::array()}};
  for (const StampedPose& p : poses) {
    const Eigen::Vector3d q = align.apply(p.p_w_b);
    out["t"].push_back(round3(static_cast<double>(p.t_ns - first_t_ns) * 1e-9));
    out["x"].push_back(roundTo(q.x(), decimals));
    out["y"].push_back(roundTo(q.y(), decimals));
    out["z"].push_back(roundTo(q.z(), decimals));
  }
  return out;
}

/// Ground-truth panels: the estimate aligned (SE(3), evo's association), ATE over time and
/// path, RPE; or why there are none.
void addGroundTruth(nlohmann::json& run, const std::string& dir, const std::vector<StampedPose>& est,
                    std::int64_t first_t_ns, eval::Similarity& align, const std::string& fallback, int decimals) {
  const std::string own = dir + "/groundtruth.tum";
  if (!fs::exists(own) && fallback.empty()) {
    run["gt_note"] =
        "no ground truth: the run folder has no groundtruth.tum (the dataset has no ground truth, or an "
        "idyvins older than the report wrote the folder; report --groundtruth GT supplies one)";
    return;
  }
  const std::vector<StampedPose> gt = fs::exists(own) ? io::readTum(own) : io::readReference(fallback);
  run["gt_source"] = fs::exists(own) ? own : fallback;
  eval::AteResult ate;
  try {
    ate = eval::computeAte(gt, est, eval::AlignMode::kSe3, 10'000'000);
  } catch (const std::exception& e) {
    run["gt_note"] =
        std::string("no ground-truth panels: groundtruth.tum does not overlap the trajectory (") + e.what() + ")";
    return;
  }
  align = ate.alignment;
  std::vector<StampedPose> gt_assoc, est_assoc;
  for (const auto& [i, j] : ate.pairs) gt_assoc.push_back(gt[i]), est_assoc.push_back(est[j]);
  nlohmann::json err = {
      {"t", nlohmann::json::array()}, {"err", nlohmann::json::array()}, {"dist", nlohmann::json::array()}};
  double dist = 0;
  const int err_decimals = decimalsFor(ate.stats.max);
  for (std::size_t k = 0; k < ate.errors.size(); ++k) {
    if (k) dist += (gt_assoc[k].p_w_b - gt_assoc[k - 1].p_w_b).norm();
    err["t"].push_back(round3(static_cast<double>(ate.stamps[k] - first_t_ns) * 1e-9));
    err["err"].push_back(roundTo(ate.errors[k], err_decimals));
    err["dist"].push_back(roundTo(dist, decimals));
  }
  run["ate"] = err;
  run["ate_stats"] = {{"rmse", ate.stats.rmse}, {"mean", ate.stats.mean}, {"median", ate.stats.median},
                      {"max", ate.stats.max},   {"n", ate.stats.n},       {"align", "se3"}};
  run["gt"] = positions(gt, eval::Similarity{}, first_t_ns, decimals);
  run["rpe"] = nlohmann::json::array();
  for (double delta : {1.0, 5.0, 10.0}) {
    try {
      const eval::ErrorStats r = eval::computeRpe(gt_assoc, est_assoc, delta);
      if (r.n > 0)
        run["rpe"].push_back({{"delta_m", delta}, {"rmse", r.rmse}, {"mean", r.mean}, {"max", r.max}, {"n", r.n}});
    } catch (const std::exception&) {  // path shorter than delta
    }
  }
}

/// Loop events of loops.csv (times in s from the first frame): when each loop was closed, to when.
nlohmann::json loopEvents(const std::string& path, std::int64_t first_t_ns) {
  std::ifstream in(path);
  if (!in) throw InputError(path, "missing: the run closed loops (summary.loop_closure) but has no loops.csv");
  nlohmann::json out = {
      {"t", nlohmann::json::array()}, {"old_t", nlohmann::json::array()}, {"inliers", nlohmann::json::array()}};
  std::string line;
  for (int line_no = 1; std::getline(in, line); ++line_no) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream ss(line);
    long long old_t = 0, new_t = 0, old_kf = 0, new_kf = 0, votes = 0, matches = 0, inliers = 0;
    char c1, c2, c3, c4, c5, c6, c7;
    if (!(ss >> old_t >> c1 >> new_t >> c2 >> old_kf >> c3 >> new_kf >> c4 >> votes >> c5 >> matches >> c6 >> inliers >>
          c7) ||
        c1 != ',' || c2 != ',' || c3 != ',' || c4 != ',' || c5 != ',' || c6 != ',' || c7 != ',')
      throw InputError(path, line_no, "expected old_t_ns,new_t_ns,old_keyframe,new_keyframe,votes,matches,inliers,...");
    out["t"].push_back(round3(static_cast<double>(new_t - first_t_ns) * 1e-9));
    out["old_t"].push_back(round3(static_cast<double>(old_t - first_t_ns) * 1e-9));
    out["inliers"].push_back(inliers);
  }
  return out;
}

/// Maps as flat xyz arrays per label (aligned like the trajectory), thinned evenly past the limit.
nlohmann::json mapLayers(const std::string& dir, const eval::Similarity& align, const eval::Similarity* loop_align,
                         const ReportOptions& o) {
  std::vector<io::LabelledPoint> pts = io::readPly(dir + "/map_static.ply");
  const std::vector<io::LabelledPoint> dyn = io::readPly(dir + "/map_dynamic.ply");
  pts.insert(pts.end(), dyn.begin(), dyn.end());
  std::vector<io::LabelledPoint> loop_pts;
  if (loop_align && fs::exists(dir + "/map_static_loop.ply")) loop_pts = io::readPly(dir + "/map_static_loop.ply");
  std::vector<io::LabelledPoint> ghosts;  // static-map points on moving objects (run with masks)
  if (fs::exists(dir + "/map_static_on_moving.ply")) ghosts = io::readPly(dir + "/map_static_on_moving.ply");
  const std::size_t total = pts.size() + loop_pts.size();
  const std::size_t stride = std::max<std::size_t>(1, (total + o.max_map_points - 1) / o.max_map_points);
  nlohmann::json layers = {{"static", nlohmann::json::array()},
                           {"eliminated", nlohmann::json::array()},
                           {"confirmed", nlohmann::json::array()},
                           {"static_loop", nlohmann::json::array()},
                           {"ghosts", nlohmann::json::array()}};
  static const char* const names[] = {"static", "eliminated", "confirmed"};
  const auto add = [&](const std::vector<io::LabelledPoint>& v, bool is_loop, const char* name = nullptr) {
    for (std::size_t i = 0; i < v.size(); i += stride) {
      nlohmann::json& layer = layers[name ? name : is_loop ? "static_loop" : names[v[i].label]];
      const Eigen::Vector3d q = is_loop ? loop_align->apply(v[i].p) : align.apply(v[i].p);
      layer.push_back(round3(q.x()));
      layer.push_back(round3(q.y()));
      layer.push_back(round3(q.z()));
    }
  };
  add(pts, false);
  add(loop_pts, true);
  add(ghosts, false, "ghosts");
  layers["points_total"] = total;
  layers["stride"] = stride;
  return layers;
}

/// The loop-corrected trajectory (aligned to the ground truth on its own: it may be in a loaded
/// map's frame), its ATE over time, and the loop events.
void addLoop(nlohmann::json& run, const std::string& folder, std::int64_t first, eval::Similarity& loop_align,
             int decimals) {
  const std::vector<StampedPose> lt = io::readTum(folder + "/trajectory_loop.tum");
  if (run.contains("gt")) try {
      const eval::AteResult ate = eval::computeAte(io::readReference(run["gt_source"].get<std::string>()), lt,
                                                   eval::AlignMode::kSe3, 10'000'000);
      loop_align = ate.alignment;
      nlohmann::json err = {{"t", nlohmann::json::array()}, {"err", nlohmann::json::array()}};
      for (std::size_t k = 0; k < ate.errors.size(); ++k) {
        err["t"].push_back(round3(static_cast<double>(ate.stamps[k] - first) * 1e-9));
        err["err"].push_back(roundTo(ate.errors[k], decimalsFor(ate.stats.max)));
      }
      run["loop_ate"] = err;
    } catch (const std::exception&) {  // no overlap: drawn unaligned
    }
  run["loop"] = positions(lt, loop_align, first, decimals);
  run["loop_events"] = loopEvents(folder + "/loops.csv", first);
}

}  // namespace

nlohmann::json reportRun(const std::string& folder, const ReportOptions& options) {
  if (!fs::is_directory(folder)) throw InputError(folder, "not a folder (expected the OUT of 'idyvins run')");
  const nlohmann::json stats = readStats(folder + "/stats.json");
  const nlohmann::json& summary = stats["summary"];
  const std::int64_t first = summary["first_t_ns"].get<std::int64_t>();
  nlohmann::json run = {
      {"folder", folder}, {"name", fs::path(folder).lexically_normal().filename().string()}, {"summary", summary}};
  if (run["name"] == "" || run["name"] == ".")
    run["name"] = fs::absolute(folder).lexically_normal().parent_path().filename().string();
  nlohmann::json ds;
  run["frames"] = frameSeries(stats["frames"], first, ds);
  run["ds_hist"] = ds;
  const std::vector<StampedPose> est = io::readTum(folder + "/trajectory.tum");
  eval::Similarity align;
  const int decimals = decimalsFor(extentOf(est));
  addGroundTruth(run, folder, est, first, align, options.groundtruth, decimals);
  run["est"] = positions(est, align, first, decimals);
  run["position_decimals"] = decimals;
  const bool loop = summary.contains("loop_closure") && summary["loop_closure"].is_object();
  eval::Similarity loop_align;
  if (loop) addLoop(run, folder, first, loop_align, decimals);
  run["maps"] = mapLayers(folder, align, loop ? &loop_align : nullptr, options);
  if (fs::exists(folder + "/run.json"))
    run["run"] = readJson(folder + "/run.json");
  else
    run["run_note"] = "the folder has no run.json (the command and config): an idyvins older than the report wrote it";
  return run;
}

nlohmann::json reportData(const std::vector<std::string>& folders, const ReportOptions& options) {
  nlohmann::json data = {{"runs", nlohmann::json::array()}};
  for (const std::string& f : folders) {
    nlohmann::json run = reportRun(f, options);
    if (!data["runs"].empty()) {
      const nlohmann::json& a = data["runs"][0]["summary"];
      const nlohmann::json& b = run["summary"];
      if (a["first_t_ns"] != b["first_t_ns"])
        throw InputError(f, "another sequence than " + folders.front() + " (first frame at " + b["first_t_ns"].dump() +
                                " ns, not " + a["first_t_ns"].dump() +
                                "): a report puts runs of one sequence side by side");
    }
    data["runs"].push_back(std::move(run));
  }
  return data;
}

std::string reportHtml(const nlohmann::json& data) {
  std::string json = data.dump();
  for (std::size_t at = json.find("</"); at != std::string::npos; at = json.find("</", at + 3))
    json.insert(at + 1, "\\");
  std::string page = reportTemplate();
  const auto put = [&page](const std::string& slot, const std::string& text) {
    const std::size_t at = page.find(slot);
    if (at == std::string::npos) throw std::logic_error("report template lacks " + slot);
    page.replace(at, slot.size(), text);
  };
  put("/*IDY_STYLE*/", reportStyle());
  put("/*IDY_SCRIPT*/", reportScript());  // the script slot follows the data slot: data last
  put("/*IDY_DATA*/", json);
  return page;
}

}  // namespace idyvins::app
