#pragma once
// An output folder that never destroys what idyvins did not write. Results are written into a
// staging folder beside it (OUT.partial-PID) and swapped in when complete, so an interrupted run
// never leaves old and new files mixed. Every folder idyvins writes carries a manifest
// (OUT/idyvins_manifest.json: the tool and every file it wrote); only a folder whose files are
// all listed in its manifest is replaced. Anything else is refused before the work starts: a
// folder with other files in it, one that is, holds or lies inside an input, a read-only one.
// With `force` a folder with other files is written into, and still only files a manifest lists
// are removed (a foreign file in the way of an output is moved aside to NAME.orig).

#include <string>
#include <vector>

namespace idyvins::io {

/// The manifest's file name inside an output folder.
inline constexpr const char* kManifestName = "idyvins_manifest.json";

struct OutputFolderOptions {
  std::string tool;                 ///< "run", "simulate", ...: written into the manifest, named in messages
  std::vector<std::string> inputs;  ///< what the command reads: OUT may not be, hold or lie inside one
  bool force = false;               ///< write into a folder with files idyvins did not write (removes none of them)
  /// A folder without a manifest whose top-level entries all have one of these names, and which
  /// holds every name of `legacy_required`, counts as an earlier output of the tool (folders
  /// written before manifests existed).
  std::vector<std::string> legacy_names, legacy_required;
};

/// What a folder holds, judged against its manifest.
struct FolderVerdict {
  bool exists = false, empty = true, is_folder = true, read_only = false;
  std::vector<std::string> ours;     ///< relative paths of files a manifest (or the legacy rule) lists
  std::vector<std::string> foreign;  ///< relative paths of every other file
};

/// Looks at `folder` (recursively, symbolic links not followed). Throws InputError when it cannot
/// be read.
FolderVerdict inspectFolder(const std::string& folder, const OutputFolderOptions& options);

/// Throws InputError when `out` is one of `inputs`, holds one or lies inside one (paths compared
/// after resolving symbolic links and `..`).
void checkApartFromInputs(const std::string& out, const std::vector<std::string>& inputs);

class OutputFolder {
 public:
  /// Validates `out` (see the file comment) and creates the staging folder. Throws InputError
  /// with one line naming the folder and the reason.
  OutputFolder(const std::string& out, OutputFolderOptions options);
  OutputFolder(const OutputFolder&) = delete;
  OutputFolder& operator=(const OutputFolder&) = delete;
  /// A folder not published is removed with everything in it (all of it written by this run).
  ~OutputFolder();

  /// The staging folder: write every output here.
  const std::string& path() const { return staging_; }
  /// The folder the outputs end up in.
  const std::string& finalPath() const { return final_; }
  /// Where to write an extra output file named on the command line (e.g. `--dump-observations`):
  /// inside the output folder it goes into the staging folder (published with it); elsewhere
  /// its folder is created and the file opened once, so a path that cannot be written fails
  /// before the work, not after it. An existing file elsewhere is refused unless `force`.
  std::string extraFile(const std::string& path) const;
  /// The same for an extra output folder (e.g. `--save-map`).
  std::string extraFolder(const std::string& path) const;
  /// Writes the manifest and moves the results into place, replacing the previous output
  /// (only its listed files). Returns the warnings it has (files moved aside, an old folder that
  /// could not be removed whole); throws InputError when the results cannot be moved into place
  /// (the staging folder is then kept, and the message names it).
  std::vector<std::string> publish();

 private:
  bool isOutput(const std::string& p) const;
  bool insideOutput(const std::string& p) const;
  OutputFolderOptions options_;
  std::string final_, staging_;
  bool published_ = false;
};

}  // namespace idyvins::io
