// `idyvins simulate`: the synthetic dynamic-scene benchmark generator.

#include <cstdio>
#include <filesystem>

#include "commands.h"
#include "core/error.h"
#include "progress.h"
#include "sim/simulator.h"

namespace idyvins::app {
namespace {

struct SimulateArgs {
  std::string scene = "city", level = "none", out;
  std::uint64_t seed = 1;
  double duration = 60.0, noise = 1.0, image_noise = 2.0;
  int threads = 2;
  bool opening_vehicle = false, standard_set = false;
};

int simulateOne(const SimulateArgs& a, const std::string& scene, const std::string& level, const std::string& out) {
  sim::SimOptions o;
  o.scene.scene = scene;
  if (!sim::parseLevel(level, o.scene.level))
    throw CLI::ValidationError("--level", "expected none|low|mid|high, got '" + level + "'");
  o.scene.seed = a.seed;
  o.scene.opening_vehicle = a.opening_vehicle;
  o.duration_s = a.duration;
  o.imu.scale = a.noise;
  o.image_noise_sigma = a.image_noise;
  o.threads = a.threads;
  ProgressBar bar("simulate " + scene + " " + level, 0, "frames");
  std::size_t total = 0;
  const sim::SimResult r = sim::simulate(o, out, [&](std::size_t done, std::size_t n) {
    if (total == 0) {
      total = n;
      bar = ProgressBar("simulate " + scene + " " + level, n, "frames");
    }
    bar.update(done);
  });
  bar.finish();
  std::printf("%s: %s %s seed %llu, %.1f s, %zu stereo frames, %zu IMU samples, path %.1f m, "
              "moving objects cover %.1f%% of cam0 on average (max %.1f%%, >=30%% in %.1f%% of frames), "
              "written in %.1f s\n",
              out.c_str(), scene.c_str(), level.c_str(), static_cast<unsigned long long>(a.seed), a.duration,
              r.frames, r.imu_samples, r.path_length_m, 100 * r.coverage.mean, 100 * r.coverage.max,
              100 * r.coverage.frames_over_30pct, r.seconds);
  return kOk;
}

int runSimulate(const SimulateArgs& a) {
  if (!(a.duration > 0)) throw CLI::ValidationError("--duration", "must be positive");
  if (a.noise < 0) throw CLI::ValidationError("--noise", "must be >= 0");
  if (!a.standard_set) return simulateOne(a, a.scene, a.level, a.out);
  for (const char* scene : {"city", "parking_lot"})
    for (const char* level : {"none", "low", "mid", "high"}) {
      const std::string dir = (std::filesystem::path(a.out) / (std::string(scene) + "_" + level + "_s" +
                                                               std::to_string(a.seed)))
                                  .string();
      if (std::filesystem::exists(std::filesystem::path(dir) / "meta.json")) {
        std::printf("%s: exists, kept\n", dir.c_str());
        continue;
      }
      simulateOne(a, scene, level, dir);
    }
  return kOk;
}

}  // namespace

void registerSimulate(CLI::App& app, int& exit_code) {
  auto a = std::make_shared<SimulateArgs>();
  CLI::App* cmd = app.add_subcommand(
      "simulate",
      "Render a synthetic stereo-inertial dataset of a dynamic scene (VIODE-like) in EuRoC\n"
      "layout: cam0/cam1 PNGs (752x480, 20 Hz) with per-pixel object-id masks, IMU at 200 Hz\n"
      "(ADIS16448-like noise and bias random walk), ground truth with velocity and biases,\n"
      "a VINS-Fusion config under DIR/config/, and DIR/meta.json. Deterministic.");
  cmd->add_option("--scene", a->scene, "city | parking_lot")->check(CLI::IsMember({"city", "parking_lot"}));
  cmd->add_option("--level", a->level, "moving objects: none | low | mid | high")
      ->check(CLI::IsMember({"none", "low", "mid", "high"}));
  cmd->add_option("--seed", a->seed, "random seed (scene layout, traffic, noise)");
  cmd->add_option("--duration", a->duration, "seconds of data");
  cmd->add_option("-o,--out", a->out, "output folder (with --standard-set: the parent folder)")->required();
  cmd->add_option("--noise", a->noise, "IMU noise scale (0 = perfect IMU, 1 = ADIS16448-like)");
  cmd->add_option("--image-noise", a->image_noise, "pixel noise sigma, gray levels");
  cmd->add_option("--threads", a->threads, "rendering threads")->check(CLI::Range(1, 64));
  cmd->add_flag("--opening-vehicle", a->opening_vehicle,
                "a vehicle crosses close in front of the drone during the first seconds");
  cmd->add_flag("--standard-set", a->standard_set,
                "write city and parking_lot x none/low/mid/high into OUT/<scene>_<level>_s<seed>, "
                "keeping folders that already hold a meta.json");
  cmd->callback([a, &exit_code] { exit_code = runSimulate(*a); });
}

}  // namespace idyvins::app
