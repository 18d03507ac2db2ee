// `idyvins report`: one offline HTML page of one run, or of several runs of one sequence side
// by side (docs/report.md). Reads the run folders, writes the page; no per-frame logic.

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>

#include "commands.h"
#include "core/error.h"
#include "report_data.h"

namespace idyvins::app {
namespace {

struct ReportArgs {
  std::vector<std::string> runs;
  std::string html, groundtruth;
  std::size_t max_points = ReportOptions{}.max_map_points;
};

int runReport(const ReportArgs& a) {
  ReportOptions options;
  options.max_map_points = a.max_points;
  options.groundtruth = a.groundtruth;
  const nlohmann::json data = reportData(a.runs, options);
  const std::string html = a.html.empty() ? (std::filesystem::path(a.runs.front()) / "report.html").string() : a.html;
  const std::string page = reportHtml(data);
  const std::string part = html + ".part";
  {
    std::ofstream out(part, std::ios::binary);
    out << page;
    if (!out) throw InputError(part, "cannot write file");
  }
  std::error_code ec;
  std::filesystem::rename(part, html, ec);
  if (ec) throw InputError(html, "cannot rename " + part + ": " + ec.message());
  std::printf("wrote %s (%.1f MB, %zu run%s): open it in a browser (works offline)\n", html.c_str(),
              static_cast<double>(page.size()) / 1e6, a.runs.size(), a.runs.size() == 1 ? "" : "s");
  return kOk;
}

}  // namespace

void registerReport(CLI::App& app, int& exit_code) {
  auto a = std::make_shared<ReportArgs>();
  CLI::App* cmd = app.add_subcommand(
      "report",
      "Write one HTML page (offline: script and data inlined) of one run folder, or of several runs of\n"
      "the same sequence side by side (e.g. baseline and idy): trajectory against ground truth (top view,\n"
      "height, ATE over time and along the path, RPE; resets and initialization marked), an interactive\n"
      "3D map (static / eliminated / confirmed dynamic, trajectory; orbit, zoom, layer toggles), dynamic\n"
      "preprocessing (d_s histogram against chi2(1), CV per frame against sqrt(2), candidates and\n"
      "eliminations over time, classification against ground-truth masks), timing per stage, and the\n"
      "command and config that made each run. Without ground truth (no OUT/groundtruth.tum) the page\n"
      "says so in place of those panels. docs/report.md.");
  cmd->add_option("runs", a->runs, "run folders (OUT of idyvins run), same sequence")->required();
  cmd->add_option("--html", a->html, "page to write (default: FIRST_RUN/report.html)");
  cmd->add_option("--groundtruth", a->groundtruth,
                  "ground truth for runs without OUT/groundtruth.tum: a TUM or EuRoC CSV file or a EuRoC folder");
  cmd->add_option("--max-map-points", a->max_points,
                  "map points per run on the page; larger maps are thinned evenly (the page says so)")
      ->check(CLI::Range(std::size_t{1000}, std::size_t{20'000'000}));
  cmd->callback([a, &exit_code] { exit_code = runReport(*a); });
}

}  // namespace idyvins::app
