// `idyvins bench`: the paper's Tables I and II (and the dynamic-landmark figures) in one
// command: simulate (or reuse) the standard set, run every mode in parallel, evaluate.

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "bench_page.h"
#include "bench_sweep.h"
#include "commands.h"
#include "config/config.h"
#include "core/build_info.h"
#include "core/error.h"
#include "io/output_folder.h"
#include "progress.h"

namespace fs = std::filesystem;

namespace idyvins::app {
namespace {

struct BenchArgs {
  std::string suite = "standard", out, seeds = "1", data, modes, config = IDYVINS_VIODE_CONFIG;
  std::string realism = "none", cameras = "stereo";
  double duration = 60.0;
  bool ablations = false;
  bool reuse_runs = false;
  bool force = false;                ///< --force: an --out holding other files (none is removed)
  std::string plan;                  ///< --plan FILE: write the jobs, run none
  std::vector<std::string> collect;  ///< --collect DIR...: tables from finished job folders
  int jobs = 2;
  int run_threads = 1;
};

std::string self() {
  char buf[4096];
  const ssize_t n = readlink("/proc/self/exe", buf, sizeof(buf) - 1);
  if (n <= 0) throw std::runtime_error("cannot locate the idyvins executable");
  buf[n] = 0;
  return buf;
}

/// ATE, or NaN for a failure (no output, not initialized, or ATE > 10 % of the path: diverged).
double ateOf(const nlohmann::json& s) {
  if (s.is_null() || !s.contains("ate_rmse_m")) return NAN;
  const double ate = s["ate_rmse_m"], path = s["path_length_m"];
  return ate > 0.1 * path ? NAN : ate;
}

/// A field of a run that did not fail (ateOf), or NaN.
double fieldOf(const nlohmann::json& s, const char* key) {
  if (std::isnan(ateOf(s)) || !s.contains(key) || !s[key].is_number()) return NAN;
  return s[key].get<double>();
}

std::string fmt(double v, int digits = 3) {
  if (std::isnan(v)) return "x";
  char b[32];
  std::snprintf(b, sizeof(b), "%.*f", digits, v);
  return b;
}

std::vector<int> parseSeeds(const std::string& text) {
  std::vector<int> seeds;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    try {
      seeds.push_back(std::stoi(item));
    } catch (const std::exception&) {
      throw CLI::ValidationError("--seeds", "expected integers like 1,2,3, got '" + item + "'");
    }
  }
  return seeds;
}

std::vector<std::string> parseModes(const std::string& text) {
  std::vector<std::string> modes;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    Mode m;
    if (!parseMode(item, m)) throw CLI::ValidationError("--modes", "expected " + modeNames() + ", got '" + item + "'");
    modes.push_back(item);
  }
  if (std::find(modes.begin(), modes.end(), "baseline") == modes.end())
    throw CLI::ValidationError("--modes", "the tables compare with baseline: include it");
  return modes;
}

const std::vector<std::string> kScenes = {"city", "parking_lot"}, kLevels = {"none", "low", "mid", "high"};

/// A render's config from before the simulator wrote only changed keys pins every key at the
/// defaults of its day: said once per sequence, on stderr (the run uses it as it is).
void warnIfConfigPinsEveryKey(const fs::path& config) {
  if (!fs::exists(config) || savedWithChangedKeysOnly(config.string())) return;
  std::fprintf(stderr,
               "warning: %s sets every key (rendered by an earlier version): it keeps that day's defaults; "
               "render it again, or delete the lines of the keys whose default should apply\n",
               config.string().c_str());
}

