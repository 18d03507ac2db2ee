// `idyvins eval`: ATE / RPE of an estimated trajectory against ground truth (evo conventions).

#include <cstdio>
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "commands.h"
#include "core/error.h"
#include "eval/trajectory_metrics.h"
#include "io/open_dataset.h"
#include "io/trajectory_io.h"

namespace idyvins::app {
namespace {

struct EvalArgs {
  std::string gt, est, align = "se3", rpe;
  double max_dt = 0.01;
  bool json = false;
};

nlohmann::json statsJson(const eval::ErrorStats& s) {
  return {{"n", s.n},     {"rmse", s.rmse}, {"mean", s.mean}, {"median", s.median},
          {"std", s.std}, {"min", s.min},   {"max", s.max},   {"sse", s.sse}};
}

std::vector<double> parseDeltas(const std::string& text) {
  std::vector<double> out;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    try {
      std::size_t used = 0;
      const double v = std::stod(item, &used);
      if (used != item.size() || !(v > 0)) throw std::invalid_argument(item);
      out.push_back(v);
    } catch (const std::exception&) {
      throw CLI::ValidationError("--rpe", "expected positive distances in metres like 1,5,10, got '" + item + "'");
    }
  }
  return out;
}

/// What eval computed, for printing.
struct EvalOutcome {
  eval::AlignMode mode;
  eval::AteResult ate;
  std::vector<std::pair<double, eval::ErrorStats>> rpes;
  double path = 0;
  std::size_t ref_poses = 0, est_poses = 0;
};

void printJson(const EvalArgs& a, const EvalOutcome& o) {
  nlohmann::json j = {{"reference", a.gt},
                      {"estimate", a.est},
                      {"align", toString(o.mode)},
                      {"max_dt_s", a.max_dt},
                      {"pairs", o.ate.pairs.size()},
                      {"reference_poses", o.ref_poses},
                      {"estimate_poses", o.est_poses},
                      {"path_length_m", o.path},
                      {"scale", o.ate.alignment.s},
                      {"ate", statsJson(o.ate.stats)},
                      {"rpe", nlohmann::json::array()}};
  for (const auto& [d, s] : o.rpes) j["rpe"].push_back({{"delta_m", d}, {"stats", statsJson(s)}});
  std::cout << j.dump(2) << "\n";
}

void printText(const EvalArgs& a, const EvalOutcome& o) {
  std::printf("reference: %s (%zu poses)\nestimate:  %s (%zu poses)\n", a.gt.c_str(), o.ref_poses, a.est.c_str(),
              o.est_poses);
  std::printf("pairs: %zu (max dt %.3f s), alignment: %s", o.ate.pairs.size(), a.max_dt, toString(o.mode));
  if (o.mode == eval::AlignMode::kSim3) std::printf(" (scale %.6f)", o.ate.alignment.s);
  std::printf(", path length %.3f m\n", o.path);
  const auto row = [](const char* name, const eval::ErrorStats& s) {
    if (s.n == 0) {  // no numbers to show: zeros would read as a perfect result
      std::printf("%-14s n      0  no pairs (the trajectory is shorter than this distance)\n", name);
      return;
    }
    std::printf("%-14s n %6zu  rmse %.6f  mean %.6f  median %.6f  std %.6f  min %.6f  max %.6f\n", name, s.n, s.rmse,
                s.mean, s.median, s.std, s.min, s.max);
  };
  row("ATE (m)", o.ate.stats);
  if (o.path > 0) std::printf("ATE rmse / path length: %.3f %%\n", 100.0 * o.ate.stats.rmse / o.path);
  for (const auto& [d, s] : o.rpes) {
    char name[32];
    std::snprintf(name, sizeof(name), "RPE %gm (m)", d);
    row(name, s);
  }
}

int runEval(const EvalArgs& a) {
  EvalOutcome o;
  if (!eval::parseAlignMode(a.align, o.mode))
    throw CLI::ValidationError("--align", "expected se3|sim3|posyaw|none, got '" + a.align + "'");
  const auto deltas = parseDeltas(a.rpe);
  const auto ref = io::readReference(a.gt);
  const auto est = io::readTrajectory(a.est);
  o.ref_poses = ref.size();
  o.est_poses = est.size();
  try {
    o.ate = eval::computeAte(ref, est, o.mode, fromSeconds(a.max_dt));
  } catch (const std::invalid_argument& e) {
    throw InputError(a.est, std::string(e.what()) + " (max dt " + std::to_string(a.max_dt) + " s)");
  }
  // Associated and aligned copies for RPE (pairs are chosen on the aligned estimate, as evo does).
  std::vector<StampedPose> ref_a, est_a;
  for (const auto& [i, j] : o.ate.pairs) {
    ref_a.push_back(ref[i]);
    StampedPose p = est[j];
    p.p_w_b = o.ate.alignment.apply(p.p_w_b);
    p.q_w_b = Eigen::Quaterniond(o.ate.alignment.R * p.q_w_b.toRotationMatrix());
    est_a.push_back(p);
  }
  for (double d : deltas) o.rpes.emplace_back(d, eval::computeRpe(ref_a, est_a, d));
  o.path = eval::pathLength(ref_a);
  if (a.json)
    printJson(a, o);
  else
    printText(a, o);
  return kOk;
}

}  // namespace

void registerEval(CLI::App& app, int& exit_code) {
  auto a = std::make_shared<EvalArgs>();
  CLI::App* cmd =
      app.add_subcommand("eval",
                         "Absolute (ATE) and relative (RPE) trajectory error of an estimate against a reference,\n"
                         "with evo's conventions: association by nearest time stamp within --max-dt from the\n"
                         "shorter trajectory, Umeyama alignment of the estimate onto the reference, RPE over\n"
                         "path-length deltas with consecutive pairs. Files: TUM (t x y z qx qy qz qw) or EuRoC CSV\n"
                         "(also the 17-column ground truth); --gt may be a EuRoC dataset folder.");
  cmd->add_option("--gt", a->gt, "reference trajectory (TUM, EuRoC CSV) or EuRoC folder")->required();
  cmd->add_option("--est", a->est, "estimated trajectory (TUM or EuRoC CSV)")->required();
  cmd->add_option("--align", a->align, "se3 (default) | sim3 | posyaw (4-DoF) | none");
  cmd->add_option("--max-dt", a->max_dt, "max time difference for association, seconds");
  cmd->add_option("--rpe", a->rpe, "RPE path-length deltas in metres, comma separated (e.g. 1,5,10)");
  cmd->add_flag("--json", a->json, "print results as JSON");
  cmd->callback([a, &exit_code] { exit_code = runEval(*a); });
}

}  // namespace idyvins::app
