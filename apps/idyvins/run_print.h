#pragma once
// What `idyvins run` prints at the end.

#include <nlohmann/json.hpp>
#include <string>

#include "config/config.h"
#include "io/open_dataset.h"
#include "pipeline/system.h"

namespace idyvins::app {

/// Prints the run's summary (stats.json's "summary", with "last_status"): frames and speed,
/// initialization, time offset, dropped input, timing, resets, ATE, loops, maps, the
/// classification against masks, and the files written into `out`.
void printRunSummary(const nlohmann::json& summary, const std::string& out);

/// Says how a run stopped by `sig` (SIGINT, SIGTERM) after `frames` of `total` frames ended and
/// returns its exit code, 128 + sig. Stopped before the first frame, it wrote nothing: OUT is
/// as it was (the staging folder goes with the run).
int reportRunStop(int sig, std::size_t frames, std::size_t total, const std::string& out);
/// kOk, or kNoResult with the line saying why when the poses cover too few of the frames.
int runResultCode(const pipeline::Result& result, const std::string& out);
/// The config's and the dataset's warnings, one line each on stderr.
void printRunWarnings(const Config& config, const io::OpenedDataset& in);

}  // namespace idyvins::app