/// The suite's datasets (name, folder), simulated where missing (each simulation uses both cores).
std::vector<std::pair<std::string, std::string>> simulateMissing(const BenchArgs& a, const std::string& exe,
                                                                 const fs::path& data, const fs::path& runs) {
  std::vector<std::pair<std::string, std::string>> sequences;
  const std::string family = a.suite == "validation" ? "validation" : "standard";
  for (int seed : parseSeeds(a.seeds))
    for (const auto& scene : kScenes)
      for (const auto& level : kLevels) {
        const std::string name = scene + "_" + level + "_s" + std::to_string(seed);
        const fs::path ds = data / name;
        sequences.emplace_back(name, ds.string());
        if (fs::exists(ds / "meta.json")) {  // reuse it if it was simulated with the same realism
          std::ifstream in(ds / "meta.json");
          nlohmann::json meta;
          try {
            in >> meta;
          } catch (const std::exception&) {
            throw InputError((ds / "meta.json").string(), "not valid JSON (delete the folder to simulate it again)");
          }
          const std::string had = meta.value("realism", std::string("none"));
          if (had != a.realism)
            throw InputError(ds.string(), "simulated with --realism " + had + ", the benchmark asks for " + a.realism +
                                              ": use another --data folder");
          const std::string had_family = meta.value("family", std::string("standard"));
          if (had_family != family)
            throw InputError(ds.string(), "simulated with --family " + had_family + ", the " + a.suite +
                                              " suite needs --family " + family + ": use another --data folder");
          warnIfConfigPinsEveryKey(ds / "config" / "sim_stereo_imu_config.yaml");
          continue;
        }
        std::printf("simulating %s\n", name.c_str());
        std::fflush(stdout);
        const std::string cmd = quote(exe) + " simulate --scene " + scene + " --level " + level + " --seed " +
                                std::to_string(seed) + " --duration " + std::to_string(a.duration) + " --realism " +
                                a.realism + " --family " + family + " --out " + quote(ds.string()) + " > " +
                                quote((runs / (name + "_simulate.log")).string()) + " 2>&1";
        if (std::system(cmd.c_str()) != 0) throw InputError(ds.string(), "simulation failed (see its log in runs/)");
      }
  return sequences;
}

/// Runs every job (`idyvins run` in a child process), `jobs` at a time, with a progress bar;
/// with --reuse-runs, jobs whose folder has a stats.json are kept.
void runJobs(const std::vector<Job>& jobs, const BenchArgs& a, const std::string& exe, const fs::path& out) {
  std::atomic<std::size_t> next{0}, done{0};
  auto worker = [&] {
    for (std::size_t k = next++; k < jobs.size(); k = next++) {
      const std::string cmd = jobCommand(jobs[k], out, exe, a.run_threads, a.reuse_runs);
      (void)std::system(cmd.c_str());  // a failed run is reported as x in the tables
      ++done;
    }
  };
  ProgressBar bar("bench: " + std::to_string(jobs.size()) + " runs", jobs.size(), "runs");
  std::vector<std::thread> pool;
  for (int i = 0; i < std::max(1, a.jobs); ++i) pool.emplace_back(worker);
  while (done < jobs.size()) {
    bar.update(done);
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
  }
  for (auto& t : pool) t.join();
  bar.update(done);
  bar.finish();
}

/// The runs' summaries, grouped the ways the tables need them.
struct Collected {
  nlohmann::json results = nlohmann::json::array();  ///< results.json: what does not depend on the machine
  nlohmann::json timing = nlohmann::json::array();   ///< timing.json: the rest
  std::map<std::string, std::map<std::string, std::vector<double>>> ate;  ///< scene_level -> mode -> per seed
  std::map<std::string, std::map<std::string, std::vector<double>>> ate_sim3, scale_error;  ///< the same
  std::map<std::string, std::map<std::string, std::vector<nlohmann::json>>> by_level;  ///< level -> mode -> summaries
};

Collected collect(const Sweep& sweep, const std::vector<JobResult>& found) {
  Collected c;
  for (std::size_t k = 0; k < sweep.jobs.size(); ++k) {
    const Job& j = sweep.jobs[k];
    const nlohmann::json& s = found[k].problem.empty() ? found[k].summary : nlohmann::json();
    nlohmann::json timing = nlohmann::json::object();
    const std::string run = "runs/" + j.name;
    c.results.push_back({{"sequence", j.sequence},
                         {"mode", j.mode},
                         {"dataset", j.dataset},
                         {"run", run},
                         {"summary", withoutTiming(s, timing)}});
    c.timing.push_back({{"sequence", j.sequence}, {"mode", j.mode}, {"run", run}, {"timing", timing}});
    c.ate[j.group][j.mode].push_back(ateOf(s));
    c.ate_sim3[j.group][j.mode].push_back(fieldOf(s, "ate_sim3_rmse_m"));
    c.scale_error[j.group][j.mode].push_back(fieldOf(s, "scale_error"));
    if (!s.is_null()) c.by_level[j.level][j.mode].push_back(s);
  }
  return c;
}

