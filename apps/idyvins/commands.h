#pragma once
// Subcommands of the `idyvins` command line. Each registers itself on the app
// and returns its exit code through the callback it installs.

#include <CLI/CLI.hpp>
#include <string>

#include "config/config.h"

namespace idyvins::app {

/// Exit codes shared by all subcommands.
/// kNoResult: the run finished but its poses cover less than pipeline::kMinPoseShare of its
/// frames (never initialized, or lost); its files are written for inspection.
enum ExitCode : int { kOk = 0, kInputError = 1, kUsageError = 2, kInternalError = 3, kNoResult = 4 };

/// `idyvins info DATASET [--config CFG] [--json]`.
void registerInfo(CLI::App& app, int& exit_code);

/// `idyvins simulate --scene S --level L --seed N --duration T --out DIR`.
void registerSimulate(CLI::App& app, int& exit_code);

/// `idyvins eval --gt GT --est EST [--align ...] [--rpe 1,5,10] [--json]`.
void registerEval(CLI::App& app, int& exit_code);

/// `idyvins track --config CFG --dataset DIR [--mode ...] [--save-tracks DIR]`.
void registerTrack(CLI::App& app, int& exit_code);

/// `idyvins run --config CFG --dataset DIR --out OUT [--mode ...]`; `command_line` (filled before
/// parsing) goes into OUT/run.json.
void registerRun(CLI::App& app, int& exit_code, const std::string& command_line);

/// `idyvins report OUT [OUT2 ...] [--html FILE]`: one offline HTML page of one or several runs.
void registerReport(CLI::App& app, int& exit_code);

/// A word as a POSIX shell reads it back (single quotes where needed).
std::string shellQuote(const std::string& word);

/// `idyvins convert BAG OUT [--config CFG] [--groundtruth-topic T]`.
void registerConvert(CLI::App& app, int& exit_code);

/// `idyvins bench --suite standard --out DIR [--seeds 1,2,3] [--ablations]`.
void registerBench(CLI::App& app, int& exit_code);
/// `idyvins perturb`: a EuRoC folder with one fault (dropouts, time jumps, bad images, IMU spikes).
void registerPerturb(CLI::App& app, int& exit_code);

}  // namespace idyvins::app
