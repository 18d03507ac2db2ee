#pragma once
// A benchmark sweep as independent jobs (idyvins bench --plan / --collect): the jobs with the
// checksums of their inputs (OUT/bench.json), the plan file (one shell command per line, for
// GNU parallel, a Slurm array or a Kubernetes Indexed Job), and gathering finished job folders.

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace idyvins::app {

/// One run: a sequence (in a table column `group` at traffic `level`) in one mode; its folder
/// is OUT/runs/<name>.
struct Job {
  std::string sequence, group, level, mode, dataset, config, name;
  std::string config_fnv1a64, dataset_fnv1a64;  ///< the inputs' checksums (filled by checksumInputs)
};

struct Sweep {
  std::string suite, seeds, commit;  ///< commit: of the idyvins that planned it
  int threads = 1;                   ///< threads of each run
  std::vector<std::string> modes, columns;
  std::vector<Job> jobs;
};

/// `s` in single quotes, for the shell commands bench writes and runs.
std::string quote(const std::string& s);

/// FNV-1a 64 (hex) of a dataset: a bag's every byte; a folder's index files (meta.json, the IMU,
/// both cameras' and the ground truth's data.csv, those present). Throws InputError.
std::string datasetChecksum(const std::string& path);
/// Fills each job's input checksums (a config is read once per path).
void checksumInputs(std::vector<Job>& jobs);

/// A one-camera copy of `config`: its folder's files copied into `dir`, num_of_cam set to 1 (cam0
/// of the same files); returns the copy's path. Throws InputError when the config has no num_of_cam.
std::string oneCameraConfig(const std::string& config, const std::filesystem::path& dir);

/// The shell command of one job: `idyvins run` into OUT/runs/<name>, its log beside it;
/// skip_finished: preceded by a test that skips it when OUT/runs/<name>/stats.json exists.
std::string jobCommand(const Job& job, const std::filesystem::path& out, const std::string& exe, int threads,
                       bool skip_finished);

/// OUT/bench.json: the sweep with its jobs and their checksums.
void writeSweep(const std::filesystem::path& out, const Sweep& sweep);
/// Reads DIR/bench.json. Throws InputError (missing, damaged, another format).
Sweep readSweep(const std::filesystem::path& dir);
/// The plan: one line per job, the command then `# name config_fnv1a64=... dataset_fnv1a64=...`.
void writePlan(const std::string& file, const Sweep& sweep, const std::filesystem::path& out, const std::string& exe);

/// A job's result found in one of the folders: its stats.json summary, or why there is none.
struct JobResult {
  nlohmann::json summary;  ///< null when missing
  std::string folder;      ///< where it was found ("" if nowhere)
  std::string problem;     ///< "" when finished; else "missing", "failed or killed: see LOG", "partial"
};
/// Each job's folder among dirs' runs/. Throws InputError when a finished job was made by another
/// commit than the sweep's or from a config whose checksum is not the plan's.
std::vector<JobResult> findResults(const Sweep& sweep, const std::vector<std::filesystem::path>& dirs);

/// A run's summary without what depends on the machine and its load (wall time, real-time factor,
/// every "..._ms" figure), which goes to `timing`: what results.json holds, so that the same
/// sweep gives the same results.json wherever its jobs ran.
nlohmann::json withoutTiming(const nlohmann::json& summary, nlohmann::json& timing);

}  // namespace idyvins::app