double meanOrNan(const std::vector<double>& v) {
  double sum = 0;
  for (double x : v) {
    if (std::isnan(x)) return NAN;
    sum += x;
  }
  return v.empty() ? static_cast<double>(NAN) : sum / v.size();
}

void tableHeader(std::ostringstream& t, const std::vector<std::string>& columns) {
  t << "| mode |";
  for (const auto& c : columns) t << " " << c << " |";
  t << "\n| --- |";
  for (std::size_t i = 0; i < columns.size(); ++i) t << " --- |";
  t << "\n";
}

/// Table 1: ATE RMSE (m), mean over seeds, best per column in bold, failures x; then ratios
/// to the baseline (seg, ground-truth masks, is what a perfect detector would give).
std::string table1(const Collected& c, const std::vector<std::string>& modes, const std::string& seeds,
                   const std::vector<std::string>& columns) {
  // Mean over seeds of one column and mode of a per-seed table (NaN when any seed failed).
  auto mean = [&](const auto& by_group, const std::string& col, const std::string& mode) {
    const auto it = by_group.find(col);
    if (it == by_group.end() || !it->second.count(mode)) return static_cast<double>(NAN);
    return meanOrNan(it->second.at(mode));
  };
  auto ate = [&](const std::string& col, const std::string& mode) { return mean(c.ate, col, mode); };
  std::ostringstream t1;
  t1 << "ATE RMSE (m, SE3 alignment)" << (seeds.empty() ? std::string() : ", mean over seeds " + seeds)
     << "; x = failure (no estimate, or ATE > 10 % of path).\n\n";
  tableHeader(t1, columns);
  for (const auto& mode : modes) {
    t1 << "| " << mode << " |";
    for (const auto& col : columns) {
      const double v = ate(col, mode);
      double best = INFINITY;
      for (const auto& m : modes)
        if (!std::isnan(ate(col, m))) best = std::min(best, ate(col, m));
      t1 << " " << (!std::isnan(v) && v == best ? "**" + fmt(v) + "**" : fmt(v)) << " |";
    }
    t1 << "\n";
  }
  t1 << "\nATE relative to baseline (ratio of the means over seeds; < 1 is better than the baseline).\n\n";
  tableHeader(t1, columns);
  for (const auto& mode : modes) {
    if (mode == "baseline") continue;
    t1 << "| " << mode << " / baseline |";
    for (const auto& col : columns) {
      const double q = ate(col, mode) / ate(col, "baseline");
      t1 << " " << (std::isnan(q) ? std::string("x") : fmt(q, 2) + "x") << " |";
    }
    t1 << "\n";
  }
  // The same runs aligned with a similarity (evo's -as): the error left once the scale is
  // free, and the scale error 1/s − 1 (positive: the path is too long).
  t1 << "\nATE RMSE (m) after a similarity alignment (sim3, evo's -as), and in brackets the scale error "
        "1/s - 1 (%, positive: the estimated path is too long)"
     << (seeds.empty() ? std::string() : ", means over seeds " + seeds) << ".\n\n";
  tableHeader(t1, columns);
  for (const auto& mode : modes) {
    t1 << "| " << mode << " |";
    for (const auto& col : columns) {
      const double v = mean(c.ate_sim3, col, mode), e = mean(c.scale_error, col, mode);
      char pct[32];
      std::snprintf(pct, sizeof(pct), " (%+.2f %%)", 100.0 * e);
      t1 << " " << fmt(v) << (std::isnan(e) ? std::string() : pct) << " |";
    }
    t1 << "\n";
  }
  return t1.str();
}

