// The battery of broken inputs a new user brings, on the real EuRoC excerpt: none ends with
// exit 0 and a silent loss of data or accuracy. Output folders that are or hold the dataset,
// foreign files, read-only folders; runs without a trajectory (exit 4); rigs and data that
// cannot be right (units, NaN, baselines, rates); misspelled keys; perturb's magnitudes.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <regex>
#include <sstream>
#include <string>

#include "cli_util.h"
#include "test_util.h"

namespace {

namespace fs = std::filesystem;
using idyvins::test::readFile;
using idyvins::test::runCli;
using idyvins::test::TempDir;
using idyvins::test::writeFile;

const std::string kMicro = idyvins::test::sharedData("euroc_v101_micro");
const std::string kConfig = std::string(IDYVINS_SOURCE_DIR) + "/config/euroc/euroc_stereo_imu_config.yaml";

bool has(const idyvins::test::CliResult& r, const std::string& needle) {
  return r.out.find(needle) != std::string::npos;
}

/// DIR/ds: the excerpt's cameras linked, its IMU rows passed through `edit` (a row: the CSV
/// line's fields; return false to drop it).
std::string datasetWithImu(const TempDir& dir, const std::function<bool(std::vector<std::string>&)>& edit,
                           bool with_cam1 = true) {
  const fs::path ds = dir / "ds", mav0 = ds / "mav0";
  fs::create_directories(mav0 / "imu0");
  fs::create_directory_symlink(fs::path(kMicro) / "mav0/cam0", mav0 / "cam0");
  if (with_cam1) fs::create_directory_symlink(fs::path(kMicro) / "mav0/cam1", mav0 / "cam1");
  std::ifstream in(kMicro + "/mav0/imu0/data.csv");
  std::ofstream out(mav0 / "imu0/data.csv");
  for (std::string line; std::getline(in, line);) {
    if (line.empty() || line[0] == '#') {
      out << line << "\n";
      continue;
    }
    std::vector<std::string> f;
    std::stringstream ss(line);
    for (std::string x; std::getline(ss, x, ',');) f.push_back(x);
    if (!edit(f)) continue;
    for (std::size_t i = 0; i < f.size(); ++i) out << (i ? "," : "") << f[i];
    out << "\n";
  }
  return ds.string();
}

/// The shipped EuRoC config (and its camera files) in DIR/cfg with `from` replaced by `to`
/// in the file named `file` (the config or a camera file).
std::string editedConfig(const TempDir& dir, const std::string& file, const std::string& from, const std::string& to) {
  const fs::path src = fs::path(kConfig).parent_path(), cfg = dir / "cfg";
  fs::create_directories(cfg);
  for (const char* f : {"euroc_stereo_imu_config.yaml", "cam0_pinhole.yaml", "cam1_pinhole.yaml"})
    fs::copy_file(src / f, cfg / f, fs::copy_options::overwrite_existing);
  std::string text = readFile((cfg / file).string());
  text = std::regex_replace(text, std::regex(from), to);
  writeFile((cfg / file).string(), text);
  return (cfg / "euroc_stereo_imu_config.yaml").string();
}

TEST(CliRefusals, RunNeverWritesIntoTheDatasetAParentOfItOrAFolderOfForeignFiles) {
  TempDir dir;
  const std::string ds = datasetWithImu(dir, [](auto&) { return true; });
  writeFile(dir / "mine/notes.txt", "mine");
  const std::string run = "run -c " + kConfig + " -d " + ds + " --frames 40 -o ";
  for (const std::string& out :
       {ds, dir.path().string(), ds + "/mav0/out", dir / "mine", std::string("''"), dir / "ds/mav0/imu0/data.csv"}) {
    const auto r = runCli(run + out);
    EXPECT_EQ(r.code, 1) << out << "\n" << r.out;
    EXPECT_FALSE(has(r, "frames (")) << "refused only after the run:\n" << r.out;
  }
  EXPECT_TRUE(fs::exists(dir / "ds/mav0/imu0/data.csv"));
  EXPECT_EQ(readFile(dir / "mine/notes.txt"), "mine");
  EXPECT_TRUE(has(runCli(run + dir / "mine"), "holds 1 file(s) idyvins run did not write ('notes.txt')"));
  // --force writes beside the foreign file and keeps it; a read-only earlier run stays as it was.
  const auto forced = runCli(run + dir / "mine" + " --force");
  EXPECT_EQ(forced.code, 0) << forced.out;
  EXPECT_EQ(readFile(dir / "mine/notes.txt"), "mine");
  EXPECT_TRUE(fs::exists(dir / "mine/trajectory.tum"));
  ASSERT_EQ(runCli(run + dir / "ro").code, 0);
  fs::permissions(dir / "ro", fs::perms::owner_write | fs::perms::group_write | fs::perms::others_write,
                  fs::perm_options::remove);
  const auto ro = runCli(run + dir / "ro");
  fs::permissions(dir / "ro", fs::perms::owner_write, fs::perm_options::add);
  EXPECT_EQ(ro.code, 1);
  EXPECT_TRUE(has(ro, "is read-only")) << ro.out;
  EXPECT_TRUE(fs::exists(dir / "ro/trajectory.tum"));
  for (const auto& e : fs::directory_iterator(dir.path()))  // no OUT.old-PID or OUT.partial-PID left
    EXPECT_EQ(e.path().filename().string().find('-'), std::string::npos) << e.path();
}

TEST(CliRefusals, OtherCommandsRefuseTheirInputsAsOutputs) {
  TempDir dir;
  const std::string ds = datasetWithImu(dir, [](auto&) { return true; });
  EXPECT_EQ(runCli("perturb " + ds + " " + ds + "/mav0/copy --fault black").code, 1);
  EXPECT_FALSE(fs::exists(ds + "/mav0/copy"));
  writeFile(dir / "mine/notes.txt", "mine");
  const auto sim = runCli("simulate --scene city --duration 1 --out " + dir / "mine");
  EXPECT_EQ(sim.code, 1) << sim.out;
  EXPECT_TRUE(has(sim, "idyvins simulate did not write")) << sim.out;
  const auto bench = runCli("bench --suite standard --seeds 1 --duration 1 --out " + dir / "mine");
  EXPECT_EQ(bench.code, 1) << bench.out;
  EXPECT_TRUE(has(bench, "no bench.json")) << bench.out;
  EXPECT_EQ(readFile(dir / "mine/notes.txt"), "mine");
  EXPECT_EQ(fs::directory_iterator(dir / "mine")->path().filename(), "notes.txt");
}

TEST(CliRefusals, ARunWithoutATrajectoryExitsFourAndSaysWhy) {
  TempDir dir;
  const auto one = runCli("run -c " + kConfig + " -d " + kMicro + " -o " + dir / "one" + " --frames 1");
  EXPECT_EQ(one.code, 4) << one.out;
  EXPECT_TRUE(has(one, "error: no trajectory: 0 poses for 1 frames")) << one.out;
  EXPECT_TRUE(has(one, "initialization needs 11 frames")) << one.out;
  EXPECT_TRUE(fs::exists(dir / "one/stats.json"));  // written for inspection
  // All-black images: nothing to track.
  ASSERT_EQ(runCli("perturb " + kMicro + " " + dir / "black" + " --fault black --at 0 --duration 10").code, 0);
  const auto black = runCli("run -c " + kConfig + " -d " + dir / "black" + " -o " + dir / "black_out");
  EXPECT_EQ(black.code, 4) << black.out;
  EXPECT_TRUE(has(black, "too few features")) << black.out;
  // The share of frames with a pose is in the summary of a run that has one.
  const auto good = runCli("run -c " + kConfig + " -d " + kMicro + " -o " + dir / "good");
  EXPECT_EQ(good.code, 0) << good.out;
  EXPECT_TRUE(std::regex_search(good.out, std::regex(R"(\d+ poses \(\d+\.\d% of the frames\))"))) << good.out;
}

TEST(CliRefusals, ImplausibleRigsAreRefusedWithTheirCause) {
  TempDir dir;
  const std::vector<std::tuple<std::string, std::string, std::string, std::string>> cases = {
      {"euroc_stereo_imu_config.yaml", "\ntd: 0\\.0", "\ntd: 100",
       "expected a camera-IMU offset within 0.5 s (td is in seconds)"},
      {"cam0_pinhole.yaml", "k1: [-0-9.e]+", "k1: 1e6", "moves the image corner by a factor"},
      {"euroc_stereo_imu_config.yaml", "-0\\.0216401454975", ".nan", "expected finite numbers"},
      {"euroc_stereo_imu_config.yaml", "0\\.0148655429818", "0.0158655429818", "not orthonormal"},
      {"euroc_stereo_imu_config.yaml", "-0\\.0198435579556", "-19.8435579556", "translations in millimetres?"},
      {"euroc_stereo_imu_config.yaml", "image1_topic: \"/cam1/image_raw\"", "image1_topic: \"/cam0/image_raw\"",
       "image1_topic and image0_topic are the same topic"},
  };
  for (const auto& [file, from, to, why] : cases) {
    const std::string cfg = editedConfig(dir, file, from, to);
    const auto info = runCli("info " + kMicro + " -c " + cfg + " --skip-images");
    const auto r = runCli("run -c " + cfg + " -d " + kMicro + " -o " + dir / "out");
    EXPECT_EQ(r.code, 1) << to << "\n" << r.out;
    EXPECT_TRUE(has(r, why)) << to << "\n" << r.out;
    EXPECT_EQ(info.code, 1) << to << "\n" << info.out;  // info refuses it in the same words
    EXPECT_TRUE(has(info, why)) << info.out;
  }
  // body_T_cam1 = body_T_cam0: no baseline.
  std::string text = readFile(kConfig);
  const std::regex cam1("body_T_cam1:[^\\]]*\\]"), cam0("body_T_cam0:[^\\]]*\\]");
  std::smatch m0;
  ASSERT_TRUE(std::regex_search(text, m0, cam0));
  const std::string copy = std::regex_replace(m0.str(), std::regex("body_T_cam0"), "body_T_cam1");
  const std::string cfg = editedConfig(dir, "euroc_stereo_imu_config.yaml", "body_T_cam1:[^\\]]*\\]", copy);
  const auto zero = runCli("run -c " + cfg + " -d " + kMicro + " -o " + dir / "out");
  EXPECT_EQ(zero.code, 1);
  EXPECT_TRUE(has(zero, "stereo baseline 0 m")) << zero.out;
}

TEST(CliRefusals, DataInTheWrongUnitOrWithoutIMUAtTheFramesIsRefused) {
  const std::vector<std::tuple<std::function<bool(std::vector<std::string>&)>, std::string>> cases = {
      {[](auto& f) { return f[0] = std::to_string(std::stoll(f[0]) / 1000), true; },
       "the IMU at 200000 Hz if its stamps are ns"},
      {[](auto& f) {
         for (int i = 1; i <= 3; ++i) f[i] = std::to_string(std::stod(f[i]) * 57.29578);
         return true;
       },
       "expected rad/s"},
      {[](auto& f) { return std::fill(f.begin() + 1, f.end(), "0"), true; }, "accelerometer median 0.000 m/s^2"},
      {[](auto& f) {
         for (int i = 4; i <= 6; ++i) f[i] = std::to_string(std::stod(f[i]) / 9.81);
         return true;
       },
       "(in g? expected m/s^2)"},
  };
  for (const auto& [edit, why] : cases) {
    TempDir dir;
    const std::string ds = datasetWithImu(dir, edit);
    const auto r = runCli("run -c " + kConfig + " -d " + ds + " -o " + dir / "out");
    EXPECT_EQ(r.code, 1) << why << "\n" << r.out;
    EXPECT_TRUE(has(r, why)) << r.out;
    EXPECT_TRUE(has(runCli("info " + ds + " -c " + kConfig + " --skip-images"), why));
  }
  TempDir dir;  // a stereo config on a folder without cam1: run refuses it as info does
  const std::string mono = datasetWithImu(
      dir, [](auto&) { return true; }, /*with_cam1=*/false);
  const auto r = runCli("run -c " + kConfig + " -d " + mono + " -o " + dir / "out");
  EXPECT_EQ(r.code, 1) << r.out;
  EXPECT_TRUE(has(r, "but the dataset has no cam1/")) << r.out;
}

TEST(CliRefusals, ASlowOrLateImuAndMisspelledKeysAreWarnedAbout) {
  TempDir dir;
  std::size_t k = 0;
  const std::string slow = datasetWithImu(dir, [&](auto&) { return k++ % 10 == 0; });  // 20 Hz
  const auto r = runCli("run -c " + kConfig + " -d " + slow + " -o " + dir / "out");
  EXPECT_TRUE(has(r, "warning: ")) << r.out;
  EXPECT_TRUE(has(r, "IMU at 20.0 Hz, 1.0 samples per frame")) << r.out;
  TempDir late_dir;
  const std::string late = datasetWithImu(late_dir, [&](auto& f) {
    return std::stoll(f[0]) >= 1403715273262142976LL + 2'000'000'000LL;  // 2 s after the excerpt's first frame
  });
  const auto l = runCli("run -c " + kConfig + " -d " + late + " -o " + late_dir / "out");
  EXPECT_TRUE(has(l, "the IMU starts 2.000 s after the first frame")) << l.out;
  EXPECT_NE(l.code, 0) << l.out;  // half the frames without a pose
  const std::string typo = editedConfig(dir, "euroc_stereo_imu_config.yaml", "\nequalize:", "\nequalise:");
  const auto t = runCli("info " + kMicro + " -c " + typo + " --skip-images");
  EXPECT_EQ(t.code, 0) << t.out;
  EXPECT_TRUE(has(t, "unknown key 'equalise' ignored; did you mean 'equalize'?")) << t.out;
  EXPECT_TRUE(has(t, "valid: yes, with 1 warning(s)")) << t.out;
  const std::string extr =
      editedConfig(dir, "euroc_stereo_imu_config.yaml", "estimate_extrinsic: 0", "estimate_extrinsic: 1");
  const auto e = runCli("info " + kMicro + " -c " + extr + " --skip-images");
  EXPECT_EQ(e.code, 0) << e.out;  // honoured now: no warning about it
  EXPECT_TRUE(has(e, "valid: yes")) << e.out;
  EXPECT_FALSE(has(e, "not honoured")) << e.out;
  EXPECT_FALSE(has(e, "valid: yes, with")) << e.out;
  const std::string bad =
      editedConfig(dir, "euroc_stereo_imu_config.yaml", "estimate_extrinsic: 0", "estimate_extrinsic: 3");
  const auto b = runCli("info " + kMicro + " -c " + bad + " --skip-images");
  EXPECT_NE(b.code, 0) << b.out;
  EXPECT_TRUE(has(b, "key 'estimate_extrinsic': expected 0, 1 or 2")) << b.out;
}

TEST(CliRefusals, PerturbDefaultsChangeTheDataAndBadMagnitudesAreRefused) {
  TempDir dir;
  for (const char* fault : {"time-jump", "desync", "imu-spike"}) {
    const std::string out = dir / fault;
    const auto r = runCli("perturb " + kMicro + " " + out + " --fault " + fault + " --at 1");
    ASSERT_EQ(r.code, 0) << r.out;
    const bool imu = std::string(fault) == "imu-spike";
    const std::string file = imu ? "/mav0/imu0/data.csv" : "/mav0/cam1/data.csv";
    EXPECT_NE(readFile(out + file), readFile(kMicro + file)) << fault << ": the default did nothing";
  }
  for (const char* bad :
       {"--fault time-jump --magnitude nan", "--fault desync --magnitude 0", "--fault imu-spike --magnitude inf",
        "--fault black --at 100", "--fault black --magnitude 3", "--fault salt --magnitude 150"}) {
    const auto r = runCli("perturb " + kMicro + " " + dir / "bad " + std::string(bad));
    EXPECT_EQ(r.code, 2) << bad << "\n" << r.out;
    EXPECT_FALSE(fs::exists(dir / "bad")) << bad;
  }
}

TEST(CliRefusals, UnclearLinesNameTheirCause) {
  TempDir dir;
  const auto sub = runCli("frobnicate");
  EXPECT_EQ(sub.code, 2);
  EXPECT_TRUE(has(sub, "unknown command 'frobnicate'")) << sub.out;
  fs::create_symlink(dir / "loop_b", dir / "loop_a");
  fs::create_symlink(dir / "loop_a", dir / "loop_b");
  const auto loop = runCli("info " + dir / "loop_a");
  EXPECT_EQ(loop.code, 1) << loop.out;
  const auto longpath = runCli("run -c " + kConfig + " -d " + kMicro + " -o " + std::string(4100, 'a'));
  EXPECT_EQ(longpath.code, 1) << longpath.out.substr(0, 300);
  // eval: a distance longer than the trajectory gives a row without pairs, said so.
  writeFile(dir / "a.tum", "1.0 0 0 0 0 0 0 1\n1.1 0.1 0 0 0 0 0 1\n1.2 0.1 0.1 0 0 0 0 1\n1.3 0 0.1 0.1 0 0 0 1\n");
  const auto ev = runCli("eval --gt " + dir / "a.tum" + " --est " + dir / "a.tum" + " --rpe 1000");
  EXPECT_EQ(ev.code, 0) << ev.out;
  EXPECT_TRUE(has(ev, "no pairs")) << ev.out;
}

}  // namespace
