#pragma once
// `idyvins report`: what the page shows, read from run folders (stats.json, trajectories, PLY
// maps, run.json, groundtruth.tum) and validated; then the page itself, one offline HTML file
// (the script bundled from web/ at build time is inlined with the data). docs/report.md.

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace idyvins::app {

/// Limits of the page's payload.
struct ReportOptions {
  std::size_t max_map_points = 200'000;  ///< per run; beyond it the map is thinned evenly (said on the page)
  /// Ground truth for runs whose folder has no groundtruth.tum: a TUM or EuRoC CSV file or a
  /// EuRoC folder ("" = none).
  std::string groundtruth;
};

/// One run folder as the page's data. Throws InputError (file, line when known, what was
/// expected) when a file the run must have is missing or damaged: stats.json, trajectory.tum,
/// map_static.ply, map_dynamic.ply, and with loop closure trajectory_loop.tum. Ground truth
/// (groundtruth.tum) and run.json are optional; their absence is explained on the page.
nlohmann::json reportRun(const std::string& folder, const ReportOptions& options);

/// The page's data for several runs of one sequence (InputError if they are of different
/// sequences: other first frame time or frame count).
nlohmann::json reportData(const std::vector<std::string>& folders, const ReportOptions& options);

/// web/src/template.html and the esbuild bundle of web/src/report.js (script and style), embedded
/// at build time by cmake/embed_report.cmake.
std::string reportTemplate();
std::string reportScript();
std::string reportStyle();

/// The HTML page: template, style and script (embedded at build time) with `data` inlined.
std::string reportHtml(const nlohmann::json& data);

}  // namespace idyvins::app