/// Table 2: timing per level, mean over both scenes and all seeds.
std::string table2(const Collected& c, const std::vector<std::string>& modes) {
  std::ostringstream t2;
  t2 << "Mean per frame over both scenes and all seeds: tracking ms + dynamic preprocessing ms (the mode's filter), "
        "and optimization ms.\n\n| mode | tracking+filter none | low | mid | high | optimization none | low | mid | "
        "high |\n"
        "| --- | --- | --- | --- | --- | --- | --- | --- | --- |\n";
  static const std::vector<nlohmann::json> kNone;
  for (const auto& mode : modes) {
    t2 << "| " << mode << " |";
    for (int part = 0; part < 2; ++part)
      for (const auto& level : kLevels) {
        double tr = 0, fi = 0, op = 0;
        const auto lv = c.by_level.find(level);
        const auto& v = lv != c.by_level.end() && lv->second.count(mode) ? lv->second.at(mode) : kNone;
        for (const auto& s : v) {
          tr += s["mean_tracking_ms"].get<double>();
          fi += s["mean_filter_ms"].get<double>();
          op += s["mean_optimization_ms"].get<double>();
        }
        const double n = std::max<std::size_t>(v.size(), 1);
        t2 << " " << (part == 0 ? fmt(tr / n, 2) + "+" + fmt(fi / n, 3) : fmt(op / n, 2)) << " |";
      }
    t2 << "\n";
  }
  return t2.str();
}

/// Classification and map cleanliness per sequence and mode.
std::string dynamicTable(const nlohmann::json& results) {
  std::ostringstream td;
  td << "Against the simulator's masks, per tracked observation; an observation counts as flagged when its track "
        "was eliminated or confirmed dynamic. Moving flagged: share of observations on moving objects flagged (all; in "
        "brackets: of tracks seen in at least two frames). Static flagged: share of static observations flagged. "
        "Static "
        "map on moving: share of static-map points whose track was mostly on moving objects (in brackets: ever on "
        "one).\n\n| sequence | mode | moving flagged | static flagged | F1 | static map on moving | static map "
        "points |\n| --- | --- | --- | --- | --- | --- | --- |\n";
  for (const nlohmann::json& r : results) {
    const auto& s = r["summary"];
    if (s.is_null() || s["classification"].is_null()) continue;
    const auto& c = s["classification"];
    td << "| " << r["sequence"].get<std::string>() << " | " << r["mode"].get<std::string>() << " | "
       << fmt(100 * c["moving_detected_fraction"].get<double>(), 1) << " % ("
       << fmt(100 * c.value("moving_detected_fraction_tracked", 0.0), 1) << " %) | "
       << fmt(100 * c["static_flagged_fraction"].get<double>(), 2) << " % | " << fmt(c["f1"].get<double>(), 3) << " | "
       << fmt(100 * c["static_map_fraction_on_moving"].get<double>(), 2) << " % ("
       << fmt(100 * c.value("static_map_fraction_ever_on_moving", 0.0), 2) << " %) | " << s["map_static_points"]
       << " |\n";
  }
  return td.str();
}

/// Plots (Debian's python3-matplotlib), optional.
void plots(const fs::path& out) {
  const std::string script = std::string(IDYVINS_SOURCE_DIR) + "/scripts/bench_plots.py";
  if (!fs::exists(script) || !fs::exists("/usr/bin/python3")) return;
  const std::string cmd = "/usr/bin/python3 " + quote(script) + " " + quote(out.string()) + " > " +
                          quote((out / "plots.log").string()) + " 2>&1";
  if (std::system(cmd.c_str()) != 0) std::printf("plots failed, see %s\n", (out / "plots.log").c_str());
}

const std::vector<std::string> kViodeEnvironments = {"city_day", "city_night", "parking_lot"};
const std::vector<std::string> kViodeBags = {"0_none", "1_low", "2_mid", "3_high"};

