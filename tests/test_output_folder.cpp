// io::OutputFolder: results staged and swapped in whole, and nothing idyvins did not write
// ever removed: the dataset, a parent of it, a folder with foreign files, a read-only folder.

#include <gtest/gtest.h>

#include <filesystem>

#include "io/output_folder.h"
#include "test_util.h"

namespace {

namespace fs = std::filesystem;
using idyvins::io::OutputFolder;
using idyvins::io::OutputFolderOptions;
using idyvins::test::expectError;
using idyvins::test::readFile;
using idyvins::test::TempDir;
using idyvins::test::writeFile;

OutputFolderOptions runOptions(std::vector<std::string> inputs = {}, bool force = false) {
  OutputFolderOptions o;
  o.tool = "run";
  o.inputs = std::move(inputs);
  o.force = force;
  o.legacy_names = {"trajectory.tum", "stats.json", "run.json"};
  o.legacy_required = {"run.json", "stats.json"};
  return o;
}

/// One "run" into `out`: writes trajectory.tum with `text` and publishes.
void writeRun(const std::string& out, const std::string& text, const OutputFolderOptions& o) {
  OutputFolder f(out, o);
  writeFile(f.path() + "/trajectory.tum", text);
  fs::create_directories(f.path() + "/sub");
  writeFile(f.path() + "/sub/a.csv", text);
  f.publish();
}

TEST(OutputFolder, ANewFolderGetsTheResultsAndAManifestListingThem) {
  TempDir tmp;
  writeRun(tmp / "out", "one", runOptions());
  EXPECT_EQ(readFile(tmp / "out/trajectory.tum"), "one");
  const std::string manifest = readFile(tmp / "out/idyvins_manifest.json");
  EXPECT_NE(manifest.find("\"tool\": \"run\""), std::string::npos) << manifest;
  EXPECT_NE(manifest.find("\"sub/a.csv\""), std::string::npos) << manifest;
  EXPECT_NE(manifest.find("\"sub/\""), std::string::npos) << manifest;
  EXPECT_FALSE(fs::exists(tmp / ("out.partial-" + std::to_string(::getpid()))));
}

TEST(OutputFolder, AnEarlierRunIsReplacedWhole) {
  TempDir tmp;
  writeRun(tmp / "out", "one", runOptions());
  {
    OutputFolder f(tmp / "out", runOptions());
    writeFile(f.path() + "/trajectory.tum", "two");
    f.publish();
  }
  EXPECT_EQ(readFile(tmp / "out/trajectory.tum"), "two");
  EXPECT_FALSE(fs::exists(tmp / "out/sub/a.csv"));          // the earlier run's file, not written this time
  for (const auto& e : fs::directory_iterator(tmp.path()))  // no OUT.old-PID left behind
    EXPECT_EQ(e.path().filename(), "out");
}

TEST(OutputFolder, AFolderWithForeignFilesIsRefusedBeforeAnythingIsWritten) {
  TempDir tmp;
  writeFile(tmp / "out/notes.txt", "mine");
  expectError([&] { OutputFolder f(tmp / "out", runOptions()); },
              "holds 1 file(s) idyvins run did not write ('notes.txt')");
  EXPECT_EQ(readFile(tmp / "out/notes.txt"), "mine");
  // An earlier run with a foreign file added to it is not the tool's alone either.
  writeRun(tmp / "run", "one", runOptions());
  writeFile(tmp / "run/sub/mine.txt", "mine");
  expectError([&] { OutputFolder f(tmp / "run", runOptions()); }, "'sub/mine.txt'");
}

TEST(OutputFolder, ForceWritesBesideForeignFilesAndRemovesOnlyTheToolsOwn) {
  TempDir tmp;
  writeFile(tmp / "out/notes.txt", "mine");
  writeFile(tmp / "out/trajectory.tum", "a file of the user's with an output's name");
  writeRun(tmp / "out", "one", runOptions({}, true));
  EXPECT_EQ(readFile(tmp / "out/notes.txt"), "mine");
  EXPECT_EQ(readFile(tmp / "out/trajectory.tum"), "one");
  EXPECT_EQ(readFile(tmp / "out/trajectory.tum.orig"), "a file of the user's with an output's name");
  // Again with --force: the first run's files go, the user's stay.
  {
    OutputFolder f(tmp / "out", runOptions({}, true));
    writeFile(f.path() + "/trajectory.tum", "two");
    f.publish();
  }
  EXPECT_EQ(readFile(tmp / "out/trajectory.tum"), "two");
  EXPECT_FALSE(fs::exists(tmp / "out/sub"));
  EXPECT_EQ(readFile(tmp / "out/notes.txt"), "mine");
  EXPECT_TRUE(fs::exists(tmp / "out/trajectory.tum.orig"));
}

TEST(OutputFolder, TheDatasetAParentOfItAndAFolderInsideItAreRefused) {
  TempDir tmp;
  writeFile(tmp / "ds/mav0/imu0/data.csv", "x");
  for (bool force : {false, true}) {
    expectError([&] { OutputFolder f(tmp / "ds", runOptions({tmp / "ds"}, force)); }, "is the input");
    expectError([&] { OutputFolder f(tmp.path().string(), runOptions({tmp / "ds"}, force)); }, "holds the input");
    expectError([&] { OutputFolder f(tmp / "ds/mav0/out", runOptions({tmp / "ds"}, force)); }, "lies inside the input");
    expectError([&] { OutputFolder f(tmp / "ds/../ds/", runOptions({tmp / "ds/mav0"}, force)); }, "holds the input");
  }
  EXPECT_EQ(readFile(tmp / "ds/mav0/imu0/data.csv"), "x");
  // A file input (a bag, a config) only may not be inside OUT.
  writeFile(tmp / "rec/x.bag", "bag");
  EXPECT_NO_THROW(OutputFolder(tmp / "rec/out", runOptions({tmp / "rec/x.bag"})));
}

TEST(OutputFolder, AReadOnlyFolderTheEmptyNameAndTheRootAreRefused) {
  TempDir tmp;
  writeRun(tmp / "out", "one", runOptions());
  fs::permissions(tmp / "out", fs::perms::owner_write | fs::perms::group_write | fs::perms::others_write,
                  fs::perm_options::remove);
  expectError([&] { OutputFolder f(tmp / "out", runOptions({}, true)); }, "is read-only");
  fs::permissions(tmp / "out", fs::perms::owner_write, fs::perm_options::add);
  EXPECT_EQ(readFile(tmp / "out/trajectory.tum"), "one");
  expectError([&] { OutputFolder f("", runOptions()); }, "expected a folder name");
  expectError([&] { OutputFolder f("/", runOptions({}, true)); }, "is the root folder");
  writeFile(tmp / "file", "x");
  expectError([&] { OutputFolder f(tmp / "file", runOptions({}, true)); }, "exists and is not a folder");
}

TEST(OutputFolder, AnUnpublishedFolderLeavesNothingAndALegacyRunIsRecognized) {
  TempDir tmp;
  {
    OutputFolder f(tmp / "out", runOptions());
    writeFile(f.path() + "/trajectory.tum", "half");
  }  // a failed run: no publish
  EXPECT_TRUE(fs::is_empty(tmp.path()));
  // Written before manifests: only the tool's names, run.json and stats.json among them.
  writeFile(tmp / "old/run.json", "{}");
  writeFile(tmp / "old/stats.json", "{}");
  writeRun(tmp / "old", "new", runOptions());
  EXPECT_EQ(readFile(tmp / "old/trajectory.tum"), "new");
  EXPECT_FALSE(fs::exists(tmp / "old/run.json"));
  writeFile(tmp / "other/stats.json", "{}");  // no run.json: not recognized
  expectError([&] { OutputFolder f(tmp / "other", runOptions()); }, "did not write");
  // Another tool's output is not the run's to replace.
  OutputFolderOptions sim = runOptions();
  sim.tool = "simulate";
  writeRun(tmp / "sim", "render", sim);
  expectError([&] { OutputFolder f(tmp / "sim", runOptions()); }, "did not write");
}

TEST(OutputFolder, ExtraFilesElsewhereAreNotOverwrittenWithoutForce) {
  TempDir tmp;
  writeFile(tmp / "obs.csv", "mine");
  OutputFolder f(tmp / "out", runOptions());
  expectError([&] { f.extraFile(tmp / "obs.csv"); }, "exists");
  EXPECT_EQ(f.extraFile(tmp / "out/obs.csv"), f.path() + "/obs.csv");
  EXPECT_EQ(f.extraFile(tmp / "new/obs.csv"), tmp / "new/obs.csv");
  EXPECT_FALSE(fs::exists(tmp / "new/obs.csv"));  // probed, not left
  EXPECT_EQ(readFile(tmp / "obs.csv"), "mine");
}

}  // namespace
