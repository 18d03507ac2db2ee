// Runs the `idyvins` binary: every subcommand's --help, `info` on the real
// EuRoC excerpt, and the one-line error + exit code on bad input.

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cli_util.h"
#include "config/config.h"
#include "pipeline/observers.h"
#include "pipeline/run.h"
#include "pipeline/run_outputs.h"
#include "test_util.h"

namespace {

using Result = idyvins::test::CliResult;
Result run(const std::string& args) { return idyvins::test::runCli(args); }

const std::string kMicro = idyvins::test::sharedData("euroc_v101_micro");

TEST(Cli, HelpForEverySubcommand) {
  const Result top = run("--help");
  EXPECT_EQ(top.code, 0);
  EXPECT_NE(top.out.find("info"), std::string::npos);
  for (const char* sub : {"info", "simulate", "eval", "track", "run", "bench"}) {
    const Result r = run(std::string(sub) + " --help");
    EXPECT_EQ(r.code, 0) << sub;
    EXPECT_NE(r.out.find("Usage"), std::string::npos) << r.out;
  }
}

TEST(Cli, UsageErrorsExitTwo) {
  // docs/cli.md: usage errors exit 2 (CLI11's own codes are 101-120).
  EXPECT_EQ(run("").code, 2);                                     // no subcommand
  EXPECT_EQ(run("frobnicate").code, 2);                           // unknown subcommand
  EXPECT_EQ(run("run --config c.yaml").code, 2);                  // required options missing
  EXPECT_EQ(run("run -c c.yaml -d d -o o --threads 3").code, 2);  // out of range
  const Result frames = run("run -c c.yaml -d d -o o --frames -1");
  EXPECT_EQ(frames.code, 2);
  EXPECT_NE(frames.out.find("--frames"), std::string::npos) << frames.out;
  EXPECT_EQ(run("track -c c.yaml -d d --frames -5").code, 2);
  EXPECT_EQ(run("--version").code, 0);
}

TEST(Cli, InfoOnRealEurocExcerpt) {
  const Result r =
      run("info " + kMicro + " --config " + IDYVINS_SOURCE_DIR + "/config/euroc/euroc_stereo_imu_config.yaml");
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("imu0          29120 samples   200.00 Hz  span  145.595 s"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("cam0             95 images     20.00 Hz  span    4.700 s"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("cam1             99 images"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("stereo pairs     95 frames"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("cam0 0, cam1 4 rows without a partner"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("95 pairs read, all 752x480"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("imu spikes   none that run would drop"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("valid: yes"), std::string::npos) << r.out;
}

TEST(Cli, InfoCountsTheImuSpikesRunWouldDrop) {
  // 25 ms of 10 g added to the real excerpt's IMU at 2 s: info names the spike run drops.
  idyvins::test::TempDir dir;
  const Result p =
      run("perturb " + kMicro + " " + (dir / "spiked") + " --fault imu-spike --at 2 --count 5 --magnitude 100");
  ASSERT_EQ(p.code, 0) << p.out;
  const Result r = run("info " + (dir / "spiked") + " --skip-images");
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("imu spikes   1 short spikes (5 samples) that run drops"), std::string::npos) << r.out;
  const Result j = run("info " + (dir / "spiked") + " --skip-images --json");
  EXPECT_NE(j.out.find("\"runs\": 1"), std::string::npos) << j.out;
}

TEST(Cli, InfoJson) {
  const Result r = run("info " + kMicro + " --json --skip-images");
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("\"count\": 29120"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("\"unmatched_cam1\": 4"), std::string::npos) << r.out;
}

TEST(Cli, BadInputIsOneLineAndNonZeroExit) {
  const Result r = run("info /nonexistent/dataset");
  EXPECT_EQ(r.code, 1);
  EXPECT_EQ(r.out, "error: /nonexistent/dataset: dataset folder does not exist\n");
  const std::string empty_bag = ::testing::TempDir() + "/empty.bag";
  { std::ofstream(empty_bag).flush(); }  // zero bytes
  const Result e = run("info " + empty_bag);
  EXPECT_EQ(e.code, 1);
  EXPECT_EQ(e.out, "error: " + empty_bag +
                       ": is a file, but neither a ROS1 bag (no '#ROSBAG V2.0' header) nor a EuRoC folder\n");
  const Result c = run("info " + kMicro + " --config /nonexistent/cfg.yaml");
  EXPECT_EQ(c.code, 1);
  EXPECT_EQ(c.out, "error: /nonexistent/cfg.yaml: cannot open file (missing or unreadable)\n");
}

TEST(Cli, SimulateBadArguments) {
  const Result level = run("simulate --level extreme --out /tmp/x");
  EXPECT_NE(level.code, 0);
  EXPECT_NE(level.out.find("extreme"), std::string::npos) << level.out;
  const Result out = run("simulate --duration 0.1 --out /proc/forbidden/sim");
  EXPECT_EQ(out.code, 1);
  EXPECT_EQ(out.out.find("error: /proc/forbidden/sim: cannot create the output folder"), 0u) << out.out;
  EXPECT_EQ(std::count(out.out.begin(), out.out.end(), '\n'), 1) << out.out;
}

TEST(Cli, SimulateWritesADatasetThatInfoValidates) {
  idyvins::test::TempDir dir;
  const Result sim = run("simulate --scene parking_lot --level low --duration 0.5 --out " + (dir / "ds"));
  ASSERT_EQ(sim.code, 0) << sim.out;
  EXPECT_NE(sim.out.find("11 stereo frames, 101 IMU samples"), std::string::npos) << sim.out;
  const Result info = run("info " + (dir / "ds") + " --config " + (dir / "ds/config/sim_stereo_imu_config.yaml"));
  ASSERT_EQ(info.code, 0) << info.out;
  EXPECT_NE(info.out.find("groundtruth     101 states"), std::string::npos) << info.out;
  EXPECT_NE(info.out.find("valid: yes"), std::string::npos) << info.out;
  const Result track = run("track --config " + (dir / "ds/config/sim_stereo_imu_config.yaml") + " --dataset " +
                           (dir / "ds") + " --mode seg --save-tracks " + (dir / "tracks"));
  ASSERT_EQ(track.code, 0) << track.out;
  EXPECT_NE(track.out.find("11 frames, mode seg"), std::string::npos) << track.out;
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir / "tracks"), std::filesystem::directory_iterator{}),
            11);
}

TEST(Cli, RunIdyWritesOutputsAndObservationDump) {
  // 4 s of city high (trucks overtaking the drone): `run --mode idy` end to end.
  idyvins::test::TempDir dir;
  const Result sim = run("simulate --scene city --level high --duration 4 --out " + (dir / "ds"));
  ASSERT_EQ(sim.code, 0) << sim.out;
  const std::string cfg = dir / "ds/config/sim_stereo_imu_config.yaml";
  const Result r = run("run --config " + cfg + " --dataset " + (dir / "ds") + " --out " + (dir / "out") +
                       " --mode idy --dump-observations " + (dir / "obs.csv"));
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("mode idy"), std::string::npos) << r.out;
  for (const char* f : {"trajectory.tum", "trajectory.csv", "state.csv", "stats.json", "map_static.ply",
                        "map_dynamic.ply", "map_all.ply"})
    EXPECT_TRUE(std::filesystem::exists(dir / (std::string("out/") + f))) << f;
  const std::string stats = idyvins::test::readFile(dir / "out/stats.json");
  EXPECT_NE(stats.find("\"stereo_tested\""), std::string::npos);
  EXPECT_NE(stats.find("\"stereo_eliminated\""), std::string::npos);
  // The dump: the header, and rows whose stereo χ² was computed and rows eliminated.
  const std::string csv = idyvins::test::readFile(dir / "obs.csv");
  const std::string header =
      "t_ns,id,u,v,track_length,frontend_label,d_s_px2,credibility,stereo_chi2,on_moving,confirmed_dynamic,"
      "in_static_map,outlier_removed,stereo_depth_m,u_right,v_right\n";
  ASSERT_EQ(csv.compare(0, header.size(), header), 0) << csv.substr(0, 200);
  std::size_t rows = 0, tested = 0, eliminated = 0, on_moving = 0, with_right = 0;
  std::size_t pos = header.size();
  while (pos < csv.size()) {
    const std::size_t end = csv.find('\n', pos);
    ASSERT_NE(end, std::string::npos);
    std::vector<std::string> cols;
    std::size_t a = pos;
    for (std::size_t b = csv.find(',', a); b < end; b = csv.find(',', a)) {
      cols.push_back(csv.substr(a, b - a));
      a = b + 1;
    }
    cols.push_back(csv.substr(a, end - a));
    ASSERT_EQ(cols.size(), 16u) << csv.substr(pos, end - pos);
    ++rows;
    tested += std::stod(cols[8]) >= 0;
    EXPECT_EQ(std::stod(cols[8]) >= 0, std::stod(cols[13]) > 0);  // a depth exactly where a χ² is
    if (!cols[14].empty()) {  // the right match, pixels: inside the 752 x 480 image, beside the left one
      ++with_right;
      EXPECT_TRUE(std::stod(cols[14]) >= 0 && std::stod(cols[14]) < 752 &&
                  std::abs(std::stod(cols[15]) - std::stod(cols[3])) < 3)
          << csv.substr(pos, end - pos);
    }
    if (std::stod(cols[8]) >= 0) {
      EXPECT_FALSE(cols[14].empty());  // the stereo test needs a right match
    }
    eliminated += cols[5] == "eliminated";
    on_moving += cols[9] == "1";
    pos = end + 1;
  }
  EXPECT_GT(rows, 5000u);
  EXPECT_GT(tested, rows / 2);  // most tracked features have right matches in both frames
  EXPECT_GT(with_right, tested);
  EXPECT_GT(eliminated, 50u);  // the trucks
  EXPECT_GT(on_moving, 500u);  // masks were read
  // Stereo test off in the config: no χ² in the dump.
  {
    std::string text = idyvins::test::readFile(cfg);
    ASSERT_EQ(text.find("stereo_motion_test:"), std::string::npos) << "the simulator leaves defaults out";
    text += "stereo_motion_test: 0\n";
    idyvins::test::writeFile(cfg, text);
  }
  // The dump named inside the output folder lands there (the folder is staged, then swapped in).
  const Result off = run("run --config " + cfg + " --dataset " + (dir / "ds") + " --out " + (dir / "out2") +
                         " --mode idy --frames 30 --dump-observations " + (dir / "out2/obs2.csv"));
  ASSERT_EQ(off.code, 0) << off.out;
  EXPECT_TRUE(std::filesystem::exists(dir / "out2/trajectory.tum"));
  const std::string csv2 = idyvins::test::readFile(dir / "out2/obs2.csv");
  std::size_t with_chi2 = 0;
  for (std::size_t p = csv2.find('\n'); p != std::string::npos && p + 1 < csv2.size(); p = csv2.find('\n', p + 1)) {
    // the 9th column (stereo_chi2) of each row
    std::size_t q = p + 1;
    for (int k = 0; k < 8; ++k) q = csv2.find(',', q) + 1;
    with_chi2 += csv2.compare(q, 3, "-1,") != 0;
  }
  EXPECT_EQ(with_chi2, 0u);
  // A dump that cannot be written fails at once, with the path, before any frame is run.
  const Result bad = run("run --config " + cfg + " --dataset " + (dir / "ds") + " --out " + (dir / "out3") +
                         " --mode idy --frames 30 --dump-observations /proc/idyvins_obs.csv");
  EXPECT_NE(bad.code, 0);
  EXPECT_NE(bad.out.find("/proc/idyvins_obs.csv"), std::string::npos) << bad.out;
  for (const auto& e : std::filesystem::directory_iterator(dir.path()))  // no output folder, staged or not
    EXPECT_EQ(e.path().filename().string().rfind("out3", 0), std::string::npos) << e.path();
  // --save-map inside the output folder lands there; a map folder that cannot be written fails at once.
  const Result map_in = run("run --config " + cfg + " --dataset " + (dir / "ds") + " --out " + (dir / "out4") +
                            " --frames 30 --save-map " + (dir / "out4/map"));
  ASSERT_EQ(map_in.code, 0) << map_in.out;
  EXPECT_TRUE(std::filesystem::exists(dir / "out4/map/map.json"));
  EXPECT_TRUE(std::filesystem::exists(dir / "out4/trajectory.tum"));
  const Result map_bad = run("run --config " + cfg + " --dataset " + (dir / "ds") + " --out " + (dir / "out5") +
                             " --frames 30 --save-map /proc/idyvins_map");
  EXPECT_NE(map_bad.code, 0);
  EXPECT_NE(map_bad.out.find("/proc/idyvins_map"), std::string::npos) << map_bad.out;
  EXPECT_FALSE(std::filesystem::exists(dir / "out5"));
}

/// Busy-loops `n` child processes until destroyed: a neighbour that takes the CPU.
class CpuBurner {
 public:
  explicit CpuBurner(int n) {
    for (int i = 0; i < n; ++i) {
      const pid_t pid = fork();
      if (pid == 0) {
        volatile unsigned long x = 0;
        while (true) x = x * 6364136223846793005ul + 1;
      }
      if (pid > 0) pids_.push_back(pid);
    }
  }
  ~CpuBurner() {
    for (pid_t p : pids_) kill(p, SIGKILL);
    for (pid_t p : pids_) waitpid(p, nullptr, 0);
  }
  std::size_t count() const { return pids_.size(); }

 private:
  std::vector<pid_t> pids_;
};

/// stats.json without the fields that measure time.
nlohmann::json withoutTiming(const nlohmann::json& j) {
  if (j.is_object()) {
    nlohmann::json out = nlohmann::json::object();
    for (auto it = j.begin(); it != j.end(); ++it)
      if (!idyvins::pipeline::isTimingField(it.key())) out[it.key()] = withoutTiming(it.value());
    return out;
  }
  if (j.is_array()) {
    nlohmann::json out = nlohmann::json::array();
    for (const auto& v : j) out.push_back(withoutTiming(v));
    return out;
  }
  return j;
}

TEST(Cli, RunIsByteIdenticalUnderLoadAndAcrossThreadCounts) {
  // 10 s of city high: one run on the idle machine with one thread (feedback delay 1), one
  // pipelined run (two threads) while two busy-looping neighbours take both cores. Solves
  // stop on iterations, never on the clock, and the pipeline's data flow is fixed: the
  // files must be the same bytes.
  idyvins::test::TempDir dir;
  const Result sim = run("simulate --scene city --level high --seed 3 --duration 10 --out " + (dir / "ds"));
  ASSERT_EQ(sim.code, 0) << sim.out;
  const std::string args = "run --config " + (dir / "ds/config/sim_stereo_imu_config.yaml") + " --dataset " +
                           (dir / "ds") + " --mode idy --out ";
  const Result idle = run(args + (dir / "idle") + " --threads 1 --feedback-delay 1");
  ASSERT_EQ(idle.code, 0) << idle.out;
  Result loaded;
  {
    CpuBurner burner(2);
    ASSERT_EQ(burner.count(), 2u);
    loaded = run(args + (dir / "loaded") + " --threads 2");
  }
  ASSERT_EQ(loaded.code, 0) << loaded.out;
  EXPECT_NE(loaded.out.find("2 threads"), std::string::npos) << loaded.out;
  for (const char* f :
       {"trajectory.tum", "trajectory.csv", "state.csv", "map_static.ply", "map_dynamic.ply", "map_all.ply"}) {
    const std::string a = idyvins::test::readFile(dir / (std::string("idle/") + f));
    EXPECT_GT(a.size(), 1000u) << f;
    EXPECT_TRUE(a == idyvins::test::readFile(dir / (std::string("loaded/") + f))) << f << " differs";
  }
  const nlohmann::json sa = withoutTiming(nlohmann::json::parse(idyvins::test::readFile(dir / "idle/stats.json")));
  const nlohmann::json sb = withoutTiming(nlohmann::json::parse(idyvins::test::readFile(dir / "loaded/stats.json")));
  EXPECT_FALSE(sa["summary"].contains("threads")) << "threads is stripped with the timing fields";
  EXPECT_TRUE(sa == sb) << "stats.json differs beyond its timing fields: "
                        << nlohmann::json::diff(sa, sb).dump().substr(0, 600);
  EXPECT_GT(sa["summary"]["poses"].get<int>(), 150);
}

TEST(Cli, LibraryUserWritesTheFilesRunWrites) {
  // A library user with pipeline::openDataset, RunOutputs and feed on 4 s of city mid with
  // masks, and `idyvins run` on the same: every file the same bytes (stats.json beyond its
  // timing fields, run.json beyond the working folder), the ghost map and groundtruth.tum too.
  idyvins::test::TempDir dir;
  const Result sim = run("simulate --scene city --level mid --seed 2 --duration 4 --out " + (dir / "ds"));
  ASSERT_EQ(sim.code, 0) << sim.out;
  const std::string cfg = dir / "ds/config/sim_stereo_imu_config.yaml";
  const Result cli = run("run -c " + cfg + " -d " + (dir / "ds") + " -o " + (dir / "cli") + " --threads 1");
  ASSERT_EQ(cli.code, 0) << cli.out;
  {
    idyvins::Config config = idyvins::loadConfig(cfg);
    idyvins::pipeline::RunRequest request;
    request.threads = 1;
    idyvins::pipeline::System system(config, idyvins::pipeline::applyRunRequest(request, config));
    idyvins::io::OpenedDataset in = idyvins::pipeline::openDataset(dir / "ds", config);
    idyvins::pipeline::RunOutputsOptions files;
    files.inputs = {dir / "ds", cfg};
    files.masks = in.has_masks;
    idyvins::pipeline::RunOutputs outputs(dir / "lib", files);
    outputs.attach(system);
    const std::size_t frames = idyvins::pipeline::feed(*in.source, system, in.source->frameCount());
    EXPECT_EQ(frames, in.source->frameCount());
    const idyvins::pipeline::Result result = system.finish();
    idyvins::pipeline::RunEnd end;
    end.extras = {{"unpaired_images", {{"cam0", in.unpaired_cam0}, {"cam1", in.unpaired_cam1}}}, {"partial", false}};
    end.groundtruth = in.groundtruth;
    const idyvins::pipeline::RunRecord record{"idyvins run", dir / "ds"};
    end.record = &record;
    outputs.write(system, result, end);
    EXPECT_TRUE(outputs.publish().empty());
  }
  for (const auto& e : std::filesystem::directory_iterator(dir / "cli")) {
    const std::string name = e.path().filename().string();
    const std::string a = idyvins::test::readFile(e.path().string()),
                      b = idyvins::test::readFile(dir / ("lib/" + name));
    if (name == "stats.json") {
      EXPECT_TRUE(withoutTiming(nlohmann::json::parse(a)) == withoutTiming(nlohmann::json::parse(b)));
    } else if (name == "run.json") {
      auto ra = nlohmann::json::parse(a), rb = nlohmann::json::parse(b);
      EXPECT_EQ(ra["config_files"], rb["config_files"]);
      EXPECT_EQ(ra["dataset"], rb["dataset"]);
    } else if (name != "idyvins_manifest.json") {
      EXPECT_TRUE(!a.empty() && a == b) << name << " differs";
    }
  }
  for (const char* f : {"map_static_on_moving.ply", "groundtruth.tum", "trajectory.tum", "idyvins_manifest.json"})
    EXPECT_TRUE(std::filesystem::exists(dir / (std::string("lib/") + f))) << f;
}

TEST(Cli, EvalOnRealGroundTruthAgainstItself) {
  const std::string gt = idyvins::test::sharedData("euroc_imu_gt_excerpt/mav0/gt0/data.csv");
  const Result r = run("eval --gt " + gt + " --est " + gt + " --rpe 1,5");
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("pairs: 3340"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("path length 75.881 m"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("rmse 0.000000"), std::string::npos) << r.out;
}

TEST(Cli, EvalBadInput) {
  const Result missing = run("eval --gt /nonexistent.tum --est /nonexistent2.tum");
  EXPECT_EQ(missing.code, 1);
  EXPECT_EQ(missing.out, "error: /nonexistent.tum: cannot open file (missing or unreadable)\n");
  idyvins::test::TempDir dir;
  idyvins::test::writeFile(dir / "a.tum", "1.0 0 0 0 0 0 0 1\n2.0 1 0 0 0 0 0 1\n");
  idyvins::test::writeFile(dir / "b.tum", "5.0 0 0 0 0 0 0 1\n6.0 1 0 0 0 0 0 1\n");
  const Result nomatch = run("eval --gt " + (dir / "a.tum") + " --est " + (dir / "b.tum"));
  EXPECT_EQ(nomatch.code, 1);
  EXPECT_NE(nomatch.out.find("no matching time stamps"), std::string::npos) << nomatch.out;
  const Result align = run("eval --gt " + (dir / "a.tum") + " --est " + (dir / "a.tum") + " --align affine");
  EXPECT_NE(align.code, 0);
  EXPECT_NE(align.out.find("se3|sim3|posyaw|none"), std::string::npos) << align.out;
}

TEST(Cli, ImageSizeDifferentFromConfig) {
  idyvins::test::TempDir dir;
  const std::string src = std::string(IDYVINS_SOURCE_DIR) + "/config/euroc/";
  for (const char* f : {"cam0_pinhole.yaml", "cam1_pinhole.yaml", "euroc_stereo_imu_config.yaml"}) {
    std::string text = idyvins::test::readFile(src + f);
    for (const char* from : {"image_width: 752", "image_height: 480"}) {
      const auto pos = text.find(from);
      ASSERT_NE(pos, std::string::npos);
      text.replace(pos, std::string(from).size(),
                   std::string(from).substr(0, std::string(from).find(':')) + (from[6] == 'w' ? ": 640" : ": 480"));
    }
    idyvins::test::writeFile(dir / f, text);
  }
  const Result r = run("info " + kMicro + " --config " + (dir / "euroc_stereo_imu_config.yaml"));
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.out.find("cam0/data.csv:2: image "), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("is 752x480, expected 640x480"), std::string::npos) << r.out;
}

TEST(Cli, BenchRefusesDataSimulatedWithAnotherRealism) {
  idyvins::test::TempDir dir;
  std::filesystem::create_directories(dir / "data/city_none_s1");
  idyvins::test::writeFile(dir / "data/city_none_s1/meta.json", "{\"scene\": \"city\"}\n");  // before --realism: none
  const Result r =
      run("bench --suite standard --out " + (dir / "out") + " --data " + (dir / "data") + " --seeds 1 --realism euroc");
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.out.find("city_none_s1: simulated with --realism none, the benchmark asks for euroc"), std::string::npos)
      << r.out;
  const Result bad = run("simulate --realism cinema --out " + (dir / "x"));
  EXPECT_NE(bad.code, 0);
  EXPECT_NE(bad.out.find("--realism"), std::string::npos) << bad.out;
}

TEST(Cli, BenchRefusesDataOfTheOtherFamily) {
  // A folder of standard sequences is not the validation suite, and the other way round.
  idyvins::test::TempDir dir;
  std::filesystem::create_directories(dir / "data/city_none_s1");
  idyvins::test::writeFile(dir / "data/city_none_s1/meta.json",
                           "{\"scene\": \"city\"}\n");  // before --family: standard
  const Result r = run("bench --suite validation --out " + (dir / "out") + " --data " + (dir / "data") + " --seeds 1");
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(
      r.out.find("city_none_s1: simulated with --family standard, the validation suite needs --family validation"),
      std::string::npos)
      << r.out;
  idyvins::test::writeFile(dir / "data/city_none_s1/meta.json", "{\"scene\": \"city\", \"family\": \"validation\"}\n");
  const Result s = run("bench --suite standard --out " + (dir / "out") + " --data " + (dir / "data") + " --seeds 1");
  EXPECT_EQ(s.code, 1);
  EXPECT_NE(s.out.find("simulated with --family validation, the standard suite needs --family standard"),
            std::string::npos)
      << s.out;
  const Result bad = run("simulate --family tuning --out " + (dir / "x"));
  EXPECT_NE(bad.code, 0);
  EXPECT_NE(bad.out.find("--family"), std::string::npos) << bad.out;
  const Result suite = run("bench --suite other --out " + (dir / "out"));
  EXPECT_NE(suite.code, 0);
  EXPECT_NE(suite.out.find("expected standard, validation or viode"), std::string::npos) << suite.out;
}

}  // namespace