/// VIODE's bags under `dir` (<environment>/<k>_<level>.bag, as published), each with a
/// config: a copy of `base`'s folder naming the environment's vehicle table.
std::vector<Job> viodeJobs(const BenchArgs& a, const fs::path& dir, const fs::path& out,
                           const std::vector<std::string>& modes, std::vector<std::string>& columns) {
  const fs::path base(a.config);
  if (!fs::is_regular_file(base)) throw InputError(a.config, "no such config (set --config)");
  std::vector<Job> jobs;
  for (const auto& env : kViodeEnvironments) {
    bool any = false;
    for (const auto& name : kViodeBags) {
      const fs::path bag = dir / env / (name + ".bag");
      if (!fs::is_regular_file(bag)) continue;
      if (!any) {  // the environment's config folder
        const fs::path cfg_dir = out / "configs" / env;
        fs::create_directories(cfg_dir);
        for (const auto& f : fs::directory_iterator(base.parent_path()))
          if (f.is_regular_file())
            fs::copy_file(f.path(), cfg_dir / f.path().filename(), fs::copy_options::overwrite_existing);
        // The environment's vehicle table replaces the base config's.
        std::ifstream in(base);
        std::string text, line;
        while (std::getline(in, line))
          if (line.rfind("segmentation_vehicle_ids:", 0) != 0) text += line + "\n";
        std::ofstream(cfg_dir / base.filename())
            << text << "segmentation_vehicle_ids: \"vehicle_ids_" << env << ".txt\"\n";
        any = true;
      }
      const std::string level = name.substr(2), group = env + "_" + level;
      if (std::find(columns.begin(), columns.end(), group) == columns.end()) columns.push_back(group);
      for (const auto& mode : modes)
        jobs.push_back({group, group, level, mode, bag.string(), (out / "configs" / env / base.filename()).string(),
                        group + "_" + mode, "", ""});
    }
  }
  if (jobs.empty())
    throw InputError(dir.string(),
                     "holds no VIODE bag (expected <environment>/<k>_<level>.bag with environment "
                     "city_day, city_night or parking_lot and k_level 0_none, 1_low, 2_mid or 3_high)");
  return jobs;
}

/// Writes the tables, results.json, timing.json and plots of a sweep's results into `out`;
/// prints the jobs without a result. Returns how many there are.
std::size_t writeOutputs(const fs::path& out, const Sweep& sweep, const std::vector<JobResult>& found) {
  const Collected c = collect(sweep, found);
  std::ofstream(out / "results.json") << c.results.dump(1) << "\n";
  std::ofstream(out / "timing.json") << c.timing.dump(1) << "\n";
  const std::string t1 = table1(c, sweep.modes, sweep.suite == "viode" ? "" : sweep.seeds, sweep.columns);
  const std::string t2 = table2(c, sweep.modes);
  std::ofstream(out / "table1.md") << t1;
  std::ofstream(out / "table2.md") << t2;
  const std::string td = dynamicTable(c.results);
  std::ofstream(out / "dynamic.md") << td;
  plots(out);
  writeBenchPages(out, sweep, found, {t1, t2, td});
  std::printf("%s\n%s\nwrote %s/{table1.md,table2.md,dynamic.md,results.json,timing.json,plots/,report.html,pages/}\n",
              t1.c_str(), t2.c_str(), out.c_str());
  std::size_t problems = 0;
  for (std::size_t k = 0; k < found.size(); ++k)
    if (!found[k].problem.empty()) {
      std::fprintf(stderr, "job %s: %s\n", sweep.jobs[k].name.c_str(), found[k].problem.c_str());
      ++problems;
    }
  return problems;
}

/// The sweep's jobs (simulating the suite's missing datasets first: they are the jobs' inputs).
Sweep planSweep(const BenchArgs& a, const std::string& exe, const fs::path& out) {
  const fs::path data = a.data.empty() ? out / "data" : fs::absolute(a.data), runs = out / "runs";
  std::error_code ec;
  fs::create_directories(runs, ec);
  fs::create_directories(data, ec);
  if (ec) throw InputError(a.out, "cannot create folder: " + ec.message());
  Sweep sw;
  sw.suite = a.suite;
  sw.seeds = a.suite == "viode" ? "" : a.seeds;
  sw.commit = buildCommit();
  sw.threads = a.run_threads;
  sw.modes = {"baseline", "ransac", "seg", "idy"};
  if (a.ablations) sw.modes.insert(sw.modes.end(), {"idy-pre", "idy-ba"});
  if (!a.modes.empty()) sw.modes = parseModes(a.modes);
  if (a.suite == "viode") {
    sw.jobs = viodeJobs(a, data, out, sw.modes, sw.columns);
  } else {
    for (const auto& scene : kScenes)
      for (const auto& level : kLevels) sw.columns.push_back(scene + "_" + level);
    for (const auto& [name, ds] : simulateMissing(a, exe, data, runs)) {
      const std::string group = name.substr(0, name.rfind("_s")), level = group.substr(group.rfind('_') + 1);
      for (const auto& mode : sw.modes)
        sw.jobs.push_back(
            {name, group, level, mode, ds, ds + "/config/sim_stereo_imu_config.yaml", name + "_" + mode, "", ""});
    }
  }
  if (a.cameras == "mono")
    for (Job& j : sw.jobs) j.config = oneCameraConfig(j.config, out / "configs_mono" / j.sequence);
  checksumInputs(sw.jobs);
  return sw;
}

