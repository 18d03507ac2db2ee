#include "bench_sweep.h"

#include <algorithm>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>

#include "commands.h"
#include "config/config.h"
#include "core/build_info.h"
#include "core/checksum.h"
#include "core/error.h"
#include "pipeline/run.h"

namespace fs = std::filesystem;

namespace idyvins::app {
namespace {

constexpr const char* kFormat = "idyvins-bench";
constexpr int kVersion = 1;

bool isTiming(const std::string& key) {
  const bool ms =
      (key.size() > 3 && key.compare(key.size() - 3, 3, "_ms") == 0) || key.find("_ms_") != std::string::npos;
  return ms || key == "wall_s" || key == "realtime_factor";
}

nlohmann::json jobJson(const Job& j) {
  return {{"sequence", j.sequence},
          {"group", j.group},
          {"level", j.level},
          {"mode", j.mode},
          {"dataset", j.dataset},
          {"config", j.config},
          {"name", j.name},
          {"config_fnv1a64", j.config_fnv1a64},
          {"dataset_fnv1a64", j.dataset_fnv1a64}};
}

Job jobFromJson(const nlohmann::json& v) {
  Job j;
  j.sequence = v.at("sequence");
  j.group = v.at("group");
  j.level = v.at("level");
  j.mode = v.at("mode");
  j.dataset = v.at("dataset");
  j.config = v.at("config");
  j.name = v.at("name");
  j.config_fnv1a64 = v.at("config_fnv1a64");
  j.dataset_fnv1a64 = v.at("dataset_fnv1a64");
  return j;
}

/// Why a job has no result: never started, or started and stopped (a log or a staged folder).
std::string whyMissing(const fs::path& dir, const std::string& name) {
  const fs::path log = dir / "runs" / (name + ".log");
  if (fs::exists(log)) return "failed or killed: see " + log.string();
  return "missing";
}

}  // namespace

std::string quote(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

std::string shellQuote(const std::string& word) {
  const bool plain = !word.empty() && word.find_first_not_of(
                                          "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ"
                                          "0123456789_-./=:,+@%") == std::string::npos;
  return plain ? word : quote(word);
}

std::string datasetChecksum(const std::string& path) {
  if (fs::is_regular_file(path)) return hex64(fnv1a64File(path));
  if (!fs::is_directory(path)) throw InputError(path, "no such dataset (a EuRoC folder, a ROS1 bag or a ROS 2 bag)");
  std::uint64_t h = kFnv1a64Offset;
  if (fs::is_regular_file(fs::path(path) / "metadata.yaml")) {  // a ROS 2 bag folder: every file in it
    std::vector<fs::path> files;
    for (const auto& e : fs::directory_iterator(path))
      if (e.is_regular_file()) files.push_back(e.path());
    std::sort(files.begin(), files.end());
    for (const fs::path& p : files) h = fnv1a64File(p.string(), fnv1a64(p.filename().string(), h));
    return hex64(h);
  }
  for (const char* f : {"meta.json", "mav0/imu0/data.csv", "mav0/cam0/data.csv", "mav0/cam1/data.csv",
                        "mav0/state_groundtruth_estimate0/data.csv"}) {
    const fs::path p = fs::path(path) / f;
    if (fs::exists(p)) h = fnv1a64File(p.string(), fnv1a64(f, h));
  }
  return hex64(h);
}

void checksumInputs(std::vector<Job>& jobs) {
  std::map<std::string, std::string> configs, datasets;
  for (Job& j : jobs) {
    if (!configs.count(j.config)) configs[j.config] = pipeline::configChecksum(loadConfig(j.config));
    if (!datasets.count(j.dataset)) datasets[j.dataset] = datasetChecksum(j.dataset);
    j.config_fnv1a64 = configs[j.config];
    j.dataset_fnv1a64 = datasets[j.dataset];
  }
}

std::string jobCommand(const Job& j, const fs::path& out, const std::string& exe, int threads, bool skip_finished) {
  const fs::path run = out / "runs" / j.name;
  return (skip_finished ? "[ -f " + quote((run / "stats.json").string()) + " ] || " : std::string()) + quote(exe) +
         " run --config " + quote(j.config) + " --dataset " + quote(j.dataset) + " --out " + quote(run.string()) +
         " --mode " + j.mode + " --threads " + std::to_string(threads) + " > " + quote(run.string() + ".log") + " 2>&1";
}

void writeSweep(const fs::path& out, const Sweep& s) {
  nlohmann::json jobs = nlohmann::json::array();
  for (const Job& j : s.jobs) jobs.push_back(jobJson(j));
  const nlohmann::json v = {{"format", kFormat}, {"version", kVersion},  {"suite", s.suite},
                            {"seeds", s.seeds},  {"commit", s.commit},   {"threads", s.threads},
                            {"modes", s.modes},  {"columns", s.columns}, {"jobs", jobs}};
  std::ofstream f(out / "bench.json");
  f << v.dump(1) << "\n";
  if (!f) throw InputError((out / "bench.json").string(), "cannot be written");
}

Sweep readSweep(const fs::path& dir) {
  const fs::path p = dir / "bench.json";
  std::ifstream in(p);
  if (!in) throw InputError(p.string(), "no benchmark here (bench.json is written by idyvins bench and bench --plan)");
  Sweep s;
  try {
    const nlohmann::json v = nlohmann::json::parse(in);
    if (v.value("format", std::string()) != kFormat) throw InputError(p.string(), "not an idyvins bench.json");
    if (v.value("version", 0) != kVersion)
      throw InputError(p.string(), "version " + v.at("version").dump() + ", this idyvins reads version 1");
    s.suite = v.at("suite");
    s.seeds = v.at("seeds");
    s.commit = v.at("commit");
    s.threads = v.at("threads");
    s.modes = v.at("modes").get<std::vector<std::string>>();
    s.columns = v.at("columns").get<std::vector<std::string>>();
    for (const auto& j : v.at("jobs")) s.jobs.push_back(jobFromJson(j));
  } catch (const nlohmann::json::exception& e) {
    throw InputError(p.string(), std::string("damaged: ") + e.what());
  }
  return s;
}

void writePlan(const std::string& file, const Sweep& s, const fs::path& out, const std::string& exe) {
  std::ofstream f(file);
  for (const Job& j : s.jobs)
    f << jobCommand(j, out, exe, s.threads, true) << "  # " << j.name << " config_fnv1a64=" << j.config_fnv1a64
      << " dataset_fnv1a64=" << j.dataset_fnv1a64 << "\n";
  if (!f) throw InputError(file, "cannot be written");
}

std::vector<JobResult> findResults(const Sweep& s, const std::vector<fs::path>& dirs) {
  std::vector<JobResult> results;
  for (const Job& j : s.jobs) {
    JobResult r;
    for (const fs::path& d : dirs) {
      const fs::path stats = d / "runs" / j.name / "stats.json";
      if (!fs::exists(stats)) continue;
      std::ifstream in(stats);
      try {
        r.summary = nlohmann::json::parse(in).at("summary");
      } catch (const nlohmann::json::exception&) {
        throw InputError(stats.string(), "damaged (not a finished run's stats.json)");
      }
      r.folder = (d / "runs" / j.name).string();
      break;
    }
    if (r.summary.is_null()) {
      r.problem = "missing";
      for (std::size_t k = 0; k < dirs.size() && r.problem == "missing"; ++k) r.problem = whyMissing(dirs[k], j.name);
    } else {
      const std::string commit = r.summary.contains("build") ? r.summary["build"].value("commit", "") : "";
      if (commit != s.commit)
        throw InputError(r.folder, "made by commit " + (commit.empty() ? std::string("unknown") : commit) +
                                       ", the sweep's is " + s.commit + ": mixed commits are not collected");
      if (r.summary.value("config_fnv1a64", std::string()) != j.config_fnv1a64)
        throw InputError(r.folder, "ran with another config (config_fnv1a64 " +
                                       r.summary.value("config_fnv1a64", std::string("none")) + ", the plan's " +
                                       j.config_fnv1a64 + "): mixed configs are not collected");
      if (r.summary.value("partial", false)) r.problem = "partial (stopped by a signal): delete " + r.folder;
    }
    results.push_back(std::move(r));
  }
  return results;
}

nlohmann::json withoutTiming(const nlohmann::json& summary, nlohmann::json& timing) {
  if (!summary.is_object()) return summary;
  nlohmann::json kept = nlohmann::json::object();
  for (auto it = summary.begin(); it != summary.end(); ++it) {
    if (isTiming(it.key())) {
      timing[it.key()] = it.value();
    } else if (it.value().is_object()) {
      nlohmann::json sub = nlohmann::json::object();
      kept[it.key()] = withoutTiming(it.value(), sub);
      if (!sub.empty()) timing[it.key()] = sub;
    } else {
      kept[it.key()] = it.value();
    }
  }
  return kept;
}

std::string oneCameraConfig(const std::string& config, const fs::path& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw InputError(dir.string(), "cannot create folder: " + ec.message());
  for (const auto& e : fs::directory_iterator(fs::path(config).parent_path()))
    if (e.is_regular_file()) fs::copy_file(e.path(), dir / e.path().filename(), fs::copy_options::overwrite_existing);
  std::ifstream in(config);
  std::stringstream text;
  text << in.rdbuf();
  static const std::regex key("^num_of_cam:.*$", std::regex::multiline);
  if (!std::regex_search(text.str(), key)) throw InputError(config, "no num_of_cam key to set to 1 (--cameras mono)");
  const fs::path copy = dir / fs::path(config).filename();
  std::ofstream(copy) << std::regex_replace(text.str(), key, "num_of_cam: 1");
  return copy.string();
}

}  // namespace idyvins::app
