#include "io/output_folder.h"

#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>

#include "core/error.h"

namespace fs = std::filesystem;

namespace idyvins::io {
namespace {

/// `p` made absolute with symbolic links and `..` resolved as far as it exists.
fs::path resolved(const fs::path& p) {
  std::error_code ec;
  fs::path r = fs::weakly_canonical(fs::absolute(p), ec);
  if (ec) throw InputError(p.string(), "cannot resolve the path: " + ec.message());
  if (r.filename().empty()) r = r.parent_path();  // "out/" -> "out"
  return r;
}

/// Whether `inner` is `outer` or lies below it (component-wise).
bool within(const fs::path& inner, const fs::path& outer) {
  auto i = inner.begin(), o = outer.begin();
  for (; o != outer.end(); ++o, ++i)
    if (i == inner.end() || *i != *o) return false;
  return true;
}

/// The manifest's entries (files, and folders with a trailing '/') when it is one of `tool`'s.
bool readManifest(const fs::path& folder, const std::string& tool, std::set<std::string>& entries) {
  std::ifstream in(folder / kManifestName);
  if (!in) return false;
  const nlohmann::json m = nlohmann::json::parse(in, nullptr, /*allow_exceptions=*/false);
  if (!m.is_object() || m.value("tool", std::string()) != tool || !m.contains("entries") || !m["entries"].is_array())
    return false;
  for (const auto& e : m["entries"])
    if (e.is_string()) entries.insert(e.get<std::string>());
  return true;
}

/// Every entry below `folder` (symbolic links not followed): files as relative paths, folders
/// with a trailing '/'.
std::vector<std::string> listEntries(const fs::path& folder) {
  std::vector<std::string> out;
  std::error_code ec;
  fs::recursive_directory_iterator it(folder, fs::directory_options::none, ec), end;
  if (ec) throw InputError(folder.string(), "cannot list the folder: " + ec.message());
  for (; it != end; it.increment(ec)) {
    if (ec) throw InputError(folder.string(), "cannot list the folder: " + ec.message());
    const std::string rel = fs::relative(it->path(), folder, ec).generic_string();
    const bool dir = it->is_directory(ec) && !it->is_symlink(ec);
    out.push_back(dir ? rel + "/" : rel);
  }
  return out;
}

/// Removes the listed entries of `folder` (files first, then the listed folders left empty,
/// deepest first); what else is there stays.
void removeListed(const fs::path& folder, const std::vector<std::string>& entries) {
  std::error_code ec;
  std::vector<std::string> dirs;
  for (const std::string& e : entries) {
    if (!e.empty() && e.back() == '/')
      dirs.push_back(e);
    else
      fs::remove(folder / e, ec);
  }
  std::sort(dirs.begin(), dirs.end(), [](const std::string& a, const std::string& b) { return a.size() > b.size(); });
  for (const std::string& d : dirs) fs::remove(folder / d, ec);  // fails (kept) unless empty
}

std::string quoted(const std::string& s) { return "'" + s + "'"; }

}  // namespace

FolderVerdict inspectFolder(const std::string& folder, const OutputFolderOptions& options) {
  FolderVerdict v;
  std::error_code ec;
  const fs::file_status st = fs::symlink_status(folder, ec);
  if (ec || !fs::exists(st)) return v;
  v.exists = true;
  if (!fs::is_directory(fs::status(folder, ec))) {
    v.is_folder = false;
    return v;
  }
  v.read_only = (fs::status(folder, ec).permissions() & fs::perms::owner_write) == fs::perms::none;
  const std::vector<std::string> entries = listEntries(folder);
  v.empty = entries.empty();
  std::set<std::string> listed;
  const bool manifest = readManifest(folder, options.tool, listed);
  bool legacy = !manifest && !options.legacy_names.empty();
  if (legacy) {
    std::set<std::string> top;
    for (const auto& e : fs::directory_iterator(folder, ec)) top.insert(e.path().filename().string());
    for (const std::string& name : top)
      legacy = legacy &&
               std::find(options.legacy_names.begin(), options.legacy_names.end(), name) != options.legacy_names.end();
    for (const std::string& name : options.legacy_required) legacy = legacy && top.count(name) > 0;
  }
  for (const std::string& e : entries) {
    const bool ours = legacy || (manifest && (listed.count(e) > 0 || e == kManifestName));
    (ours ? v.ours : v.foreign).push_back(e);
  }
  return v;
}

void checkApartFromInputs(const std::string& out, const std::vector<std::string>& inputs) {
  const fs::path o = resolved(out);
  for (const std::string& input : inputs) {
    if (input.empty()) continue;
    const fs::path p = resolved(input);
    std::error_code ec;
    if (p == o) throw InputError(out, "is the input " + quoted(input) + ": name a new folder for the outputs");
    if (within(p, o)) throw InputError(out, "holds the input " + quoted(input) + ": name a folder outside it");
    if (fs::is_directory(p, ec) && within(o, p))
      throw InputError(out, "lies inside the input " + quoted(input) + ": name a folder outside it");
  }
}

OutputFolder::OutputFolder(const std::string& out, OutputFolderOptions options) : options_(std::move(options)) {
  if (out.empty()) throw InputError("output folder ''", "expected a folder name");
  const fs::path p = resolved(out);
  if (p == p.root_path()) throw InputError(out, "is the root folder: name a folder for the outputs");
  final_ = p.string();
  checkApartFromInputs(out, options_.inputs);
  const FolderVerdict v = inspectFolder(final_, options_);
  if (v.exists && !v.is_folder) throw InputError(out, "exists and is not a folder");
  if (v.exists && v.read_only)
    throw InputError(out, "is read-only: idyvins leaves it as it is (make it writable or name another folder)");
  if (!v.foreign.empty() && !options_.force)
    throw InputError(out, "holds " + std::to_string(v.foreign.size()) + " file(s) idyvins " + options_.tool +
                              " did not write (" + quoted(v.foreign.front()) + (v.foreign.size() > 1 ? ", ..." : "") +
                              "): name a new or empty folder, or pass --force to write beside them (none is removed)");
  staging_ = final_ + ".partial-" + std::to_string(::getpid());
  std::error_code ec;
  fs::create_directories(p.parent_path(), ec);
  if (fs::exists(staging_, ec)) throw InputError(staging_, "exists (a staging folder of another run?): remove it");
  if (!fs::create_directory(staging_, ec) || ec)  // named as given: the staging folder is an implementation detail
    throw InputError(out, "cannot create the output folder: " + (ec ? ec.message() : std::string("exists")));
}

OutputFolder::~OutputFolder() {
  std::error_code ec;
  if (!published_ && !staging_.empty()) fs::remove_all(staging_, ec);
}

bool OutputFolder::isOutput(const std::string& p) const { return resolved(p) == fs::path(final_); }

bool OutputFolder::insideOutput(const std::string& p) const {
  return resolved(fs::absolute(p).parent_path()) == fs::path(final_);
}

std::string OutputFolder::extraFile(const std::string& path) const {
  std::error_code ec;
  const fs::path p(path);
  if (p.filename().empty()) throw InputError(path, "expected a file name, got a folder");
  if (insideOutput(path)) return (fs::path(staging_) / p.filename()).string();
  if (fs::exists(p, ec) && !options_.force)
    throw InputError(path, "exists: idyvins does not overwrite it (name a new file, or pass --force)");
  if (p.has_parent_path()) fs::create_directories(p.parent_path(), ec);
  const bool existed = fs::exists(p, ec);
  if (!std::ofstream(path, std::ios::app)) throw InputError(path, "cannot write file");
  if (!existed) fs::remove(p, ec);
  return path;
}

std::string OutputFolder::extraFolder(const std::string& path) const {
  std::error_code ec;
  fs::path p(path);
  if (p.filename().empty()) p = p.parent_path();  // "map/" -> "map"
  if (isOutput(p.string())) throw InputError(path, "is the output folder; name a folder beside it or inside it");
  if (insideOutput(p.string())) return (fs::path(staging_) / p.filename()).string();
  fs::create_directories(p, ec);
  const fs::path probe = p / (".idyvins-write-check-" + std::to_string(::getpid()));
  if (!std::ofstream(probe)) throw InputError(path, "cannot write into this folder");
  fs::remove(probe, ec);
  return p.string();
}

std::vector<std::string> OutputFolder::publish() {
  std::vector<std::string> warnings;
  std::error_code ec;
  {
    const nlohmann::json manifest = {{"tool", options_.tool}, {"entries", listEntries(staging_)}};
    std::ofstream m(fs::path(staging_) / kManifestName);
    m << manifest.dump(1) << "\n";
    if (!m) throw InputError(staging_ + "/" + kManifestName, "write failed");
  }
  const FolderVerdict v = inspectFolder(final_, options_);
  if (!v.exists) {
    fs::rename(staging_, final_, ec);
  } else if (v.foreign.empty()) {  // an earlier output of the tool: swapped out, then its files removed
    const std::string old = final_ + ".old-" + std::to_string(::getpid());
    fs::rename(final_, old, ec);
    if (!ec) fs::rename(staging_, final_, ec);
    if (!ec) {
      removeListed(old, v.ours);
      std::error_code rm;
      if (!fs::remove(old, rm)) warnings.push_back("kept " + old + ": files appeared in the old folder during the run");
    }
  } else {  // --force beside foreign files: the tool's own files replaced, the others left
    removeListed(final_, v.ours);
    std::vector<fs::path> staged;
    for (const auto& e : fs::directory_iterator(staging_, ec)) staged.push_back(e.path());
    for (const fs::path& e : staged) {
      const fs::path target = fs::path(final_) / e.filename();
      std::error_code exists_ec;
      if (fs::exists(fs::symlink_status(target, exists_ec))) {
        std::string aside = target.string() + ".orig";
        if (fs::exists(aside)) aside += "-" + std::to_string(::getpid());
        fs::rename(target, aside, ec);
        if (ec) break;
        warnings.push_back("moved " + target.string() + " aside to " + aside + " (not written by idyvins " +
                           options_.tool + ")");
      }
      fs::rename(e, target, ec);
      if (ec) break;
    }
    if (!ec) fs::remove(staging_, ec);
  }
  published_ = true;  // from here the staging folder is kept: on failure it holds the only copy of the results
  if (ec)
    throw InputError(final_,
                     "cannot move the finished results into place (" + ec.message() + "): they are in " + staging_);
  return warnings;
}

}  // namespace idyvins::io