/// --out: new, empty or an earlier bench's (its bench.json there); bench never removes a file, but a
/// folder of other files is refused (its tables, runs/ and data/ would land among them).
void checkBenchFolder(const BenchArgs& a) {
  io::OutputFolderOptions o;
  o.tool = "bench";
  o.inputs = {a.config};
  if (a.suite == "viode") o.inputs.push_back(a.data);
  io::checkApartFromInputs(a.out, o.inputs);
  std::error_code ec;
  if (fs::exists(a.out, ec) && !fs::is_directory(a.out, ec)) throw InputError(a.out, "exists and is not a folder");
  if (a.force || !fs::is_directory(a.out, ec) || fs::exists(fs::path(a.out) / "bench.json", ec)) return;
  bool has_files = false;  // the empty runs/ and data/ a refused bench leaves count as empty
  for (fs::recursive_directory_iterator it(a.out, ec), end; !ec && it != end && !has_files; it.increment(ec))
    has_files = !it->is_directory(ec);
  if (has_files)
    throw InputError(a.out,
                     "holds files of no earlier idyvins bench (no bench.json): name a new or empty folder, or "
                     "pass --force to write beside them (none is removed)");
}

int runBench(const BenchArgs& a) {
  if (a.suite != "standard" && a.suite != "validation" && a.suite != "viode")
    throw CLI::ValidationError("--suite", "expected standard, validation or viode, got '" + a.suite + "'");
  if (a.suite == "viode" && a.data.empty()) throw CLI::ValidationError("--data", "the folder holding VIODE's bags");
  if (a.out.empty()) throw CLI::ValidationError("--out", "the benchmark's output folder is required");
  parseSeeds(a.seeds);  // usage errors before any work
  if (!a.modes.empty()) parseModes(a.modes);
  const std::string exe = self();
  const fs::path out = fs::absolute(a.out);
  checkBenchFolder(a);
  const Sweep sweep = planSweep(a, exe, out);
  writeSweep(out, sweep);
  if (!a.plan.empty()) {
    writePlan(a.plan, sweep, out, exe);
    std::printf(
        "wrote %s: %zu jobs, one shell command per line (run them with e.g. `parallel -j2 < %s`, or a Slurm "
        "array: docs/cli.md#bench-as-independent-jobs), then: idyvins bench --collect %s\n",
        a.plan.c_str(), sweep.jobs.size(), a.plan.c_str(), out.c_str());
    return kOk;
  }
  runJobs(sweep.jobs, a, exe, out);
  writeOutputs(out, sweep, findResults(sweep, {out}));
  return kOk;  // failed runs are x in the tables, as before
}

/// bench --collect DIR...: the tables from the job folders under each DIR/runs (the first DIR's
/// bench.json is the sweep; the others, shards of it, may hold a copy).
int collectBench(const BenchArgs& a) {
  std::vector<fs::path> dirs;
  for (const std::string& d : a.collect) {
    if (!fs::is_directory(d)) throw InputError(d, "no such folder");
    dirs.push_back(fs::absolute(d));
  }
  const Sweep sweep = readSweep(dirs.front());
  for (std::size_t k = 1; k < dirs.size(); ++k)
    if (fs::exists(dirs[k] / "bench.json") && readSweep(dirs[k]).commit != sweep.commit)
      throw InputError((dirs[k] / "bench.json").string(),
                       "planned by another commit than " + (dirs.front() / "bench.json").string());
  const fs::path out = a.out.empty() ? dirs.front() : fs::path(a.out);
  std::error_code ec;
  fs::create_directories(out, ec);
  if (ec) throw InputError(out.string(), "cannot create folder: " + ec.message());
  const std::size_t problems = writeOutputs(out, sweep, findResults(sweep, dirs));
  if (problems == 0) return kOk;
  std::fprintf(stderr, "%zu of %zu jobs have no result (x in the tables): run the plan again to complete them\n",
               problems, sweep.jobs.size());
  return kInputError;
}

}  // namespace

void registerBench(CLI::App& app, int& exit_code) {
  auto a = std::make_shared<BenchArgs>();
  CLI::App* cmd = app.add_subcommand(
      "bench",
      "Run a benchmark suite, every mode (baseline, ransac, seg, idy; --ablations adds idy-pre, idy-ba) in\n"
      "parallel, evaluate, and write OUT/table1.md (ATE, the paper's Table I), OUT/table2.md (timing,\n"
      "Table II), OUT/dynamic.md (classification, map cleanliness), OUT/results.json and OUT/plots/.\n"
      "standard: simulate (or reuse) city and parking_lot x none/low/mid/high for the given seeds.\n"
      "validation: the same grid from the family no default is tuned on (simulate --family validation:\n"
      "EuRoC's intrinsics, VINS-Fusion's EuRoC IMU keys, other materials, a handheld trajectory).\n"
      "viode: VIODE's bags as published under --data: <environment>/<k>_<level>.bag with environment\n"
      "city_day, city_night, parking_lot and 0_none, 1_low, 2_mid, 3_high (masks from /cam0/segmentation).");
  cmd->add_option("--suite", a->suite, "benchmark suite: standard (default), validation or viode");
  cmd->add_option("--config", a->config,
                  "viode: the config (its folder is copied per environment with that environment's vehicle\n"
                  "table; default: the source tree's config/viode/viode_stereo_imu_config.yaml)");
  cmd->add_option("-o,--out", a->out,
                  "output folder (required, except with --collect): new, empty or an earlier bench's; one holding\n"
                  "other files is refused");
  cmd->add_flag("--force", a->force, "write into an --out holding files bench did not write (none is removed)");
  cmd->add_option("--seeds", a->seeds, "comma-separated seeds (default 1)");
  cmd->add_option("--duration", a->duration, "seconds per sequence (default 60)");
  cmd->add_option("--realism", a->realism,
                  "standard, validation: camera realism of the simulated sequences, none (default) or euroc (see\n"
                  "simulate --help); keep each realism in its own --data folder")
      ->check(CLI::IsMember({"none", "euroc"}));
  cmd->add_option("--data", a->data,
                  "standard, validation: where the simulated datasets live (default OUT/data); viode: VIODE's folder");
  cmd->add_option("-j,--jobs", a->jobs, "runs in parallel (default 2)")->check(CLI::Range(1, 64));
  cmd->add_option("--cameras", a->cameras,
                  "stereo (default): the suite's rig; mono: every run with num_of_cam 1 (cam0 of the same\n"
                  "files; each config copied under OUT/configs_mono/<sequence>/)")
      ->check(CLI::IsMember({"stereo", "mono"}));
  cmd->add_flag("--ablations", a->ablations, "also run idy-pre and idy-ba");
  cmd->add_option("--threads", a->run_threads,
                  "threads of each run: 1 (default) or 2 (pipelined runs, `run --threads 2`; use --jobs 1\n"
                  "so that runs do not share the cores)")
      ->check(CLI::Range(1, 2));
  cmd->add_option("--modes", a->modes,
                  "comma-separated modes to run instead (must include baseline), e.g. baseline,ransac,idy");
  cmd->add_flag("--reuse-runs", a->reuse_runs,
                "keep runs that already have OUT/runs/<sequence>_<mode>/stats.json (resume an interrupted\n"
                "benchmark, or re-run only the modes whose run folders were deleted)");
  cmd->add_option("--plan", a->plan,
                  "write the sweep as independent jobs to this file instead of running them: one shell command per\n"
                  "line (each skips itself when its run folder is finished), the job's name and its inputs' checksums\n"
                  "in a trailing comment; OUT/bench.json describes the sweep. Missing datasets are simulated first.\n"
                  "Run the lines anywhere (GNU parallel, a Slurm array, a Kubernetes Indexed Job), then --collect");
  cmd->add_option(
         "--collect", a->collect,
         "DIR...: write the tables, results.json and plots of a planned sweep from the finished job folders\n"
         "under each DIR/runs (the first DIR holds bench.json; --out defaults to it). Refuses runs of another\n"
         "commit or config; names jobs without a result and exits 1")
      ->expected(1, -1);
  cmd->callback([a, &exit_code] { exit_code = a->collect.empty() ? runBench(*a) : collectBench(*a); });
}

}  // namespace idyvins::app
